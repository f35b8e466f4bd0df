"""A solver's whole state as host data and back: what a checkpoint holds, so that a run stopped and
resumed steps exactly as one that was never stopped (bit for bit on the CPU).

Everything the solver holds between two steps is taken: every device array it and its neighbour
list own (the particles in their cell order, the half-step and candidate states, the rates, the
lists' build positions and cell ranges, the clock, the health census and the exclusions), the
arrays its Fields structs point to, and its plain host values (time, step, counts). Of the
neighbour lists only each list's used entries are kept (a fifth of the array), and the sorted
copies every step makes again are not. What is fixed by the configuration (Params, kernels, the
launcher) is built again from the same configuration.

The lists are stored, not rebuilt from their build positions: particles change level between two
builds (levels.py) and a list built again after that would differ from the one the run holds.
What rebuilds them is checked against the positions it claims (``_sort``): the last sort orders
the build positions by cell, as the sort does, the cell ranges are that order's, every particle
stands within the half skin of its build position while the lists are fresh, and each fluid
particle's list length is what a build from those positions finds. An edited order, build position
or count moved a resumed run by up to a millimetre, and loaded without a word.

A state comes from a file, and a file may have been edited: it is checked whole before anything
changes (``mismatch``). Every array has this solver's shape and dtype exactly; the arrays whose
values index others hold indices in range (a particle's id, kind and body, the cell order and
ranges, the lists); no float is NaN; the host values a run carries (CARRIED: its time, step, the
lists' width) are of their kind and range, and every other host value (a particle count, a level's
h) equals the live solver's, since a count set from a file let kernels index past the arrays. Only
then is every array staged on the device and copied in (``put``), so that a refusal changes nothing.
"""
import hashlib
import math

import numpy as np
import warp as wp

from .health import NO_FAILURE
from .state import BOUNDARY, DT, DT_STABLE, EXCLUDED, FLUID, PASSIVE, TARGET, VACANT, T

# the host values a state carries from its run, each checked for its kind and range; every other
# host value is fixed by the configuration and the particles and must equal the live solver's
CARRIED = {"solver": ("time", "dt", "dt_stable", "steps", "_excluded_host", "_census_host"),
           "neighbours": ("max_neighbours",)}
# host values that say what a cache holds, not the state: never carried or compared
TRANSIENT = ("_view_fresh",)
KINDS = (FLUID, BOUNDARY, EXCLUDED, PASSIVE, VACANT)
# the fastest particle a state may hold, in sound speeds: weakly compressible flow stays far below
# c0, and a particle at 1e30 m/s (an edited state) shrank the step until time stood still
SPEED_LIMIT = 10.0

PLAIN = (bool, int, float, str, type(None), np.ndarray, np.generic)


def _plain(value) -> bool:
    if isinstance(value, (tuple, list)):
        return all(_plain(v) for v in value)
    return isinstance(value, PLAIN)


def _holders(solver) -> dict:
    return {"solver": solver, "neighbours": solver.neighbours, "fields": solver.fields,
            "fields_h": solver._fields_h}


def _members(obj) -> dict:
    """The attributes of an object or of a Warp struct instance."""
    cls = getattr(obj, "_cls", None)
    if cls is not None and hasattr(cls, "vars"):
        return {name: getattr(obj, name) for name in cls.vars}
    return dict(vars(obj))


def device_arrays(solver) -> dict:
    """'holder.name' -> each device array the solver's state lives in, each array once."""
    out, seen = {}, set()
    for holder, obj in _holders(solver).items():
        for name, value in _members(obj).items():
            values = value if isinstance(value, list) else [value]
            for k, array in enumerate(values):
                if isinstance(array, wp.array) and id(array) not in seen:
                    seen.add(id(array))
                    out[f"{holder}.{name}" + (f"[{k}]" if isinstance(value, list) else "")] = array
    return out


# not stored: the lists, which put() builds again from the last build's sort, positions, sorted
# kinds and h and the lists' lengths (NeighbourList.relist), the sorted positions that build
# gathers again, and the slot of each id, which each sort works out again from the ids; the floating
# bodies' wrench table's rows, which the particles as built fix (body_sums.py), the live solver's
# as a file's (an index read from a file would let a kernel write past the table)
NOT_STORED = ("neighbours.nbr", "neighbours._pos_sorted", "neighbours._slot_of", "solver._wrench_rows",
              "solver._row_body")


def _width(state) -> "int | None":
    """The width of the lists ``state`` was taken from (the solver measures its own: neighbours.py)."""
    width = state["host"].get("neighbours", {}).get("max_neighbours") if isinstance(state["host"], dict) else None
    return width if isinstance(width, int) and not isinstance(width, bool) and width > 0 else None


def _copied(value):
    """``value`` with its arrays copied: a state is what the run held when it was taken."""
    if isinstance(value, (tuple, list)):
        return type(value)(_copied(v) for v in value)
    return value.copy() if isinstance(value, np.ndarray) else value


def _host(solver) -> dict:
    """{holder: {name: value}}: the plain host values a checkpoint holds."""
    return {holder: {name: _copied(value) for name, value in vars(obj).items()
                     if _plain(value) and name not in TRANSIENT}
            for holder, obj in (("solver", solver), ("neighbours", solver.neighbours))}


def _stored(solver) -> dict:
    return {path: a for path, a in device_arrays(solver).items() if path not in NOT_STORED}


def capture(solver) -> dict:
    """The solver's state: {"arrays": {path: numpy copy}, "host": {holder: {name: value}}}."""
    wp.synchronize_device(solver.device)
    return {"arrays": {path: a.numpy().copy() for path, a in _stored(solver).items()}, "host": _host(solver)}


def layout(target: wp.array) -> tuple:
    """(shape, numpy dtype) of ``target``'s host copy: a vector's or matrix's components a last axis."""
    dtype = target.dtype
    if hasattr(dtype, "numpy_dtype"):  # a struct
        return target.shape, np.dtype(dtype.numpy_dtype())
    if hasattr(dtype, "_wp_scalar_type_"):  # a vector, matrix or quaternion
        return target.shape + tuple(dtype._shape_), np.dtype(wp.dtype_to_numpy(dtype._wp_scalar_type_))
    return target.shape, np.dtype(wp.dtype_to_numpy(dtype))


def _fields(data: np.ndarray):
    """``data`` itself, or a struct array's fields, each as an array of its own (a struct's padding
    holds no value, and Warp leaves it arbitrary in a host copy)."""
    if data.dtype.names:
        for name in data.dtype.names:
            yield from _fields(data[name])
    else:
        yield data


def _permutation(a, n: int) -> bool:
    return a.shape == (n,) and np.array_equal(np.sort(a), np.arange(n))


def _indices(solver, arrays: dict) -> str:
    """What in ``arrays`` would index past another array, or ""."""
    n = solver.n
    bodies = max(1, len(solver.config.motions or []))
    if not _permutation(arrays["solver.ids"], n):
        return f"solver.ids is not an order of this solver's {n} particles"
    order = arrays["neighbours._order"]  # the cell sort's buffers, twice n long
    if order.min(initial=0) < 0 or order.max(initial=0) >= n:
        return f"neighbours._order holds indices outside [0, {n - 1}]"
    if not solver.neighbours.cells and not _permutation(order[:n], n):  # put() lists the particles in it
        return f"neighbours._order does not begin with an order of this solver's {n} particles"
    for path in ("solver.ptype", "neighbours._ptype_sorted", "neighbours._ptype_built"):
        if path in arrays and not np.isin(arrays[path], KINDS).all():
            return f"{path} holds kinds other than {', '.join(map(str, KINDS))}"
    body = arrays["solver.body"]
    if body.min(initial=-1) < -1 or body.max(initial=-1) >= bodies:
        return f"solver.body lies outside [-1, {bodies - 1}]"
    for path in ("neighbours._start", "neighbours._end"):
        if arrays[path].min(initial=0) < 0 or arrays[path].max(initial=0) > n:
            return f"{path} lies outside [0, {n}]"
    return ""


def _values(solver, arrays: dict, host: dict) -> str:
    """What in ``arrays`` no run of this solver holds, or "": a particle's h other than a level's
    (all zero, the clock stood still), a particle's mass or density not above 0, a speed above
    SPEED_LIMIT sound speeds, a failure recorded, a clock other than the state's time or not a time
    (only its target may be infinite)."""
    # a search's reach follows h; the build's copies are zero until a first build
    for path, levels in (("solver.hsml", solver._level_h), ("neighbours._hsml_sorted", [0.0, *solver._level_h]),
                         ("neighbours._hsml_built", [0.0, *solver._level_h])):
        hsml = arrays.get(path, arrays["solver.hsml"])
        if not np.isin(hsml, np.asarray(levels, dtype=hsml.dtype)).all():
            return f"{path} holds an h that is none of this solver's levels'"
    held = arrays["solver.ptype"] != VACANT  # a refinement level's reserved slots hold nothing yet
    for path in ("solver.mass", "solver.rho"):
        if not (arrays[path][held] > 0).all():
            return f"{path} holds a value that is not above 0 for a particle"
    speed = np.linalg.norm(arrays["solver.vel"][held].astype(np.float64), axis=-1).max(initial=0.0)
    limit = SPEED_LIMIT * solver.config.sound_speed
    if speed > limit:
        return (f"solver.vel holds a speed of {speed:.3g} m/s, above {SPEED_LIMIT:g} c0 = {limit:.3g} m/s: no flow "
                f"this solver steps moves that fast, and its step would vanish")
    # a state is of a run that has not failed (a failed run's is not kept), and the host reads a
    # failure's slot as the index of the particle or body at fault
    if not (arrays["solver._fail"] == NO_FAILURE).all():
        return "solver._fail holds a failure: a state is taken from a run that has not failed"
    clock = arrays["solver._clock"]
    if not (np.isfinite(clock[:TARGET]).all() and (clock[[T, DT, DT_STABLE]] >= 0.0).all()):
        return "solver._clock holds a time or step that is not finite and at least 0"
    if clock[T] != host["solver"]["time"]:
        return f"solver._clock's time {clock[T]!r} s is not the state's time"
    return ""


def _carried(name: str, value, live) -> bool:
    """Whether ``value`` from a state may stand for the live run's carried host value ``live``."""
    if isinstance(live, float):
        return isinstance(value, float) and math.isfinite(value) and value >= 0.0
    if isinstance(live, int):
        return type(value) is int and value >= (1 if name == "max_neighbours" else 0)
    if isinstance(live, np.ndarray):
        return (isinstance(value, np.ndarray) and value.shape == live.shape and value.dtype == live.dtype
                and not np.isnan(value).any())
    if isinstance(live, tuple):
        return (isinstance(value, tuple) and len(value) == len(live)
                and all(_carried(name, v, w) for v, w in zip(value, live)))
    return live is None


def _equal(a, b) -> bool:
    if isinstance(a, (tuple, list)):
        return type(a) is type(b) and len(a) == len(b) and all(_equal(x, y) for x, y in zip(a, b))
    if isinstance(a, (np.ndarray, np.generic)):
        return isinstance(b, (np.ndarray, np.generic)) and a.dtype == b.dtype and np.array_equal(a, b)
    return type(a) is type(b) and a == b


def mismatch(solver, state) -> str:
    """What in ``state`` does not fit ``solver``, or "": its arrays' names, shapes, dtypes and the
    values that index (``_indices``), NaN anywhere, the lists' width and entries, and its host
    values (CARRIED in kind and range, the others equal to the live solver's)."""
    if not (isinstance(state, dict) and isinstance(state.get("arrays"), dict) and isinstance(state.get("host"), dict)):
        return "it holds no arrays and host values"
    arrays = _stored(solver)
    if set(arrays) != set(state["arrays"]):
        return "its arrays are not this solver's: " + ", ".join(sorted(set(arrays) ^ set(state["arrays"])))
    for path, target in arrays.items():
        data = state["arrays"][path]
        shape, dtype = layout(target)
        if not isinstance(data, np.ndarray) or data.shape != shape:
            return f"{path} has shape {getattr(data, 'shape', None)}, this solver's {shape}"
        if data.dtype != dtype:
            return f"{path} holds {data.dtype}, this solver's {dtype}"
        if any(f.dtype.kind == "f" and (np.isnan(f).any() or (path != "solver._clock" and np.isinf(f).any()))
               for f in _fields(data)):
            return f"{path} holds a value that is not finite"
    problem = _indices(solver, state["arrays"]) or _lists(solver, state)
    if problem:
        return problem
    for holder, values in _host(solver).items():
        given = state["host"].get(holder)
        if not isinstance(given, dict) or set(given) != set(values):
            return f"its {holder} values are not this solver's"
        for name, live in values.items():
            if name in CARRIED[holder]:
                if not _carried(name, given[name], live):
                    return f"its {holder} value {name} is not a value this solver can carry on from"
            elif not _equal(live, given[name]):
                return f"its {holder} value {name} differs from this solver's: the state is of another run"
    # last: it runs the sort's and the lists' passes over the state, whose every value must be in range
    return (_values(solver, state["arrays"], state["host"]) or _on_bodies(solver, state["arrays"])
            or _sort(solver, state["arrays"], _width(state)))


def _lists(solver, state) -> str:
    """What in ``state``'s neighbour lists does not fit ``solver``'s, or "" (none where it walks the
    cells)."""
    nl = solver.neighbours
    if nl.cells:
        return ""
    count, width = state["arrays"]["neighbours.count"], _width(state)
    if width is None:
        return "it holds no width of its neighbour lists (neighbours.max_neighbours)"
    widest = solver._widest if solver._measured_width else nl.max_neighbours
    if width > widest:
        return f"its neighbour lists are {width} wide, more than this solver's {widest}"
    if count.min(initial=0) < 0 or count.max(initial=0) > width:
        return f"neighbours.count lies outside [0, {width}]"
    return ""


def _rotate(q: np.ndarray, v: np.ndarray) -> np.ndarray:
    """Each v rotated by each unit quaternion q = (x, y, z, w) (Warp's order), row by row."""
    u, w = q[:, :3], q[:, 3:4]
    t = 2.0 * np.cross(u, v)
    return v + w * t + np.cross(u, t)


def _on_bodies(solver, arrays: dict) -> str:
    """What puts a moving body's particle off where its body's pose places it, or "": each step sets
    it there from its rest position, which ``solver.ids`` finds (shuffled ids loaded, and the bodies'
    particles jumped onto others' places until the step vanished)."""
    if "solver._poses" not in arrays:
        return ""
    from .bodies import FIXED

    laws, poses = arrays["solver._laws"], arrays["solver._poses"]
    body, ptype = arrays["solver.body"], arrays["solver.ptype"]
    moving = (body >= 0) & (ptype == BOUNDARY)
    moving[moving] = laws["kind"][body[moving]] != FIXED
    if not moving.any():
        return ""
    b = body[moving]
    rest = arrays["solver._rest"][arrays["solver.ids"][moving]]
    placed = poses["x"][b] + _rotate(poses["q"][b], rest - laws["centre"][b])
    pos = arrays["solver.pos"][moving].astype(np.float64)
    off = np.linalg.norm(pos - placed, axis=1)
    # float32 positions carry a rounding of their size; a particle one spacing off is not that
    allowed = 1.0e-4 * solver.config.dx + 4.0 * np.finfo(arrays["solver.pos"].dtype).eps * np.abs(placed).max()
    if off.max() > allowed:
        i = int(np.flatnonzero(moving)[np.argmax(off)])
        return (f"a moving body's particle ({i}) stands {off.max():.3g} m from where its body's pose and its rest "
                f"position (solver._poses, solver._rest[solver.ids]) place it: ids, poses or positions were edited")
    return ""


def _sort(solver, arrays: dict, width: int) -> str:
    """What in the last build a state holds does not follow from the positions it was built on, or
    "": its sort, cell ranges, build positions and (with lists) its fluid particles' list lengths,
    each worked out again with the solver's own passes (the cell keys and a list's search)."""
    nl = solver.neighbours
    n, device = solver.n, solver.device
    if int(arrays["neighbours.builds"][0]) == 0:  # nothing built yet: the first step builds it all
        return ""
    order = arrays["neighbours._order"][:n]
    if not _permutation(order, n):
        return f"neighbours._order does not begin with an order of this solver's {n} particles"
    vec = nl._x_build.dtype
    x_build = arrays["neighbours._x_build"]
    if nl.cells:
        built = arrays["neighbours._ptype_built"]
    else:
        built = np.empty(n, dtype=np.int32)
        built[order] = arrays["neighbours._ptype_sorted"]
    keys, values = wp.zeros(n, dtype=wp.int32, device=device), wp.zeros(n, dtype=wp.int32, device=device)
    x_dev = wp.array(x_build, dtype=vec, device=device)
    slots = wp.array(np.arange(n, dtype=np.int32), dtype=wp.int32, device=device)  # each slot's key, in slot order
    wp.launch(nl._passes.cell_keys, dim=n, inputs=[nl.grid, x_dev, wp.array(built, dtype=wp.int32, device=device),
                                                   slots, keys, values], device=device)
    key = keys.numpy()[order]
    step = np.diff(key)
    # a cell's particles by id (this version's sort) or by slot (the sort before it, keyed on the
    # cell alone): the lists rebuilt from either are the run's
    tied = step == 0
    by_id, by_slot = (not ((np.diff(arrays["solver.ids"][order]) < 0) & tied).any(),
                      not ((np.diff(order) < 0) & tied).any())
    if (step < 0).any() or not (by_id or by_slot):
        return ("neighbours._order is not the cell sort of the build positions (neighbours._x_build): the "
                "lists it rebuilds are not the run's")
    ncells = len(arrays["neighbours._start"])
    start, end = np.zeros(ncells, dtype=np.int32), np.zeros(ncells, dtype=np.int32)
    inside = key < ncells
    cells, first = np.unique(key[inside], return_index=True)
    start[cells] = first
    end[cells] = np.append(first[1:], inside.sum())
    if not (np.array_equal(start, arrays["neighbours._start"]) and np.array_equal(end, arrays["neighbours._end"])):
        return "neighbours._start and _end are not the cell ranges of its sort"
    if int(arrays["neighbours.stale"][0]) == 0:  # fresh lists: nobody has moved half the skin since
        held = arrays["solver.ptype"] != VACANT
        d = (arrays["solver.pos"] - x_build)[held].astype(np.float64)
        g = nl.grid
        for ax in range(3):
            if g.periodic[ax]:
                d[:, ax] -= float(g.length[ax]) * np.round(d[:, ax] / float(g.length[ax]))
        far = np.linalg.norm(d, axis=1).max(initial=0.0)
        if far > float(g.half_skin) * (1.0 + 1.0e-4):
            return (f"a particle stands {far:.3g} m from its build position (neighbours._x_build), past the "
                    f"half skin {float(g.half_skin):.3g} m its lists allow: the positions are not those its "
                    "lists were built on")
    if nl.cells:
        return ""
    # each fluid particle's list length, found again from the build positions in the state's sort,
    # in lists as wide as the state's (put() widens the solver's to them)
    stored = arrays["neighbours.count"]
    sorted_pos = wp.array(x_build[order], dtype=vec, device=device)
    found = wp.zeros(n, dtype=wp.int32, device=device)
    lists = wp.zeros((n, width), dtype=wp.int32, device=device)
    grid = type(nl.grid)()
    for name in nl.grid._cls.vars:
        setattr(grid, name, getattr(nl.grid, name))
    grid.max_neighbours = width
    fail = wp.array(np.full(1, NO_FAILURE, dtype=np.int32), dtype=wp.int32, device=device)
    wp.launch(nl._passes.neighbour_list, dim=n,
              inputs=[grid, sorted_pos, wp.array(arrays["neighbours._ptype_sorted"], dtype=wp.int32, device=device),
                      wp.array(arrays["neighbours._hsml_sorted"], dtype=nl._hsml_sorted.dtype, device=device),
                      wp.array(order, dtype=wp.int32, device=device),
                      wp.array(arrays["neighbours._start"], dtype=wp.int32, device=device),
                      wp.array(arrays["neighbours._end"], dtype=wp.int32, device=device), lists, found,
                      wp.array(arrays["solver._needs_list"], dtype=wp.int32, device=device),
                      wp.array(arrays["solver.ghost"], dtype=vec, device=device), wp.zeros_like(x_dev),
                      wp.zeros(1, dtype=wp.int32, device=device), fail, 0, wp.ones(1, dtype=wp.int32, device=device),
                      0, 1], device=device)
    found = found.numpy()
    fluid = built == FLUID
    # a particle made since the build (a refinement level's) has no list yet: only a run with levels
    # holds one, and it reads 0 where a build would find some
    wrong = fluid & (stored != found) & ~((stored == 0) & (len(solver._level_h) > 1))
    if wrong.any():
        i = int(np.flatnonzero(wrong)[0])
        return (f"neighbours.count is not what its build positions give: particle {i} lists {int(stored[i])} "
                f"neighbours where a build finds {int(found[i])}")
    return ""


def fingerprint(state: dict) -> dict:
    """{field: a digest of its values} of ``state`` (``capture``): two states hold the same values,
    bit for bit, where their fingerprints are equal."""
    out = {path: hashlib.sha256(b"".join(np.ascontiguousarray(f).tobytes() for f in _fields(a))).hexdigest()
           for path, a in state["arrays"].items()}
    for holder, values in state["host"].items():
        out.update({f"{holder}.{name}": repr(v) for name, v in values.items()})
    return out


def restore(solver, state: dict):
    """Put ``state`` (``capture`` of a solver of the same configuration and particle count) into
    ``solver``; ValueError naming what does not match, before anything is changed."""
    problem = mismatch(solver, state)
    if problem:
        raise ValueError(f"checkpoint: {problem}")
    put(solver, state)


def put(solver, state: dict):
    """Put ``state`` into ``solver``, which ``mismatch`` has found it fits; its lists as wide as
    they were. Every array is built on the device before the first is copied in."""
    nl = solver.neighbours
    width = _width(state)
    staged = {path: wp.array(state["arrays"][path], dtype=target.dtype, device=target.device)
              for path, target in _stored(solver).items()}
    if width != nl.max_neighbours and not nl.cells:
        solver.resize_lists(width)
    for path, target in _stored(solver).items():
        wp.copy(target, staged[path])
    if not nl.cells:
        nl.relist()
    for holder, obj in (("solver", solver), ("neighbours", nl)):
        for name, value in state["host"][holder].items():
            setattr(obj, name, value)
    solver._view_fresh = False
    wp.synchronize_device(solver.device)
