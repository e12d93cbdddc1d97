"""Loading and saving rule bases; the format follows the file extension.

Saving never leaves a half-written file: the text goes to a temporary file beside the
target, which then replaces it in one step (:func:`fuzzcore.outputs.write_text`); if
anything fails first, the old file is untouched. :func:`check_save_path` lets a command
check where it will write before it starts a long piece of work.
"""
from __future__ import annotations

from pathlib import Path
from typing import Callable, Iterable

from . import fis_format, yaml_format
from .errors import RuleBaseError
from .outputs import check_output, write_text
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
    write_text(path, text)


def check_save_path(path: str | Path, sources: Iterable[str | Path] = (), overwrite: bool = False,
                    overwrite_hint: str = "overwrite=True") -> Path:
    """Check, before any work, that a rule base can be saved at ``path``; return it as a Path.

    The extension must name a format of :data:`WRITERS`; the rest is
    :func:`fuzzcore.outputs.check_output`.

    Parameters
    ----------
    path : str or Path
        Where the rule base will be written.
    sources : iterable of str or Path
        Files the work reads (the starting rule base, data): ``path`` must not be one of
        them, under any name (``os.path.samefile``: links and ``..`` are seen through).
    overwrite : bool
        Whether an existing file at ``path`` may be replaced.
    overwrite_hint : str
        How the caller allows overwriting, for the message (e.g. ``--overwrite``).

    Raises
    ------
    ValueError
        Unknown extension, or ``path`` is one of ``sources``.
    FileNotFoundError
        The folder of ``path`` does not exist.
    FileExistsError
        ``path`` exists (and is not a folder) and ``overwrite`` is False; or it is a folder.
    """
    path = Path(path)
    _format(path, WRITERS)
    return check_output(path, WRITERS, sources, overwrite, option=overwrite_hint, what="rule base")
