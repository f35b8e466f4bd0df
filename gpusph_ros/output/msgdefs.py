"""Message definitions as ``ros2 bag record -s mcap`` stores them, read from the installed
message packages: the ``ros2msg`` full text (the type's .msg, then each type it uses, depth
first, after a line of 80 '=' and ``MSG: pkg/msg/Type``; rosbag2 docs/message_definition_encoding.md)
and the RIHS01 type hash that rosidl generated beside it (``<share>/<pkg>/msg/<Type>.json``).
"""
import functools
import importlib
import json
import re
from pathlib import Path

PRIMITIVES = {"bool", "byte", "char", "float32", "float64", "int8", "uint8", "int16", "uint16", "int32", "uint32",
              "int64", "uint64", "string", "wstring"}
SEPARATOR = "=" * 80


def share_dir(package: str) -> Path:
    """<prefix>/share/<package>: from the ament index when AMENT_PREFIX_PATH is set (a sourced
    ROS 2), else beside the package's Python module (<prefix>/lib/pythonX.Y/site-packages/<package>,
    the layout of both /opt/ros and this project's venv)."""
    try:
        from ament_index_python.packages import get_package_share_directory
        return Path(get_package_share_directory(package))
    except Exception:  # no ament index: fall back to the module's prefix
        module = importlib.import_module(package)
        return Path(module.__file__).resolve().parents[4] / "share" / package


def _split(type_name: str):
    package, _, name = type_name.partition("/msg/")
    if not name:
        raise ValueError(f"message type {type_name!r} is not of the form pkg/msg/Type")
    return package, name


def _msg_text(type_name: str) -> str:
    package, name = _split(type_name)
    return (share_dir(package) / "msg" / f"{name}.msg").read_text()


def _dependencies(text: str, package: str) -> list:
    """Message types a .msg text uses, in order of first use, as pkg/msg/Type."""
    found = []
    for line in text.splitlines():
        line = line.split("#", 1)[0].strip()
        if not line:
            continue
        parts = line.split()
        if len(parts) < 2 or "=" in parts[1]:  # constants are primitive
            continue
        base = re.sub(r"(\[.*\]|<=\d+)$", "", parts[0])
        base = re.sub(r"<=\d+$", "", base)
        if base in PRIMITIVES:
            continue
        if "/" in base:
            pkg, _, typ = base.rpartition("/")
            pkg = pkg.split("/")[0]
        else:
            pkg, typ = package, base
        full = f"{pkg}/msg/{typ}"
        if full not in found:
            found.append(full)
    return found


@functools.lru_cache(maxsize=None)
def full_text(type_name: str) -> str:
    """The ros2msg schema text of ``type_name`` (e.g. ``sensor_msgs/msg/PointCloud2``)."""
    text = _msg_text(type_name)
    order, stack = [], list(reversed(_dependencies(text, _split(type_name)[0])))
    while stack:
        dep = stack.pop()
        if dep in order:
            continue
        order.append(dep)
        stack.extend(reversed([d for d in _dependencies(_msg_text(dep), _split(dep)[0]) if d not in order]))
    parts = [text.rstrip("\n")]
    for dep in order:
        parts.append(f"{SEPARATOR}\nMSG: {dep}\n{_msg_text(dep).rstrip(chr(10))}")
    return "\n".join(parts) + "\n"


@functools.lru_cache(maxsize=None)
def type_hash(type_name: str) -> str:
    """The RIHS01 hash rosidl generated for ``type_name``."""
    package, name = _split(type_name)
    data = json.loads((share_dir(package) / "msg" / f"{name}.json").read_text())
    for entry in data["type_hashes"]:
        if entry["type_name"] == type_name:
            return entry["hash_string"]
    raise KeyError(f"no type hash for {type_name} in {package}'s {name}.json")


def type_name_of(message_class) -> str:
    """pkg/msg/Type of a generated message class."""
    return f"{message_class.__module__.split('.')[0]}/msg/{message_class.__name__}"
