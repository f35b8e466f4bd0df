"""Where a recording may go: checked before a run is built, so a bad path costs nothing. Standard
library only, so the node checks ``record_dir`` without loading the MCAP writer."""
import os
from pathlib import Path

# where no recording goes, whatever the permissions (a node may run as root): the file system's root
# itself and the operating system's folders; checked on the path with links and '..' resolved
SYSTEM_FOLDERS = ("/bin", "/boot", "/dev", "/etc", "/lib", "/lib32", "/lib64", "/libx32", "/proc", "/run", "/sbin",
                  "/sys", "/usr", "/var/lib", "/var/log", "/var/spool", "/var/cache")


def _system_folder(target: Path):
    """The operating-system folder ``target`` is or lies in ("/" for the root itself), or None."""
    real = Path(os.path.realpath(target))
    if real == Path(real.anchor):
        return "/"
    for folder in SYSTEM_FOLDERS:
        if real == Path(folder) or Path(folder) in real.parents:
            return folder
    return None


def folder_problem(path, empty: bool = False):
    """Why a recording cannot be written under ``path`` (a folder, created if missing; with
    ``empty`` it must be empty or new), or None. Checked before a run is built, so a bad path
    costs nothing."""
    if not str(path).strip():
        return "an empty path is no folder; name one"
    target = Path(path).expanduser()
    system = _system_folder(target)
    if system:
        return f"{target} lies in {system}, a folder of the operating system; recordings go elsewhere"
    if target.exists() and not target.is_dir():
        return f"{target} is a file, not a folder"
    if empty and target.is_dir() and any(target.iterdir()):
        return f"{target} exists and is not empty; choose a new folder"
    existing = next(q for q in [target, *target.parents] if q.exists())
    if not existing.is_dir():
        return f"{target} lies under {existing}, which is a file"
    if not os.access(existing, os.W_OK | os.X_OK):
        return f"{existing} is not writable"
    return None
