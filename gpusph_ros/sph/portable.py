"""A run's state that any number of ranks can take up: what a checkpoint of a run on MPI ranks
holds (issue 69 item 4; docs/ranks.md).

checkpoint.py keeps a solver's every array, in its slots and with its lists: one solver's state,
which one solver of the same particles takes up again. A run on ranks has no one solver. What it
holds between two steps, whatever its cut, is:
- **each particle's state, by its id in the run:** position, velocity, density, mass, kind, body,
  smoothing length, and where it stood when the lists were last built (``x_build``);
- **the run's counters:** the clock, the step counts, the step loop's flags, the census and the
  exclusions (the same on every rank: the ranks add up each census and each step's exclusions
  before they check them, sph/exchange.py);
- **the moving bodies' state** (the same on every rank): each body's law (a driven body's segment,
  a floating body's external wrench), a floating body's state, every body's last pose and the
  force and torque on it.

A solver takes it up (``put``) with its particles in the order of their ids, and builds its lists
from ``x_build``. Every neighbour sum adds its terms in the order of their cells then ids
(neighbours.cell_keys), and the lists list the same pairs as the run's last build did. So a run
resumed from it on any number of ranks steps on bit for bit as the run that took it
(tests/test_ranks.py).

A state comes from a file: ``mismatch`` checks every array's shape, dtype and range against the
run's own particles before anything changes, as checkpoint.mismatch does.
"""
import numpy as np
import warp as wp

from . import bodies, health
from .checkpoint import SPEED_LIMIT
from .state import DT, EXCLUDED, FAILED_STEP, FLUID, N_CLOCK, N_FLAGS, N_STEPS, T

FORMAT = "portable"
PARTICLE_KEYS = ("pos", "vel", "rho", "mass", "ptype", "body", "hsml", "x_build")
# the keys a run's own build fixes: a state of another run, or an edited one, is refused
FIXED = ("mass", "body", "hsml")
COUNTERS = ("_clock", "_steps", "_flags", "_excluded", "_excluded_mass", "_energy_sum")
# the moving bodies' arrays (bodies.py): each body's law, floating state and pose (structs), and the
# force and torque the last force pass found on each (two vectors a body), which the next step's
# first pose reads
BODIES = {"_laws": bodies.Law, "_rigid": bodies.Rigid, "_poses": bodies.Pose, "_body_sums": wp.vec3d}


def is_portable(state) -> bool:
    return isinstance(state, dict) and state.get("format") == FORMAT


def particle_arrays(solver) -> dict:
    """Each key's device array in ``solver``, one entry a slot."""
    return {k: solver.neighbours.x_build if k == "x_build" else getattr(solver, k) for k in PARTICLE_KEYS}


def counters(solver) -> dict:
    """The solver's counters (``COUNTERS``) as host copies."""
    wp.synchronize_device(solver.device)
    return {k: getattr(solver, k).numpy().copy() for k in COUNTERS}


def of_solver_state(state) -> dict:
    """The run's state in this format from one solver's (checkpoint.capture: its arrays by slot, the
    ids saying whose each slot is), for a run on ranks to take up; ValueError where it does not
    hold a solver's arrays. What it holds is then checked as any state is (``mismatch``)."""
    try:
        arrays = state["arrays"]
        ids = np.asarray(arrays["solver.ids"])
        if ids.ndim != 1 or not np.array_equal(np.sort(ids), np.arange(len(ids))):
            raise ValueError("its solver.ids is not an order of its particles")
        order = np.argsort(ids)
        particles = {k: np.asarray(arrays["neighbours._x_build" if k == "x_build" else f"solver.{k}"])[order]
                     for k in PARTICLE_KEYS}
        counters = {k: np.asarray(arrays[f"solver.{k}"]) for k in COUNTERS}
        body = {k: np.asarray(arrays[f"solver.{k}"]) for k in BODIES if f"solver.{k}" in arrays}
    except (KeyError, TypeError, IndexError) as err:
        raise ValueError(f"not one solver's state ({type(err).__name__}: {err})") from None
    return {"format": FORMAT, "particles": particles, "counters": counters, "bodies": body}


def body_arrays(solver) -> dict:
    """The solver's moving bodies' arrays (``BODIES``) as host copies; none without a moving body."""
    wp.synchronize_device(solver.device)
    return {k: getattr(solver, k).numpy().copy() for k in BODIES} if solver._moving else {}


def _layouts(config, n: int) -> tuple:
    """({key: (shape, dtype)} of the particles, the same of the counters) of a run of ``n``
    particles under ``config``."""
    scalar = np.dtype(config.precision)
    rows = {k: ((n, 3) if k in ("pos", "vel", "x_build") else (n,),
                np.dtype(np.int32) if k in ("ptype", "body") else scalar) for k in PARTICLE_KEYS}
    count = {"_clock": ((N_CLOCK,), np.float64), "_steps": ((N_STEPS,), np.int32), "_flags": ((N_FLAGS,), np.int32),
             "_excluded": ((health.N_REASONS,), np.int32),
             "_excluded_mass": ((len(health.EXCLUDED_START),), np.float64),
             "_energy_sum": ((len(health.CENSUS_START),), np.float64)}
    return rows, {k: (shape, np.dtype(dtype)) for k, (shape, dtype) in count.items()}


def mismatch(config, particles, state) -> str:
    """Why ``state`` is not a state of the run under ``config`` (sph.config) whose particles, as
    built, are ``particles`` (sph.particles.Particles); "" when it is. Read before any solver takes
    it up."""
    if not is_portable(state) or set(state) != {"format", "particles", "counters", "bodies"}:
        return f"not a run's state of format {FORMAT!r}"
    rows, count = state["particles"], state["counters"]
    problem = _bodies_mismatch(config, state["bodies"])
    if problem:
        return problem
    if not isinstance(rows, dict) or set(rows) != set(PARTICLE_KEYS):
        return f"its particles are not {', '.join(PARTICLE_KEYS)}"
    if not isinstance(count, dict) or set(count) != set(COUNTERS):
        return f"its counters are not {', '.join(COUNTERS)}"
    n = len(particles)
    want_rows, want_count = _layouts(config, n)
    for held, want, what in ((rows, want_rows, ""), (count, want_count, "counter ")):
        for key, (shape, dtype) in want.items():
            a = held[key]
            if not isinstance(a, np.ndarray) or a.dtype != dtype or a.shape != shape:
                return f"its {what}{key} is not {shape} of {dtype}"
            # a counter may hold infinity (the step loop's target), never NaN; a particle neither
            if a.dtype.kind == "f" and (np.isnan(a).any() if what else not np.isfinite(a).all()):
                return f"its {what}{key} holds a value that is not a number"
    spacing = particles.spacing if particles.spacing is not None else np.full(n, config.dx)
    expected = {"mass": particles.mass, "body": particles.body, "hsml": config.hdx * spacing}
    for key in FIXED:
        if not np.array_equal(rows[key], np.asarray(expected[key]).astype(rows[key].dtype)):
            return f"its {key} is not the run's: a state of another run or scene"
    built = np.asarray(particles.ptype)
    if not np.all((rows["ptype"] == built) | ((rows["ptype"] == EXCLUDED) & (built == FLUID))):
        return "its kinds are not the run's (a fluid particle may only have been excluded)"
    if not (rows["rho"] > 0.0).all():
        return "its densities are not all above 0"
    if np.linalg.norm(rows["vel"], axis=1).max(initial=0.0) > SPEED_LIMIT * config.sound_speed:
        return f"a particle moves faster than {SPEED_LIMIT:g} sound speeds"
    clock, steps, flags = count["_clock"], count["_steps"], count["_flags"]
    if not (np.isfinite(clock[T]) and clock[T] >= 0.0 and np.isfinite(clock[DT]) and clock[DT] >= 0.0):
        return "its clock is not a time and a step"
    if (np.delete(steps, FAILED_STEP) < 0).any() or steps[FAILED_STEP] != -1:
        return "its step counts are not counts of a healthy run"
    if not np.isin(flags, (0, 1)).all() or (count["_excluded"] < 0).any():
        return "its flags or exclusion counts are out of range"
    return ""


def _bodies_mismatch(config, held) -> str:
    """Why ``held`` is not the moving bodies' arrays of a run under ``config``, or ""."""
    motions = config.motions or []
    moving = any(m is not None for m in motions)
    if not isinstance(held, dict) or set(held) != (set(BODIES) if moving else set()):
        return f"its bodies are not {', '.join(BODIES) if moving else 'none'}"
    for key, kind in BODIES.items():
        a = held.get(key)
        if a is None:
            continue
        if key == "_body_sums":
            dtype, shape = np.dtype(np.float64), (2 * len(motions), 3)
        else:
            dtype, shape = np.dtype(kind.numpy_dtype()), (len(motions),)
        if not isinstance(a, np.ndarray) or a.dtype != dtype or a.shape != shape:
            return f"its bodies' {key} is not {shape} of the build's {dtype}"
        values = [a[name] for name in dtype.names] if dtype.names else [a]
        if any(v.dtype.kind == "f" and not np.isfinite(v).all() for v in values):
            return f"its bodies' {key} holds a value that is not finite"
    built = bodies.build(wp.float64).law_list(motions)
    if moving and not (np.array_equal(held["_laws"]["kind"], [law.kind for law in built])
                       and np.array_equal(held["_laws"]["centre"], [list(law.centre) for law in built])):
        return "its bodies' laws are not the run's: a state of another run or scene"
    return ""


def put(solver, rows: dict, count: dict, body_arrays: dict):
    """``rows`` (``PARTICLE_KEYS`` of the solver's particles 0 .. len(rows) - 1, the rest left as they
    are), ``count`` (``COUNTERS``) and ``body_arrays`` (``BODIES``) into ``solver``, its particles
    first put back in the order of their ids (a solver that has stepped has sorted them); its lists
    built from ``x_build``, as the run's last build made them, and their staleness found on the
    positions now."""
    ids = solver.ids.numpy()
    if not np.array_equal(ids, np.arange(len(ids))):
        slot = np.empty(len(ids), dtype=np.int64)
        slot[ids] = np.arange(len(ids))
        solver.permute(slot)  # every per-slot array with it: the walls' ghost offsets, a rank's marks
    m = len(rows["pos"])
    targets = particle_arrays(solver)
    for key in PARTICLE_KEYS:
        a = targets[key].numpy().copy()
        a[:m] = rows[key]
        targets[key].assign(a)
    needs = solver._needs_list.numpy().copy()
    needs[:m] = solver.needs_list(rows["ptype"], rows["body"])
    solver._needs_list.assign(needs)
    for key in COUNTERS:
        getattr(solver, key).assign(count[key])
    for key, kind in BODIES.items():
        if key in body_arrays:
            getattr(solver, key).assign(wp.array(body_arrays[key], dtype=kind, device="cpu"))
    if body_arrays:
        solver._law_list = solver._laws.list()  # the host's copy, which drive() changes and copies whole
        # the moving walls' acceleration where the run's next step puts it first (a fixed wall's zero)
        solver.wall_acc.zero_()
        solver._move_walls(0.0, solver.pos, solver.vel)
    nl = solver.neighbours
    nl.rebuild(wp.clone(nl.x_build), force=True)
    nl.stale.zero_()
    nl.moved(solver.pos, solver.vel, solver.clock)
    solver.update_pressure()
    solver._graph.drop()
    solver._sync()
