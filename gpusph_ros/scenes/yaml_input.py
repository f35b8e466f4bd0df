"""YAML as the package reads it from users: scene, run-configuration and study files, ``--set``
values. A file or a value comes from anyone (a node parameter names a path), so reading one is
bounded: at most MAX_BYTES, UTF-8 text, at most MAX_DEPTH nested levels, no anchors or aliases
(a few hundred bytes of aliases expand to gigabytes), and every failure is a ``ConfigError`` naming
the field and the file, never quoting the file's contents.

Numbers are read as YAML 1.2 reads them: ``1e-6`` is a float (YAML 1.1, PyYAML's default, reads
it as the string '1e-6' because it lacks a dot).
"""
import re
from pathlib import Path

import yaml

from ..sph.config import ConfigError

MAX_BYTES = 1 << 20  # a scene is a few kB; a 50 MB file of probes is no scene
MAX_DEPTH = 32  # a scene nests 4 levels


class _Refused(yaml.YAMLError):
    pass


class _Loader(yaml.SafeLoader):
    """SafeLoader without anchors, aliases or deep nesting, with YAML 1.2 floats."""

    def compose_node(self, parent, index):
        event = self.peek_event()
        if isinstance(event, yaml.AliasEvent) or getattr(event, "anchor", None) is not None:
            raise _Refused(f"anchors and aliases (&, *) are not allowed (line {event.start_mark.line + 1})")
        self._depth = getattr(self, "_depth", 0) + 1
        try:
            if self._depth > MAX_DEPTH:
                raise _Refused(f"more than {MAX_DEPTH} nested levels (line {event.start_mark.line + 1})")
            return super().compose_node(parent, index)
        finally:
            self._depth -= 1


_Loader.add_implicit_resolver(
    "tag:yaml.org,2002:float",
    re.compile(r"""^(?:[-+]?(?:[0-9][0-9_]*)\.[0-9_]*(?:[eE][-+]?[0-9]+)?
                  |[-+]?(?:[0-9][0-9_]*)(?:[eE][-+]?[0-9]+)
                  |\.[0-9_]+(?:[eE][-+]?[0-9]+)?
                  |[-+]?\.(?:inf|Inf|INF)
                  |\.(?:nan|NaN|NAN))$""", re.X),
    list("-+0123456789."))


def _reason(err: yaml.YAMLError) -> str:
    """What is wrong and where, without the snippet of the file PyYAML quotes."""
    if isinstance(err, _Refused):
        return str(err)
    problem = getattr(err, "problem", None) or "not YAML"
    mark = getattr(err, "problem_mark", None)
    return problem + (f" at line {mark.line + 1}, column {mark.column + 1}" if mark is not None else "")


def parse(text: str, field_name: str, where: str):
    """The YAML ``text`` as plain data; ConfigError on ``field_name`` saying what is wrong at ``where``."""
    try:
        return yaml.load(text, Loader=_Loader)  # _Loader is a SafeLoader
    except yaml.YAMLError as err:
        raise ConfigError(field_name, where, f"valid YAML ({_reason(err)})") from None
    except RecursionError:
        raise ConfigError(field_name, where, f"valid YAML (nested too deep; at most {MAX_DEPTH} levels)") from None


def read_text(path: Path, field_name: str, limit: int = MAX_BYTES) -> str:
    """The text of the file at ``path``, at most ``limit`` bytes of UTF-8."""
    try:
        size = path.stat().st_size
        if size > limit:
            raise ConfigError(field_name, str(path), f"a file of at most {limit // 1024} KiB ({size:,} bytes)")
        data = path.read_bytes()
    except OSError as err:
        raise ConfigError(field_name, str(path), f"a readable file ({err.strerror})") from None
    if b"\0" in data:
        raise ConfigError(field_name, str(path), "a text file (this one is binary)")
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError as err:
        raise ConfigError(field_name, str(path), f"a UTF-8 text file (byte {err.start} is not UTF-8)") from None


def value(text: str):
    """A ``--set`` value read as YAML (``1e-6`` a number, ``true`` a boolean); the text itself when
    it is no YAML scalar a setting could take."""
    try:
        return yaml.load(text, Loader=_Loader)  # _Loader is a SafeLoader
    except (yaml.YAMLError, RecursionError):
        return text
