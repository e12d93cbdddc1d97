"""Loading and saving rule bases; the format follows the file extension."""
from __future__ import annotations

from pathlib import Path
from typing import Callable

from . import fis_format, yaml_format
from .system import FuzzySystem

#: extension -> reader(path) -> FuzzySystem
READERS: dict[str, Callable[[Path], FuzzySystem]] = {
    ".yaml": yaml_format.read, ".yml": yaml_format.read, ".fis": fis_format.read,
}
#: extension -> writer(system, path)
WRITERS: dict[str, Callable[[FuzzySystem, Path], None]] = {
    ".yaml": yaml_format.write, ".yml": yaml_format.write, ".fis": fis_format.write,
}


def _format(path: Path, table: dict) -> Callable:
    try:
        return table[path.suffix.lower()]
    except KeyError:
        raise ValueError(f"{path}: unknown rule base format {path.suffix!r}; "
                         f"expected one of {', '.join(sorted(table))}") from None


def load(path: str | Path) -> FuzzySystem:
    """Read a rule base: YAML (``.yaml``/``.yml``) or MATLAB (``.fis``), by extension."""
    path = Path(path)
    reader = _format(path, READERS)
    if not path.is_file():
        raise FileNotFoundError(f"{path}: no such rule base file")
    return reader(path)


def save(system: FuzzySystem, path: str | Path) -> None:
    """Write ``system`` to ``path`` in the format its extension names."""
    path = Path(path)
    _format(path, WRITERS)(system, path)
