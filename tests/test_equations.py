"""The README's equation -> file table holds: every function it names is defined in the file it
names, and every equation of thesis Section 2 (2.1-2.28) has a row."""
import re

import pytest

from conftest import REPO

pytestmark = pytest.mark.unit


def _rows():
    text = (REPO / "README.md").read_text()
    table = text.split("### Equations and where they live", 1)[1].split("```", 1)[0]
    for line in table.splitlines():
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        if len(cells) == 3 and cells[0] not in ("thesis Eq.", "---"):
            yield cells


def _homes(cell):
    """(file, [names]) pairs of a 'home' cell: `path`: `name`, `name`; `path`: ..."""
    for part in re.findall(r"`([\w/]+\.py)`: ((?:`\w+`(?:, )?)+)", cell):
        yield part[0], re.findall(r"`(\w+)`", part[1])


def test_every_named_home_defines_its_function():
    rows = list(_rows())
    assert len(rows) > 20
    for number, what, home in rows:
        homes = list(_homes(home))
        assert homes, f"{number} {what}: no `file`: `function` in {home!r}"
        for path, names in homes:
            source = (REPO / "gpusph_ros" / path).read_text()
            for name in names:
                assert re.search(rf"^\s*(def|class) {name}\b", source, re.M), f"{number} {what}: {name} not in {path}"


def test_every_equation_of_section_2_has_a_row():
    covered = set()
    for number, _, _ in _rows():
        m = re.fullmatch(r"2\.(\d+)(?:-2\.(\d+))?", number)
        if m:
            covered |= set(range(int(m[1]), int(m[2] or m[1]) + 1))
    assert covered == set(range(1, 29))
