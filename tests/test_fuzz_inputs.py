"""Fuzzing gpusph-run with 200 bad inputs (seeded, so every run of the test sees the same ones):
scene files broken in one of many ways and bad --set values. Each must end with exit status 1
and one line naming a field or the file, within 5 s, with no traceback: the CLI is called
in-process, so any exception it lets through fails the test."""
import io
import random
import re
import time
from contextlib import redirect_stderr, redirect_stdout

import pytest
import yaml

from gpusph_ros.cli import run_main
from gpusph_ros.scenes.schema import SCENE_KEYS, load_scene
from gpusph_ros.scenes.settings import RUN_KEYS

pytestmark = pytest.mark.unit

CASES = 200
BASE = yaml.safe_load(load_scene("dambreak1_thesis").text)
# a run that an accepted input would start finishes at once (and then fails the test)
QUICK = ["--set", "output_rate=1000", "--set", "end_time=0.001", "--set", "dx=0.05"]
FIELDS = set(SCENE_KEYS) | set(RUN_KEYS) | {"scene", "--set", "--out", "run_config"}

BAD_SETS = ["kernel=gauss", "dx=-1", "dx=1e-6", "dx=2.0e-5", "cfl=1.0e-12", "cfl=2", "dt_fixed=1.0e-12",
            "output_rate=1.0e+9", "output_rate=0", "end_time=-1", "end_time=.inf", "device=tpu", "device=cuda:7",
            "precision=float16", "model=3d", "boundary=glass", "xsph=maybe", "shepard_every=1.5", "no_such=1",
            "particle_rate=5000", "end_time=0.0001", "viscosity=none", "c0=-3", "max_particles=0",
            "gravity=[0, 0, -9.81]", "dx", "=0.02", "hdx=[1, 2]", "alpha=.nan", "slab_width=-0.1", "crop=yes please"]


def _broken_scene(rng: random.Random):
    """(bytes of a scene file, what was broken): one mutation that no valid scene has."""
    data = yaml.safe_load(yaml.safe_dump(BASE))
    kind = rng.choice(["drop", "bad_value", "unknown_key", "junk", "nesting", "alias", "text", "box", "probe"])
    if kind == "drop":
        del data[rng.choice(["dim", "tank", "fluid"])]
    elif kind == "bad_value":
        field, value = rng.choice([("dim", 4), ("dim", "three"), ("tank", [1.6, -0.6, 0.4]), ("tank", "big"),
                                   ("depth", -1.0), ("headroom", "x"), ("wet_bed", 99.0), ("gravity", [0, 0, 9.81]),
                                   ("periodic", [False, False, True]), ("walls", "glass"), ("fluid", 5),
                                   ("fluid", []), ("probes", [1, 2]), ("obstacles", "one"), ("run", [1]),
                                   ("name", "has space/and slash"), ("walls", {"roof": "planes"})])
        data[field] = value
    elif kind == "unknown_key":
        kind = f"extra_{rng.randrange(1000)}"  # the message names the stray field itself
        data[kind] = rng.random()
    elif kind == "box":
        box = rng.choice(["lo", "hi"])
        data["fluid"][0][box] = rng.choice([[0.0, 0.0], [5.0, 0.0, 0.0], ["a", 0, 0], [0, 0, float("nan")]])
    elif kind == "probe":
        name = next(iter(data["probes"]))
        data["probes"][name] = rng.choice([{"type": "laser", "position": [0.5, 0.3, 0.1]},
                                           {"type": "point", "position": [9.0, 0.3, 0.1]},
                                           {"type": "point"}, {"type": "point", "position": [0.5, 0.3, 0.1],
                                                               "heights": [0.1]}])
    if kind == "junk":
        return bytes(rng.randrange(256) for _ in range(rng.randrange(1, 400))) + b"\0", kind
    if kind == "nesting":
        depth = rng.randrange(40, 5000)
        return b"a: " + b"[" * depth + b"]" * depth, kind
    if kind == "alias":
        return b"x: &a [1, 2, 3]\ny: [*a, *a]\n", kind
    if kind == "text":
        return rng.choice([b"", b"just some words\n", b"- a\n- list\n", "caf\xe9: 1\n".encode("latin-1")]), kind
    return yaml.safe_dump(data).encode(), kind


def _case(rng: random.Random, tmp_path, k: int):
    """(argv, what) of fuzz case ``k``."""
    out = str(tmp_path / f"out_{k}")
    if rng.random() < 0.6:
        data, kind = _broken_scene(rng)
        path = tmp_path / f"scene_{k}.yaml"
        path.write_bytes(data)
        return [str(path), *QUICK, "--out", out, "--quiet"], f"scene: {kind}"
    bad = rng.choice(BAD_SETS)
    return (["dambreak1_thesis", *QUICK, "--set", bad, "--out", out, "--quiet"],
            f"--set {bad}")


def test_two_hundred_bad_inputs_each_get_exit_1_and_a_line_naming_the_field_or_file(tmp_path):
    rng = random.Random(20261201)
    kinds = set()
    for k in range(CASES):
        argv, what = _case(rng, tmp_path, k)
        kinds.add(what.split(":")[0] if what.startswith("scene") else "set")
        err, out = io.StringIO(), io.StringIO()
        start = time.perf_counter()
        with redirect_stderr(err), redirect_stdout(out):
            code = run_main(argv)
        wall = time.perf_counter() - start
        message = err.getvalue().strip()
        assert code == 1, (what, code, message, out.getvalue()[-500:])
        assert wall < 5.0, (what, wall)
        assert "Traceback" not in message and len(message.splitlines()) == 1, (what, message)
        named = re.match(r"gpusph-run: (?:--out: )?(\S+?):? ", message)
        assert named, (what, message)
        field = named.group(1)
        known = FIELDS | {what.split(": ")[-1], what.removeprefix("--set ").split("=")[0]}
        assert field in known or field.split("[")[0].split(".")[0] in known or argv[0] in message, (what, message)
    assert kinds == {"scene", "set"}
