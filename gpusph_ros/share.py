"""Where the package's installed folders are: config/ (scenes, runs, studies, node parameters) and
data/ (the reference tables and experimental series the analysis compares against). In a checkout or
an editable install they are the source tree's; once installed by pip or colcon (setup.py's
data_files), <prefix>/share/gpusph_ros/<folder>."""
import sys
from pathlib import Path

_HERE = Path(__file__).resolve().parent


def _candidates(folder: str) -> list:
    candidates = [_HERE.parent / folder, Path(sys.prefix) / "share" / "gpusph_ros" / folder]
    if len(_HERE.parents) > 3:  # installed: <prefix>/lib/pythonX.Y/site-packages/gpusph_ros
        candidates.insert(1, _HERE.parents[3] / "share" / "gpusph_ros" / folder)
    return candidates


def _find(folder: str, sub: str) -> Path:
    candidates = _candidates(folder)
    for base in candidates:
        if (base / sub).is_dir():
            return base / sub
    raise FileNotFoundError(f"{folder}/{sub} not found in " + ", ".join(str(c) for c in candidates))


def config_dir(sub: str = "") -> Path:
    """The first of the checkout's and the install prefixes' config/ folders that holds ``sub``."""
    return _find("config", sub)


def data_dir(sub: str = "") -> Path:
    """The first of the checkout's and the install prefixes' data/ folders that holds ``sub``."""
    return _find("data", sub)
