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
"""
import numpy as np
import warp as wp

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


# not stored: the sorted copies every step's cell sort makes again before a pass reads them, and the
# lists, whose used entries are stored packed (LISTS) instead of the whole fixed-width array
NOT_STORED = ("neighbours.nbr", "neighbours._pos_sorted", "neighbours._ptype_sorted", "neighbours._hsml_sorted")
LISTS = "neighbours.nbr_used"


def _used(width: int, count) -> np.ndarray:
    """Which entries of lists ``width`` wide (n x width) hold a neighbour."""
    return np.arange(width)[None, :] < np.asarray(count)[:, None]


def _width(state) -> "int | None":
    """The width of the lists ``state`` was taken from (the solver measures its own: neighbours.py)."""
    width = state["host"].get("neighbours", {}).get("max_neighbours") if isinstance(state["host"], dict) else None
    return width if isinstance(width, int) and not isinstance(width, bool) and width > 0 else None


def _host(solver) -> dict:
    """{holder: {name: value}}: the plain host values a checkpoint holds."""
    return {holder: {name: value for name, value in vars(obj).items() if _plain(value)}
            for holder, obj in (("solver", solver), ("neighbours", solver.neighbours))}


def _stored(solver) -> dict:
    return {path: a for path, a in device_arrays(solver).items() if path not in NOT_STORED}


def capture(solver) -> dict:
    """The solver's state: {"arrays": {path: numpy copy}, "host": {holder: {name: value}}}."""
    wp.synchronize_device(solver.device)
    arrays = {path: a.numpy().copy() for path, a in _stored(solver).items()}
    nl = solver.neighbours
    arrays[LISTS] = nl.nbr.numpy()[_used(nl.max_neighbours, arrays["neighbours.count"])]
    return {"arrays": arrays, "host": _host(solver)}


def mismatch(solver, state) -> str:
    """What in ``state`` does not fit ``solver`` (its arrays' names and shapes, the lists' length,
    the host values' names and types), or ""."""
    if not (isinstance(state, dict) and isinstance(state.get("arrays"), dict) and isinstance(state.get("host"), dict)):
        return "it holds no arrays and host values"
    arrays = _stored(solver)
    if set(arrays) | {LISTS} != set(state["arrays"]):
        return "its arrays are not this solver's: " + ", ".join(sorted((set(arrays) | {LISTS}) ^ set(state["arrays"])))
    for path, target in arrays.items():
        data = state["arrays"][path]
        if not isinstance(data, np.ndarray) or data.shape[:target.ndim] != target.shape:  # (n,) of vectors: (n, 3)
            return f"{path} has shape {getattr(data, 'shape', None)}, this solver's {target.shape}"
    nl, count, width = solver.neighbours, state["arrays"]["neighbours.count"], _width(state)
    if width is None:
        return "it holds no width of its neighbour lists (neighbours.max_neighbours)"
    if count.min(initial=0) < 0 or count.max(initial=0) > width:
        return f"neighbours.count lies outside [0, {width}]"
    lists, used = state["arrays"][LISTS], int(count.sum())
    if not isinstance(lists, np.ndarray) or lists.shape != (used,) or not 0 <= lists.min(initial=0) <= lists.max(
            initial=0) < nl.n:
        return f"{LISTS} is not {used} indices of this solver's {nl.n} particles"
    for holder, values in _host(solver).items():
        given = state["host"].get(holder)
        if not isinstance(given, dict) or set(given) != set(values):
            return f"its {holder} values are not this solver's"
        wrong = [name for name, value in values.items()  # None stands for a value not yet known
                 if value is not None and given[name] is not None and type(given[name]) is not type(value)]
        if wrong:
            return f"its {holder} values {', '.join(wrong)} are not of this solver's types"
    return ""


def restore(solver, state: dict):
    """Put ``state`` (``capture`` of a solver of the same configuration and particle count) into
    ``solver``; ValueError naming what does not match, before anything is changed."""
    problem = mismatch(solver, state)
    if problem:
        raise ValueError(f"checkpoint: {problem}")
    put(solver, state)


def put(solver, state: dict):
    """Put ``state`` into ``solver``, which ``mismatch`` has found it fits; its lists as wide as
    they were."""
    nl = solver.neighbours
    width = _width(state)
    if width != nl.max_neighbours:
        solver.resize_lists(width)
    for path, target in _stored(solver).items():
        wp.copy(target, wp.array(state["arrays"][path], dtype=target.dtype, device=target.device))
    lists = np.array(nl.nbr.numpy())
    lists[_used(width, state["arrays"]["neighbours.count"])] = state["arrays"][LISTS]
    nl.nbr.assign(lists)
    for holder, obj in (("solver", solver), ("neighbours", nl)):
        for name, value in state["host"][holder].items():
            setattr(obj, name, value)
    wp.synchronize_device(solver.device)
