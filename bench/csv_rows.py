"""A benchmark's result rows: each appended to its CSV as its run ends (the header with the first),
so that a long sweep keeps what it has finished and can be resumed."""
import csv
from pathlib import Path


def append(path: Path, row: dict, fields: list | None = None) -> None:
    """Append ``row`` to the CSV at ``path`` (its columns ``fields``, else the row's keys)."""
    path = Path(path)
    new = not path.exists()
    path.parent.mkdir(parents=True, exist_ok=True)
    with open(path, "a", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=fields or list(row))
        if new:
            writer.writeheader()
        writer.writerow(row)
