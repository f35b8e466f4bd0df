"""No float atomic add writes the state or a recorded output: the kernels are read for them.

A float sum's bits depend on the order of its terms, and a GPU adds atomically in whatever order
its threads arrive, so an atomic float sum differs from run to run there (tests/test_determinism.py
sees the same on the CPU across thread counts). Sums go through fixed-order partial sums
(sph/sums.py) or, where a sum only counts, integers (int32, or int64 fixed point: the excluded
mass). Atomic minima and maxima stay: their result is one of the terms whatever the order. Warp
compiles ``a[i] += x`` in a kernel to an atomic add, so that form counts too.

ALLOWED names the float atomic adds kept, each with its reason: only one that decides a threshold
may stand there.
"""
import ast

import pytest

from conftest import REPO

pytestmark = pytest.mark.unit

INTEGER = {"wp.int32", "wp.int64", "wp.uint32", "wp.uint64", "int"}
ADDS = {"wp.atomic_add", "wp.atomic_sub"}
# (file, function, array): reason
ALLOWED = {}


def _decorated(node) -> bool:
    return any(ast.unparse(d).startswith(("wp.kernel", "wp.func")) for d in node.decorator_list)


def _dtypes(node) -> dict:
    """Each array argument's element type, as written (wp.array(dtype=wp.int32) -> 'wp.int32')."""
    out = {}
    for arg in node.args.args:
        ann = arg.annotation
        if isinstance(ann, ast.Call) and ast.unparse(ann.func).startswith("wp.array"):
            for kw in ann.keywords:
                if kw.arg == "dtype":
                    out[arg.arg] = ast.unparse(kw.value)
    return out


def float_adds():
    """(file, function, array, line) of every atomic add onto an array not of an integer type, in
    the package's Warp kernels and functions."""
    found = []
    for path in sorted((REPO / "gpusph_ros").rglob("*.py")):
        tree = ast.parse(path.read_text())
        for node in ast.walk(tree):
            if not isinstance(node, ast.FunctionDef) or not _decorated(node):
                continue
            types = _dtypes(node)
            for inner in ast.walk(node):
                target = None
                if isinstance(inner, ast.Call) and ast.unparse(inner.func) in ADDS:
                    target = inner.args[0]
                elif (isinstance(inner, ast.AugAssign) and isinstance(inner.target, ast.Subscript)
                      and isinstance(inner.op, (ast.Add, ast.Sub))):
                    target = inner.target.value
                if target is None:
                    continue
                name = ast.unparse(target)
                if types.get(name) not in INTEGER:
                    found.append((str(path.relative_to(REPO)), node.name, name, inner.lineno))
    return found


def test_no_float_atomic_add_but_those_allowed_with_a_reason():
    found = [f for f in float_adds() if f[:3] not in ALLOWED]
    assert not found, "float atomic adds (file, function, array, line): " + "; ".join(map(str, found))


def test_the_reader_finds_float_adds_and_passes_integer_ones(tmp_path, monkeypatch):
    # the reader itself, on a kernel of each kind: a test that cannot fail proves nothing
    package = tmp_path / "gpusph_ros"
    package.mkdir()
    (package / "k.py").write_text(
        "import warp as wp\n"
        "@wp.kernel\n"
        "def k(a: wp.array(dtype=float), n: wp.array(dtype=wp.int32), v: wp.array(dtype=wp.vec3d)):\n"
        "    i = wp.tid()\n"
        "    wp.atomic_add(a, 0, 1.0)\n"
        "    wp.atomic_add(n, 0, 1)\n"
        "    v[0] += wp.vec3d(1.0)\n"
        "    wp.atomic_max(a, 1, 2.0)\n")
    monkeypatch.setattr(__import__(__name__), "REPO", tmp_path)
    assert sorted((f, a) for _, f, a, _ in float_adds()) == [("k", "a"), ("k", "v")]
