"""The saved state's file (gpusph_ros/output/state_file.py): data that cannot run code. What is written
reads back equal, type for type; numpy reads it as an .npz without pickle; a pickle (what earlier
versions wrote), a file cut anywhere, a FIFO, a folder, another kind of state, compressed or
object members are each refused with the reason, and nothing a file holds is ever run."""
import io
import json
import os
import pickle
import threading
import zipfile

import numpy as np
import pytest

from gpusph_ros.output import state_file
from gpusph_ros.output.state_file import StateFileError

pytestmark = pytest.mark.unit


def _tree():
    return {"invocation": {"scene": "collapse_2d", "run_config": [], "sets": ["dx=0.01"]},
            "host": {"n": 138, "time": 0.1 + 0.2, "big": 2 ** 70, "none": None, "flag": True, "inf": float("inf"),
                     "pair": (np.arange(5, dtype=np.int32), np.array([0.0, -1.0])), "levels": [0.026, 0.013]},
            "arrays": {"pos": np.random.default_rng(1).random((7, 3), dtype=np.float32),
                       "count": np.arange(7, dtype=np.int32), "empty": np.zeros(0)},
            "scalar": np.float32(0.1), "tagged": {"__array__": 3, "__tuple__": "text"}, "text": "caf\xe9\n"}


def _same(a, b):
    assert type(a) is type(b), (a, b)
    if isinstance(a, dict):
        assert list(a) == list(b)
        for k in a:
            _same(a[k], b[k])
    elif isinstance(a, (list, tuple)):
        assert len(a) == len(b)
        for x, y in zip(a, b):
            _same(x, y)
    elif isinstance(a, (np.ndarray, np.generic)):
        assert a.dtype == b.dtype and a.shape == b.shape and np.array_equal(a, b)
    else:
        assert a == b


def test_a_state_reads_back_equal_type_for_type_and_numpy_reads_it_without_pickle(tmp_path):
    path = state_file.write(tmp_path / "state.npz", "checkpoint", _tree())
    _same(state_file.read(path, "checkpoint", ("invocation", "host")), _tree())
    with np.load(path, allow_pickle=False) as npz:
        assert "header" in npz.files and npz["a0"].dtype == np.int32
    assert [p.name for p in tmp_path.iterdir()] == ["state.npz"]  # the temporary file is gone
    with pytest.raises(StateFileError, match="lacks run"):
        state_file.read(path, "checkpoint", ("run",))
    with pytest.raises(StateFileError, match="is a 'checkpoint', not a 'node state'"):
        state_file.read(path, "node state")
    with pytest.raises(TypeError, match="not data"):
        state_file.write(tmp_path / "other.npz", "checkpoint", {"f": len})


class _Payload:
    """What an attacker puts in a pickle: loading it runs a shell command."""

    def __init__(self, marker):
        self.marker = marker

    def __reduce__(self):
        return os.system, (f"touch {self.marker}",)


@pytest.mark.parametrize("protocol", [0, pickle.HIGHEST_PROTOCOL])
def test_a_pickle_carrying_code_is_refused_and_never_run(tmp_path, protocol):
    marker = tmp_path / "ran"
    path = tmp_path / "state.npz"
    path.write_bytes(pickle.dumps({"run": _Payload(marker)}, protocol=protocol))
    with pytest.raises(StateFileError) as err:
        state_file.read(path, "checkpoint")
    words = "earlier version (a Python pickle)" if protocol else "not a gpusph_ros state file"
    assert words in str(err.value) and not marker.exists()
    pickle.loads(path.read_bytes())  # the payload is live: loading it the way earlier versions did runs it
    assert marker.exists()
    marker.unlink()
    # an .npz that carries a pickled object: refused by numpy's allow_pickle=False, never unpickled
    with zipfile.ZipFile(path, "w") as z:
        with z.open("header.npy", "w") as m:
            np.lib.format.write_array(m, np.frombuffer(b'{"format": "gpusph_ros state", "version": 2, '
                                                       b'"kind": "checkpoint", "state": {"__array__": 0}}',
                                                       dtype=np.uint8))
        with z.open("a0.npy", "w") as m:
            np.lib.format.write_array(m, np.array([_Payload(marker)], dtype=object), allow_pickle=True)
    with pytest.raises(StateFileError, match="cannot be read"):
        state_file.read(path, "checkpoint")
    assert not marker.exists()


def test_a_file_cut_anywhere_is_refused_as_cut(tmp_path):
    whole = state_file.write(tmp_path / "whole.npz", "checkpoint", _tree()).read_bytes()
    for k in range(1, 11):
        cut = tmp_path / f"cut_{k}.npz"
        cut.write_bytes(whole[:len(whole) * k // 11])
        with pytest.raises(StateFileError, match="cut short or damaged|no .npz"):
            state_file.read(cut, "checkpoint")


def test_a_compressed_member_is_refused(tmp_path):
    path = state_file.write(tmp_path / "state.npz", "checkpoint", _tree())
    packed = tmp_path / "packed.npz"
    with zipfile.ZipFile(path) as src, zipfile.ZipFile(packed, "w", zipfile.ZIP_DEFLATED) as dst:
        for info in src.infolist():
            dst.writestr(info.filename, src.read(info))
    with pytest.raises(StateFileError, match="compressed"):
        state_file.read(packed, "checkpoint")


def _within(seconds, fn, *args):
    """fn(*args)'s exception, failing if it does not come within ``seconds`` (a blocked open)."""
    out = {}

    def call():
        try:
            fn(*args)
        except Exception as err:
            out["err"] = err

    worker = threading.Thread(target=call, daemon=True)
    worker.start()
    worker.join(seconds)
    assert not worker.is_alive(), f"{fn.__name__} blocked"
    return out.get("err")


def test_a_fifo_a_folder_or_a_device_is_refused_at_once(tmp_path):
    fifo = tmp_path / "fifo"
    os.mkfifo(fifo)
    err = _within(2.0, state_file.read, fifo, "checkpoint")
    assert isinstance(err, StateFileError) and "is a FIFO, not a regular file" in str(err)
    err = _within(2.0, state_file.write, fifo, "checkpoint", {})
    assert isinstance(err, StateFileError) and "is a FIFO" in str(err) and fifo.exists()
    err = _within(2.0, state_file.read, tmp_path, "checkpoint")
    assert isinstance(err, StateFileError) and "is a folder" in str(err)
    err = _within(2.0, state_file.read, "/dev/zero", "checkpoint")
    assert isinstance(err, StateFileError) and "is a device" in str(err)
    err = _within(2.0, state_file.read, tmp_path / "none.npz", "checkpoint")
    assert isinstance(err, StateFileError) and "cannot be opened: No such file" in str(err)


def _rewrite_header(path, change):
    """``path`` with its header's JSON changed by ``change`` (a function of the header dict)."""
    with zipfile.ZipFile(path) as z:
        members = {name: z.read(name) for name in z.namelist()}
    header = json.loads(np.lib.format.read_array(io.BytesIO(members["header.npy"])).tobytes().decode())
    buffer = io.BytesIO()
    np.lib.format.write_array(buffer, np.frombuffer(json.dumps(change(header)).encode(), dtype=np.uint8))
    members["header.npy"] = buffer.getvalue()
    with zipfile.ZipFile(path, "w", zipfile.ZIP_STORED) as z:
        for name, data in members.items():
            z.writestr(name, data)


def test_a_member_named_twice_is_refused_and_nothing_is_quoted_whole(tmp_path):
    # an 8 MB member named 300 times took a reader to 2.8 GB: each member is read once
    path = state_file.write(tmp_path / "state.npz", "checkpoint", {"a": np.zeros(10), "b": np.ones(3)})
    _rewrite_header(path, lambda h: {**h, "state": {"a": {"__array__": 0}, "b": [{"__array__": 0}] * 300}})
    with pytest.raises(StateFileError, match="names member a0.npy twice"):
        state_file.read(path, "checkpoint")
    for field in ("version", "kind"):
        _rewrite_header(path, lambda h: {**h, field: "v" * 1_000_000})
        with pytest.raises(StateFileError) as err:
            state_file.read(path, "checkpoint")
        assert len(str(err.value)) < 600, field
    _rewrite_header(path, lambda h: {**h, "version": state_file.VERSION, "kind": "checkpoint",
                                     "state": {"a": {"__array__": "r" * 1_000_000}}})
    with pytest.raises(StateFileError, match="is not a number") as err:
        state_file.read(path, "checkpoint")
    assert len(str(err.value)) < 600


def test_a_tree_nested_too_deep_is_refused_as_such(tmp_path):
    path = state_file.write(tmp_path / "state.npz", "checkpoint", {"a": 1})
    text = json.dumps({"format": state_file.FORMAT, "version": state_file.VERSION, "kind": "checkpoint",
                       "state": "PLACEHOLDER"}).replace('"PLACEHOLDER"', "[" * 100_000 + "]" * 100_000)
    buffer = io.BytesIO()
    np.lib.format.write_array(buffer, np.frombuffer(text.encode(), dtype=np.uint8))
    with zipfile.ZipFile(path, "w", zipfile.ZIP_STORED) as z:
        z.writestr("header.npy", buffer.getvalue())
    with pytest.raises(StateFileError, match="nested deeper"):
        state_file.read(path, "checkpoint")
