"""Where the package's config/ folder is: the source tree in a checkout or an editable install,
<prefix>/share/gpusph_ros/config once installed by pip or colcon (setup.py's data_files)."""
import sys
from pathlib import Path

_HERE = Path(__file__).resolve().parent


def config_dir(sub: str = "") -> Path:
    """The first of the checkout's and the install prefixes' config/ folders that holds ``sub``."""
    candidates = [_HERE.parent / "config", Path(sys.prefix) / "share" / "gpusph_ros" / "config"]
    if len(_HERE.parents) > 3:  # installed: <prefix>/lib/pythonX.Y/site-packages/gpusph_ros
        candidates.insert(1, _HERE.parents[3] / "share" / "gpusph_ros" / "config")
    for base in candidates:
        if (base / sub).is_dir():
            return base / sub
    raise FileNotFoundError(f"config/{sub} not found in " + ", ".join(str(c) for c in candidates))
