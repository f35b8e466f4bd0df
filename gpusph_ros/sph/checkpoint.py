"""A solver's whole state as host data and back: what a checkpoint holds, so that a run stopped and
resumed steps exactly as one that was never stopped (bit for bit on the CPU).

Everything the solver holds between two steps is taken: every device array it and its neighbour
list own (the particles in their cell order, the half-step and candidate states, the rates, the
lists' build positions and cell ranges, the clock, the health census and the exclusions), the
arrays its Fields structs point to, and its plain host values (time, step, counts). The neighbour
lists themselves are rebuilt on restore from the build positions (the same pairs in the same
order), and what is fixed by the configuration (Params, kernels, the launcher) is built again from
the same configuration.
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


# rebuilt on restore instead of stored (four fifths of a checkpoint): the lists and the sorted copies
# they were built from, which a rebuild from the stored build positions gives again, pair for pair
REBUILT = ("neighbours.nbr", "neighbours.count", "neighbours._pos_sorted", "neighbours._ptype_sorted",
           "neighbours._hsml_sorted")
# the neighbour list's own bookkeeping, which that rebuild moves on and which is put back after it
KEPT_OVER_REBUILD = ("neighbours.stale", "neighbours.builds", "neighbours.overflow")


def capture(solver) -> dict:
    """The solver's state: {"arrays": {path: numpy copy}, "host": {holder: {name: value}}}."""
    wp.synchronize_device(solver.device)
    arrays = {path: a.numpy().copy() for path, a in device_arrays(solver).items() if path not in REBUILT}
    host = {holder: {name: value for name, value in vars(obj).items() if _plain(value)}
            for holder, obj in (("solver", solver), ("neighbours", solver.neighbours))}
    return {"arrays": arrays, "host": host}


def restore(solver, state: dict):
    """Put ``state`` (``capture`` of a solver of the same configuration and particle count) into
    ``solver``; ValueError naming what does not match."""
    arrays = {path: a for path, a in device_arrays(solver).items() if path not in REBUILT}
    if set(arrays) != set(state["arrays"]):
        raise ValueError("checkpoint: its arrays are not this solver's: " +
                         ", ".join(sorted(set(arrays) ^ set(state["arrays"]))))

    def put(paths):
        for path in paths:
            target, data = arrays[path], state["arrays"][path]
            if data.shape[:target.ndim] != target.shape:  # a vector array: (n,) holding (n, 3)
                raise ValueError(f"checkpoint: {path} has shape {data.shape}, this solver's {target.shape}")
            wp.copy(target, wp.array(data, dtype=target.dtype, device=target.device))

    put(arrays)
    # the lists as they were built: from the build positions, in the array order of that build
    nl = solver.neighbours
    nl.rebuild(wp.clone(nl.x_build), force=True)
    put(KEPT_OVER_REBUILD)
    for holder, obj in (("solver", solver), ("neighbours", nl)):
        for name, value in state["host"][holder].items():
            setattr(obj, name, value)
    wp.synchronize_device(solver.device)
