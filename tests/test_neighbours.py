"""Neighbour lists against brute force, with a periodic axis (minimum image); the GPU's layout against
the CPU's, bit for bit; and no 32-bit product of a particle index and the list width in any kernel."""
import numpy as np
import pytest

from gpusph_ros.sph import Particles, Solver, SolverConfig
from gpusph_ros.sph.state import FLUID, PASSIVE

pytestmark = pytest.mark.unit


@pytest.mark.parametrize("precision", ["float32", "float64"])
def test_lists_match_brute_force(precision):
    rng = np.random.default_rng(7)
    dx = 0.01
    lo, hi = np.array([0.0, 0.0, 0.0]), np.array([0.1, 0.1, 0.1])
    pos = lo + rng.random((800, 3)) * (hi - lo)
    n = len(pos)
    cfg = SolverConfig(dim=3, dx=dx, precision=precision, domain_lo=tuple(lo), domain_hi=tuple(hi),
                       periodic=(True, False, False), neighbour_search="lists")
    solver = Solver(cfg, Particles(pos=pos, vel=np.zeros((n, 3)), rho=np.full(n, 1000.0),
                                   mass=np.full(n, 1.0), ptype=np.zeros(n)))
    solver.mean_neighbours()
    nl = solver.neighbours
    count = nl.count.numpy()
    nbr = nl.nbr.numpy()
    radius = nl.skin * 2.0 * cfg.h
    sep = pos[:, None, :] - pos[None, :, :]
    sep[..., 0] -= 0.1 * np.round(sep[..., 0] / 0.1)
    dist = np.linalg.norm(sep, axis=2)
    for i in range(0, n, 7):
        expected = set(np.flatnonzero((dist[i] < radius * (1 - 1e-5)) & (np.arange(n) != i)))
        got = set(nbr[i, :count[i]].tolist())
        assert expected <= got, f"particle {i}: missing {sorted(expected - got)[:5]}"
        assert all(dist[i, j] < radius * (1 + 1e-5) for j in got)
    # a periodic pair across the seam is found
    assert any(abs(pos[i, 0] - pos[j, 0]) > 0.05 for i in range(n) for j in nbr[i, :count[i]])


def test_two_levels_lists_match_brute_force():
    """Cells one fine list radius wide: a coarse particle searches two each way and still finds its
    whole list. An active particle lists its own level only; a passive one its donors too, the other
    level's active fluid and the finer level's passive fluid (and its own level's, for when it turns
    active before the next build). Each pair is
    within the list radius of h_ab = (h_a + h_b) / 2."""
    rng = np.random.default_rng(11)
    dx = 0.01
    lo, hi = np.array([0.0, 0.0, 0.0]), np.array([0.12, 0.12, 0.12])
    n = 1200
    pos = lo + rng.random((n, 3)) * (hi - lo)
    spacing = np.where(rng.random(n) < 0.5, dx, 0.5 * dx)
    ptype = np.where(rng.random(n) < 0.3, PASSIVE, FLUID)
    cfg = SolverConfig(dim=3, dx=dx, precision="float64", domain_lo=tuple(lo), domain_hi=tuple(hi),
                       periodic=(True, False, False), neighbour_search="lists")
    solver = Solver(cfg, Particles(pos=pos, vel=np.zeros((n, 3)), rho=np.full(n, 1000.0), mass=np.full(n, 1.0),
                                   ptype=ptype, spacing=spacing))
    nl = solver.neighbours
    assert nl.grid.reach == 2  # the coarse level's radius is two cells
    nl.rebuild(solver.pos, force=True)
    count = nl.count.numpy()
    nbr = nl.nbr.numpy()
    h = cfg.hdx * spacing
    sep = pos[:, None, :] - pos[None, :, :]
    sep[..., 0] -= 0.12 * np.round(sep[..., 0] / 0.12)
    dist = np.linalg.norm(sep, axis=2)
    radius = nl.skin * (h[:, None] + h[None, :])
    same = h[:, None] == h[None, :]
    donor = (ptype[None, :] == FLUID) | ((ptype[None, :] == PASSIVE) & (h[None, :] < h[:, None]))
    allowed = same | ((ptype[:, None] == PASSIVE) & donor)
    np.fill_diagonal(allowed, False)
    for i in range(n):
        expected = set(np.flatnonzero(allowed[i] & (dist[i] < radius[i] * (1 - 1e-9))))
        got = set(nbr[i, :count[i]].tolist())
        assert got == expected, f"particle {i}: missing {sorted(expected - got)[:5]}, extra {sorted(got - expected)}"
    assert any(count[i] > 0 and ptype[i] == PASSIVE and h[i] == h.max() for i in range(n))


def test_neighbour_major_lists_step_bit_identically_to_particle_major():
    """The layout a GPU takes (neighbour-major, read through a transposed view) holds the same lists
    and gives the same steps as the CPU's, bit for bit."""
    from gpusph_ros.scenes.build import build
    from gpusph_ros.scenes.schema import parse_scene

    scene = parse_scene({"name": "tank", "dim": 2, "tank": [0.6, 0.32],
                         "fluid": [{"name": "water", "lo": [0.0, 0.0], "hi": [0.12, 0.2]}]})
    states = []
    for major in (False, True):
        solver = build(scene, dx=0.01, boundary="mdbc", neighbour_search="lists").solver()
        nl = solver.neighbours
        nl.neighbour_major = major
        nl.resize(nl.max_neighbours)
        assert nl.nbr.is_contiguous != major and nl.nbr.shape == (nl.n, nl.max_neighbours)
        assert nl.walk.nbr.ptr == nl.nbr.ptr  # what the passes read
        solver.advance(0.03)
        states.append((solver.steps, nl.count.numpy().copy(), nl.nbr.numpy().copy(), solver.snapshot()))
    (steps_a, count_a, nbr_a, snap_a), (steps_b, count_b, nbr_b, snap_b) = states
    assert steps_a == steps_b > 50
    used = np.arange(nbr_a.shape[1])[None, :] < count_a[:, None]
    np.testing.assert_array_equal(count_a, count_b)
    np.testing.assert_array_equal(nbr_a[used], nbr_b[used])
    for name in ("pos", "vel", "rho"):
        np.testing.assert_array_equal(snap_a[name], snap_b[name])


def test_no_kernel_forms_a_particle_times_list_width_index():
    """Every kernel and device function reads the lists as nbr[i, k] (a 2D array: 32-bit indices, a
    64-bit byte offset) and none multiplies by the list width, which in 32 bits passed 2^31 at
    8.7 M particles of 3D lists."""
    import ast
    from pathlib import Path

    root = Path(__file__).resolve().parents[1] / "gpusph_ros"
    device_functions, reads = 0, 0
    for path in sorted(root.rglob("*.py")):
        for node in ast.walk(ast.parse(path.read_text())):
            if not isinstance(node, ast.FunctionDef) or not any(
                    "wp.kernel" in ast.unparse(d) or "wp.func" in ast.unparse(d) for d in node.decorator_list):
                continue
            device_functions += 1
            for inner in ast.walk(node):
                if isinstance(inner, ast.BinOp) and isinstance(inner.op, ast.Mult):
                    assert "max_neighbours" not in ast.unparse(inner), f"{path.name}: {ast.unparse(inner)}"
                if isinstance(inner, ast.Subscript) and ast.unparse(inner.value) in ("nbr", "nb.nbr"):
                    reads += 1
                    assert isinstance(inner.slice, ast.Tuple) and len(inner.slice.elts) == 2, \
                        f"{path.name} {node.name}: {ast.unparse(inner)}"
                if isinstance(inner, ast.arg) and inner.arg == "nbr":
                    assert "array2d" in ast.unparse(inner.annotation), f"{path.name} {node.name}"
    assert device_functions > 50 and reads == 2  # the build writes them, walk_at reads them for every pass


COLUMN = {"name": "tank", "dim": 2, "tank": [0.6, 0.32], "fluid": [{"name": "water", "lo": [0.0, 0.0],
                                                                     "hi": [0.12, 0.2]}]}
ZONED = {**COLUMN, "refine": [{"name": "downstream", "lo": [0.2, 0.0], "hi": [0.6, 0.32], "ratio": 0.5}]}


@pytest.mark.parametrize("scene, dx, outputs", [(COLUMN, 0.01, 6), (ZONED, 0.02, 20)])
def test_lists_widened_as_they_grow_step_as_lists_wide_from_the_start(monkeypatch, scene, dx, outputs):
    """Lists as wide as their longest at the start (no margin) overflow as a column collapses (and,
    zoned, as the zone's reserved slots fill); each overflowing step is not committed, the lists
    are widened to the longest and the step taken again, on the same cadence: the run is the run
    of lists wide enough from the start (the lattice's estimate, fixed), bit for bit."""
    from gpusph_ros.scenes.build import build
    from gpusph_ros.scenes.schema import parse_scene
    from gpusph_ros.sph import neighbours

    model = build(parse_scene(scene), dx=dx, neighbour_search="lists")
    wide = Solver(model.config, model.particles, max_neighbours=neighbours.default_max_neighbours(
        2, model.config.hdx, 0.5 if "refine" in scene else 1.0, model.config.multirate + 1 if "refine" in scene else 1))
    monkeypatch.setattr(neighbours, "WIDTH_MARGIN", 1.0)
    grown = Solver(model.config, model.particles)
    start = grown.neighbours.max_neighbours
    for solver in (wide, grown):
        for k in range(1, outputs + 1):
            solver.advance(0.01 * k)
    assert grown.neighbours.max_neighbours > start and grown.steps == wide.steps > 100
    for name in ("pos", "vel", "rho", "ptype"):
        np.testing.assert_array_equal(grown.snapshot()[name], wide.snapshot()[name])


def test_measured_lists_are_narrower_than_the_lattices_estimate_and_a_fixed_width_that_overflows_stops():
    """A 2D column at rest lists at most 24 (the lattice's estimate is 72): its lists are 1.6 times
    that, 40. Lists of a width given by the caller are not widened: the step that overflows them
    stops the run, naming the width, with the state before it kept."""
    from gpusph_ros.scenes.build import build
    from gpusph_ros.scenes.schema import parse_scene
    from gpusph_ros.sph import NeighbourOverflow
    from gpusph_ros.sph.neighbours import measured_width

    model = build(parse_scene(COLUMN), dx=0.01, neighbour_search="lists")
    wide = Solver(model.config, model.particles, max_neighbours=72)
    wide.neighbours.rebuild(wide.pos, force=True)
    longest = int(wide.neighbours.count.numpy().max())
    solver = Solver(model.config, model.particles)
    assert longest == 24 and solver.neighbours.max_neighbours == measured_width(longest) == 40
    fixed = Solver(model.config, model.particles, max_neighbours=longest)
    with pytest.raises(NeighbourOverflow) as err:
        fixed.advance(0.1)
    assert f"fixed {longest}" in str(err.value)
    assert 0.0 < fixed.time < 0.1 and np.isfinite(fixed.snapshot()["pos"]).all()


def test_a_checkpoint_of_widened_lists_restores_them_as_wide(monkeypatch):
    """A state taken after the lists were widened, put into a new solver (lists as its particles
    measure them at the start), widens its lists as they were and steps on as the run it was taken
    from, bit for bit."""
    from gpusph_ros.scenes.build import build
    from gpusph_ros.scenes.schema import parse_scene
    from gpusph_ros.sph import checkpoint, neighbours

    monkeypatch.setattr(neighbours, "WIDTH_MARGIN", 1.0)
    model = build(parse_scene(COLUMN), dx=0.01, neighbour_search="lists")
    first = Solver(model.config, model.particles)
    first.advance(0.04)
    state = checkpoint.capture(first)
    second = Solver(model.config, model.particles)
    assert second.neighbours.max_neighbours < first.neighbours.max_neighbours
    checkpoint.restore(second, state)
    assert second.neighbours.max_neighbours == first.neighbours.max_neighbours
    for solver in (first, second):
        solver.advance(0.06)
    for name in ("pos", "vel", "rho"):
        np.testing.assert_array_equal(first.snapshot()[name], second.snapshot()[name])


def test_lists_are_widened_no_further_than_the_lattices_estimate():
    """Particles packed at a third of the spacing (clumped, not a flow) list 9 times the lattice's
    neighbours: the lists are not widened past the lattice's estimate (what the plan prices), and the
    first step stops the run naming it."""
    from gpusph_ros.sph import NeighbourOverflow

    dx = 0.01
    g = (np.arange(30) + 0.5) * dx / 3
    x, y = np.meshgrid(g, g)
    pos = np.column_stack([x.ravel() + 0.02, y.ravel() + 0.02, np.zeros(x.size)])
    n = len(pos)
    cfg = SolverConfig(dim=2, dx=dx, gravity=(0.0, -9.81, 0.0), domain_lo=(0.0, 0.0, -1.0), domain_hi=(0.14, 0.14, 1.0),
                       neighbour_search="lists")
    solver = Solver(cfg, Particles(pos=pos, vel=np.zeros((n, 3)), rho=np.full(n, 1000.0),
                                   mass=np.full(n, 1000.0 * dx * dx / 9), ptype=np.zeros(n)))
    assert solver.neighbours.max_neighbours == 72
    with pytest.raises(NeighbourOverflow, match="the lattice's estimate, 72"):
        solver.step()


def _walks(solver) -> list:
    """Each particle's neighbours, in the order a pass meets them (its list, or its walk of the cells)."""
    import warp as wp

    from gpusph_ros.sph.neighbours import grid

    G = grid(solver.scalar)
    walk_from, walk_cells, walk_span, walk_at = G.walk_from, G.walk_cells, G.walk_span, G.walk_at

    @wp.kernel(enable_backward=False, module="unique")
    def met(g: G.Grid, nb: G.Walk, out: wp.array2d(dtype=wp.int32)):
        i = wp.tid()
        n = int(0)
        cell_i, reach_i = walk_from(g, nb, i)
        for w in range(walk_cells(reach_i)):
            span = walk_span(g, nb, i, cell_i, reach_i, w)
            for slot in range(span[0], span[1]):
                j = walk_at(g, nb, i, slot)
                if j >= 0:
                    out[i, n] = j
                    n += 1
        out[i, out.shape[1] - 1] = n

    nl = solver.neighbours
    out = wp.zeros((solver.n, 512), dtype=wp.int32, device=solver.device)
    wp.launch(met, dim=solver.n, inputs=[nl.grid, nl.walk, out], device=solver.device)
    table = out.numpy()
    return [table[i, :table[i, -1]].tolist() for i in range(solver.n)]


def test_a_walk_of_the_cells_meets_each_particles_list_in_its_order():
    """Without lists, a pass walks the cells of the last sort and tests each candidate as the
    lists' build does: two levels, passive particles, a periodic axis, and the particles moved
    since the sort (the walk tests them where they stood then); every particle meets its list,
    entry for entry, in the list's order."""
    rng = np.random.default_rng(11)
    dx, n = 0.01, 1200
    lo, hi = np.array([0.0, 0.0, 0.0]), np.array([0.12, 0.12, 0.12])
    pos = lo + rng.random((n, 3)) * (hi - lo)
    spacing = np.where(rng.random(n) < 0.5, dx, 0.5 * dx)
    ptype = np.where(rng.random(n) < 0.3, PASSIVE, FLUID)
    walks = []
    for search in ("lists", "cells"):
        cfg = SolverConfig(dim=3, dx=dx, precision="float64", domain_lo=tuple(lo), domain_hi=tuple(hi),
                           periodic=(True, False, False), neighbour_search=search)
        solver = Solver(cfg, Particles(pos=pos, vel=np.zeros((n, 3)), rho=np.full(n, 1000.0),
                                       mass=np.full(n, 1.0), ptype=ptype, spacing=spacing))
        assert solver.neighbours.cells == (search == "cells")
        solver.neighbours.rebuild(solver.pos, force=True)
        solver.pos.assign(pos + 0.001 * rng.standard_normal((n, 3)))
        walks.append(_walks(solver))
    lists, cells = walks
    assert sum(map(len, lists)) > 20 * n
    assert cells == lists


@pytest.mark.parametrize("scene, dx, numerics", [
    ({"name": "tank", "dim": 2, "tank": [0.6, 0.32], "fluid": [{"name": "water", "lo": [0.0, 0.0], "hi": [0.12, 0.2]}]},
     0.01, {"boundary": "mdbc"}),  # ghost nodes: a boundary particle lists the fluid near two centres
    (ZONED, 0.02, {}),  # two levels, multirate, particles made and vacated between builds
])
def test_a_run_that_walks_the_cells_is_the_run_of_lists_bit_for_bit(scene, dx, numerics):
    """The same steps, the same state at every output: a walk meets the pairs a list holds, in its
    order, and the cells are sorted when the lists would be built."""
    from gpusph_ros.scenes.build import build
    from gpusph_ros.scenes.schema import parse_scene

    runs = []
    for search in ("lists", "cells"):
        solver = build(parse_scene(scene), dx=dx, neighbour_search=search, **numerics).solver()
        outputs = []
        for k in range(1, 5):
            solver.advance(0.01 * k)
            outputs.append(solver.snapshot())
        runs.append((solver.steps, int(solver.neighbours.builds.numpy()[0]), outputs))
    (steps_l, builds_l, lists), (steps_c, builds_c, cells) = runs
    assert steps_l == steps_c > 40 and builds_l == builds_c
    for a, b in zip(lists, cells):
        for name in ("pos", "vel", "rho", "ptype"):
            np.testing.assert_array_equal(a[name], b[name])


def test_a_checkpoint_of_a_run_that_walks_the_cells_steps_on_bit_for_bit_and_holds_no_lists():
    """Without lists a state holds the cells of the last sort and the particles as they were then;
    put into a new solver, the run steps on as the one it was taken from. A state of a run with
    lists is another run's: refused, naming what differs."""
    from gpusph_ros.scenes.build import build
    from gpusph_ros.scenes.schema import parse_scene
    from gpusph_ros.sph import checkpoint

    model = build(parse_scene(ZONED), dx=0.02, neighbour_search="cells")
    first = model.solver()
    first.advance(0.03)
    state = checkpoint.capture(first)
    assert "neighbours.nbr" not in state["arrays"] and "neighbours.count" not in state["arrays"]
    second = model.solver()
    checkpoint.restore(second, state)
    for solver in (first, second):
        solver.advance(0.05)
    for name in ("pos", "vel", "rho", "ptype"):
        np.testing.assert_array_equal(first.snapshot()[name], second.snapshot()[name])
    listed = build(parse_scene(ZONED), dx=0.02, neighbour_search="lists").solver()
    listed.advance(0.01)
    with pytest.raises(ValueError, match="checkpoint: its arrays are not this solver's: neighbours.*"):
        checkpoint.restore(second, checkpoint.capture(listed))
