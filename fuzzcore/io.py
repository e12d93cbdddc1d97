"""Loading and saving rule bases; the format follows the file extension.

Saving never leaves a half-written file: the text goes to a temporary file beside the
target, which then replaces it in one step (:func:`write_text_atomic`); if anything fails
first, the old file is untouched. :func:`check_save_path` lets a command check where it
will write before it starts a long piece of work.
"""
from __future__ import annotations

import os
import secrets
from pathlib import Path
from typing import Callable, Iterable

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
    write_text_atomic(path, text)


def write_text_atomic(path: str | Path, text: str) -> None:
    """Write ``text`` (UTF-8) to ``path`` whole or not at all.

    The text is written and flushed to disk in a new file beside ``path`` (same folder, so
    the rename stays on one file system), which then replaces ``path`` (``os.replace``).
    A failure at any point (disk full, interrupted) removes the temporary file and leaves
    an existing ``path`` as it was. A replaced file keeps its permission bits; a new one
    gets the usual ones (0666 less the umask).
    """
    path = Path(path)
    tmp = path.with_name(f".{path.name}.{secrets.token_hex(4)}.tmp")
    mode = os.stat(path).st_mode & 0o7777 if path.exists() else 0o666
    fd = os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_EXCL, mode)
    try:
        with os.fdopen(fd, "w", encoding="utf-8", newline="") as handle:
            handle.write(text)
            handle.flush()
            os.fsync(handle.fileno())
        if path.exists():
            os.chmod(tmp, mode)  # os.open applied the umask
        os.replace(tmp, path)
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise


def check_save_path(path: str | Path, sources: Iterable[str | Path] = (), overwrite: bool = False,
                    overwrite_hint: str = "overwrite=True") -> Path:
    """Check, before any work, that a rule base can be saved at ``path``; return it as a Path.

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
    folder = path.parent
    if not folder.is_dir():
        raise FileNotFoundError(f"{path}: the folder {str(folder)!r} does not exist; create it first")
    if path.is_dir():
        raise FileExistsError(f"{path} is a folder; expected a file name ending {path.suffix or '.yaml'}")
    if path.exists():
        for source in sources:
            if Path(source).exists() and os.path.samefile(path, source):
                raise ValueError(f"{path} is the same file as {source}, which is read: write to another file")
        if not overwrite:
            raise FileExistsError(f"{path} already exists; choose another name or allow replacing it "
                                  f"({overwrite_hint})")
    return path
