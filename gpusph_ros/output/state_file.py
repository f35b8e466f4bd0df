"""A run's saved state as data that cannot run code: a checkpoint of ``gpusph-run`` and the node's
``~/save_state`` file.

The file is an ``.npz`` (a zip of ``.npy`` arrays, stored uncompressed) that ``numpy.load(path,
allow_pickle=False)`` reads: ``header.npy`` holds a JSON document (UTF-8 bytes as uint8) naming the
format and its version and holding the state's tree of dicts, lists, text and numbers; every numpy
array or scalar of the tree is a member ``aN.npy`` of its own, which the tree names. Nothing in it
is a Python object: reading it builds only dicts, lists, tuples, numbers, text and numeric arrays.

Earlier versions wrote a Python pickle, which runs whatever code the file carries when it is loaded.
Such a file is recognised by its first byte and refused, saying why; it is never unpickled.

Only a regular file is read or replaced: a FIFO, a device or a folder named as a state file is
refused at once (opening a FIFO to read blocks until a writer comes, and would hang the caller).

A file cannot make its reader hold more than the file's own size in arrays: members are stored, not
compressed, each is read once, and a tree that names one member twice is refused (the writer names
each array once; an 8 MB member named 300 times took a reader to 2.8 GB). Nothing the file holds is
quoted whole in an error.
"""
import io
import json
import os
import stat
import tempfile
import zipfile
from pathlib import Path

import numpy as np

FORMAT = "gpusph_ros state"
VERSION = 2  # 1: the pickle of earlier versions, never read
HEADER = "header.npy"
ZIP_MAGIC = b"PK\x03\x04"
PICKLE_MAGIC = b"\x80"  # a pickle of protocol 2 or later
# the tags of the values JSON has no type for; a dict with one of them as a key is written as pairs
ARRAY, SCALAR, TUPLE, PAIRS = "__array__", "__scalar__", "__tuple__", "__pairs__"
TAGS = (ARRAY, SCALAR, TUPLE, PAIRS)


class StateFileError(ValueError):
    """A state file that cannot be read or written, with the reason."""


def _encode(value, arrays: list):
    if isinstance(value, np.ndarray):
        if value.dtype.hasobject:
            raise TypeError(f"an array of Python objects ({value.dtype}) is not data")
        arrays.append(value)
        return {ARRAY: len(arrays) - 1}
    if isinstance(value, np.generic):
        arrays.append(np.asarray(value))
        return {SCALAR: len(arrays) - 1}
    if isinstance(value, tuple):
        return {TUPLE: [_encode(v, arrays) for v in value]}
    if isinstance(value, list):
        return [_encode(v, arrays) for v in value]
    if isinstance(value, dict):
        if not all(isinstance(k, str) for k in value):
            raise TypeError(f"a dict with keys other than text: {sorted(map(repr, value))[:3]}")
        if any(k in TAGS for k in value):
            return {PAIRS: [[k, _encode(v, arrays)] for k, v in value.items()]}
        return {k: _encode(v, arrays) for k, v in value.items()}
    if value is None or isinstance(value, (bool, int, float, str)):
        return value
    raise TypeError(f"{type(value).__name__} is not data a state file holds")


def _decode(value, arrays):
    if isinstance(value, list):
        return [_decode(v, arrays) for v in value]
    if not isinstance(value, dict):
        return value
    if len(value) == 1:
        (tag, inner), = value.items()
        if tag == ARRAY:
            return arrays(inner)
        if tag == SCALAR:
            return arrays(inner)[()]
        if tag == TUPLE:
            return tuple(_decode(v, arrays) for v in inner)
        if tag == PAIRS:
            return {k: _decode(v, arrays) for k, v in inner}
    return {k: _decode(v, arrays) for k, v in value.items()}


def _named(value) -> str:
    """A value from a file as a reply may name it: a number or a short text as it is, anything else
    by its type alone (a file's 1 MB "version" was quoted whole)."""
    if isinstance(value, (int, float)) or (isinstance(value, str) and len(value) <= 40):
        return repr(value)
    return f"a {type(value).__name__}" + (f" of {len(value):,} characters" if isinstance(value, str) else "")


def _regular(path: Path, what: str):
    """Refuse ``path`` unless it is a regular file (or, where it will be written, absent)."""
    try:
        mode = os.lstat(path).st_mode
    except FileNotFoundError:
        return
    if not stat.S_ISREG(mode):
        kind = ("a FIFO" if stat.S_ISFIFO(mode) else "a folder" if stat.S_ISDIR(mode)
                else "a symbolic link" if stat.S_ISLNK(mode) else "a device or socket")
        raise StateFileError(f"{path} is {kind}, not a regular file; a state is {what} a regular file only")


def write(path, kind: str, state: dict) -> Path:
    """Write ``state`` (dicts with text keys, lists, tuples, None, bool, int, float, text, numeric
    numpy arrays and scalars) to ``path`` as a state file of ``kind``, replacing it whole: written
    to a new file beside it first, so that a kill leaves the previous one."""
    path = Path(path).expanduser()
    _regular(path, "written over")
    arrays = []
    header = json.dumps({"format": FORMAT, "version": VERSION, "kind": kind, "state": _encode(state, arrays)})
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=path.name + ".", suffix=".tmp")
    try:
        with os.fdopen(fd, "wb") as f, zipfile.ZipFile(f, "w", zipfile.ZIP_STORED, allowZip64=True) as z:
            members = [(HEADER, np.frombuffer(header.encode(), dtype=np.uint8))]
            members += [(f"a{k}.npy", a) for k, a in enumerate(arrays)]
            for name, array in members:
                with z.open(name, "w", force_zip64=array.nbytes > (1 << 30)) as member:
                    np.lib.format.write_array(member, array, allow_pickle=False)
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise
    return path


def _open_regular(path: Path):
    """``path`` opened to read, without blocking, if it is a regular file (checked on what was opened)."""
    try:
        fd = os.open(path, os.O_RDONLY | os.O_NONBLOCK | os.O_CLOEXEC)
    except OSError as err:
        raise StateFileError(f"{path} cannot be opened: {err.strerror or err}") from None
    mode = os.fstat(fd).st_mode
    if not stat.S_ISREG(mode):
        os.close(fd)
        kind = "a FIFO" if stat.S_ISFIFO(mode) else "a folder" if stat.S_ISDIR(mode) else "a device or socket"
        raise StateFileError(f"{path} is {kind}, not a regular file; a state is read from a regular file only")
    return os.fdopen(fd, "rb")


def read(path, kind: str, keys=()) -> dict:
    """The state a ``write`` of ``kind`` put in ``path``, holding ``keys``; StateFileError saying why
    not (missing, not a regular file, cut short, a pickle of an earlier version, another kind)."""
    path = Path(path).expanduser()
    with _open_regular(path) as f:
        start = f.read(len(ZIP_MAGIC))
        if start[:1] == PICKLE_MAGIC:
            raise StateFileError(
                f"{path} is a state file of an earlier version (a Python pickle). This version never loads a "
                "pickle, since loading one can run any code it carries: start the run again, or finish it with "
                "the version that wrote it if the file is your own")
        if start != ZIP_MAGIC:
            raise StateFileError(f"{path} is not a gpusph_ros state file (it is no .npz)")
        f.seek(0)
        try:
            with zipfile.ZipFile(f) as z:
                state = _read_zip(z, kind)
        except StateFileError:
            raise
        except RecursionError:
            raise StateFileError(f"{path} cannot be read: its tree is nested deeper than a state is") from None
        except Exception as err:  # a cut or damaged file: zipfile's, numpy's and json's errors alike
            raise StateFileError(f"{path} cannot be read: it is cut short or damaged ({type(err).__name__}: "
                                 f"{err})") from None
    missing = [k for k in keys if not isinstance(state, dict) or k not in state]
    if missing:
        raise StateFileError(f"{path} cannot be read: it lacks {', '.join(missing)}")
    return state


def _member(z: zipfile.ZipFile, name: str) -> np.ndarray:
    info = z.getinfo(name)
    if info.compress_type != zipfile.ZIP_STORED:  # what it holds is then at most the file's own size
        raise StateFileError(f"member {name} is compressed; a state file stores its arrays as they are")
    array = np.lib.format.read_array(io.BytesIO(z.read(info)), allow_pickle=False)
    if array.dtype.hasobject:
        raise StateFileError(f"member {name} holds Python objects")
    return array


def _read_zip(z: zipfile.ZipFile, kind: str) -> dict:
    header = json.loads(_member(z, HEADER).tobytes().decode())
    if not isinstance(header, dict) or header.get("format") != FORMAT:
        raise StateFileError("it is an .npz but not a gpusph_ros state file")
    if header.get("version") != VERSION:
        raise StateFileError(f"it is of format version {_named(header.get('version'))}; this version reads {VERSION}")
    if header.get("kind") != kind:
        raise StateFileError(f"it is a {_named(header.get('kind'))}, not a {kind!r}")
    read_once = set()

    def array(k):
        if not isinstance(k, int) or isinstance(k, bool):
            raise StateFileError(f"an array reference {_named(k)} is not a number")
        if k in read_once:
            raise StateFileError(f"it names member a{k}.npy twice; a state file names each array once")
        read_once.add(k)
        return _member(z, f"a{k}.npy")

    return _decode(header["state"], array)
