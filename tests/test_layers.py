"""The house plan's import rules, read from the source (every import, at module level or inside a
function): data flows scene -> solver -> measurements -> output -> run -> node / studies / CLI, and
each layer imports only the layers below it."""
import ast
from pathlib import Path

import pytest

pytestmark = pytest.mark.unit

PACKAGE = Path(__file__).resolve().parents[1] / "gpusph_ros"
# what each layer (a sub-package, or a top-level module) may import of the package
ALLOWED = {
    "sph": set(),
    "theory": set(),
    "share": set(),
    "scenes": {"sph", "theory", "share"},
    "measure": {"sph"},
    "output": set(),
    "drive": set(),  # a driven body's commands into segments: the run's, fed by the node
    "runner": {"sph", "scenes", "measure", "output", "drive"},
    "plan": {"sph", "scenes"},
    "analysis": {"output", "share", "theory"},
    "ros": {"gpusph_ros", "sph", "scenes", "measure", "output", "runner", "share", "drive"},
    "study": {"sph", "scenes", "runner", "analysis", "theory", "share", "output", "measure"},
    "cli": None,  # the entry point may use anything
}


def _layer(dotted: str) -> str:
    """The sub-package or top-level module ``dotted`` lies in; "gpusph_ros" for the package itself
    (or a name it defines, such as __version__)."""
    parts = dotted.split(".")
    if len(parts) > 1 and ((PACKAGE / parts[1]).is_dir() or (PACKAGE / f"{parts[1]}.py").is_file()):
        return parts[1]
    return parts[0]


def imports_by_layer() -> dict:
    found = {}
    for path in PACKAGE.rglob("*.py"):
        parts = path.relative_to(PACKAGE.parent).with_suffix("").parts
        package = parts[:-1]
        module = ".".join(parts if parts[-1] != "__init__" else parts[:-1])
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.ImportFrom):
                base = list(package[:len(package) - node.level + 1]) if node.level else []
                targets = [".".join(base + ([node.module] if node.module else []))]
                if node.level and not node.module:  # from . import a, b
                    targets = [".".join(base + [a.name]) for a in node.names]
            elif isinstance(node, ast.Import):
                targets = [a.name for a in node.names]
            else:
                continue
            for target in targets:
                if target.split(".")[0] == "gpusph_ros":
                    found.setdefault(_layer(module), set()).add(_layer(target))
    return found


def test_every_layer_imports_only_the_layers_below_it():
    found = imports_by_layer()
    assert set(found) - {"gpusph_ros"} <= set(ALLOWED), f"a layer the plan does not name: {set(found) - set(ALLOWED)}"
    wrong = {layer: sorted(used - ALLOWED[layer] - {layer}) for layer, used in found.items()
             if ALLOWED.get(layer) is not None and used - ALLOWED[layer] - {layer}}
    assert not wrong, f"imports against the house plan: {wrong}"


def test_the_rules_are_read_from_the_source():
    """The reader sees the arrows that exist (so the test above could fail): the runner uses the
    scenes, the measurements and the output, the scenes the solver, and the node the runner."""
    found = imports_by_layer()
    assert {"scenes", "measure", "output"} <= found["runner"] and "sph" in found["scenes"]
    assert "runner" in found["ros"]
    assert "theory" in found["scenes"]  # reduce.py: Stoker's bore speed
