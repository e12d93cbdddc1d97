"""Loading and saving rule bases; the format follows the file extension."""
from __future__ import annotations

from pathlib import Path
from typing import Callable

from . import fis_format, yaml_format
from .errors import RuleBaseError
from .system import FuzzySystem

#: extension -> reader(path) -> FuzzySystem
READERS: dict[str, Callable[[Path], FuzzySystem]] = {
    ".yaml": yaml_format.read, ".yml": yaml_format.read, ".fis": fis_format.read,
}
#: extension -> dumps(system) -> the file's text
WRITERS: dict[str, Callable[[FuzzySystem], str]] = {
    ".yaml": yaml_format.dumps, ".yml": yaml_format.dumps, ".fis": fis_format.dumps,
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
    """Write ``system`` to ``path`` (UTF-8) in the format its extension names.

    A system the format cannot hold raises :class:`RuleBaseError` naming the file.
    """
    path = Path(path)
    dumps = _format(path, WRITERS)
    try:
        text = dumps(system)
    except RuleBaseError as exc:
        raise RuleBaseError(exc.detail, source=str(path), place=exc.place) from None
    path.write_text(text, encoding="utf-8")
