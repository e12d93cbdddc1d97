"""Files users own: outputs checked before the work, and written whole or not at all.

:func:`check_output` checks, before a command starts its work, that a file can be written
where the user asked: the suffix is one the command writes, the folder exists, the path is
not one of the command's inputs (``os.path.samefile``: links and ``..`` are seen through)
and an existing file is replaced only when the user allowed it. :func:`check_output_folder`
does the same for a folder of outputs.

:func:`write_atomic` writes a file beside its target (same folder, so the rename stays on
one file system) and renames it over the target (``os.replace``), so a failure at any
point (disk full, interrupted) leaves the old file as it was and never a half-written one.
Every writer of the project goes through it: rule bases (:func:`fuzzcore.save`), reports,
arrays and figures (:mod:`monitor.userfiles`).
"""
from __future__ import annotations

import os
import secrets
from pathlib import Path
from typing import BinaryIO, Callable, Iterable


def check_output(path: str | Path, suffixes: Iterable[str], inputs: Iterable[str | Path] = (),
                 overwrite: bool = False, option: str = "--overwrite", what: str = "output") -> Path:
    """Check, before any work, that a file can be written at ``path``; return it as a Path.

    Parameters
    ----------
    path : str or Path
        Where the file will be written.
    suffixes : iterable of str
        The suffixes the writer produces (lower case, with the dot), e.g. ``(".npy",)``.
    inputs : iterable of str or Path
        Files and folders the work reads: ``path`` must be none of them, under any name,
        and must not lie inside an input folder.
    overwrite : bool
        Whether an existing file at ``path`` may be replaced.
    option : str
        How the user allows replacing, for the message (``--overwrite``, ``overwrite=True``).
    what : str
        What the file is, for messages.

    Raises
    ------
    ValueError
        A suffix not in ``suffixes``, or ``path`` is (or lies in) one of ``inputs``.
    FileNotFoundError
        The folder of ``path`` does not exist.
    FileExistsError
        ``path`` is a folder, or exists and ``overwrite`` is False.
    """
    path = Path(path)
    suffixes = tuple(suffixes)
    if path.suffix.lower() not in suffixes:
        raise ValueError(f"{what} {path}: suffix {path.suffix!r}, expected {' or '.join(suffixes)}")
    if not path.parent.is_dir():
        raise FileNotFoundError(f"{what} {path}: the folder {str(path.parent)!r} does not exist; "
                                "create it first")
    if path.is_dir():
        raise FileExistsError(f"{what} {path} is a folder, expected a file name ending "
                              f"{' or '.join(suffixes)}")
    for source in inputs:
        source = Path(source)
        if source.is_dir() and path.parent.resolve() == source.resolve():
            raise ValueError(f"{what} {path} lies in {source}, which is read: write it elsewhere")
        if path.exists() and source.exists() and os.path.samefile(path, source):
            raise ValueError(f"{what} {path} is the same file as {source}, which is read: "
                             "write to another file")
    if path.exists() and not overwrite:
        raise FileExistsError(f"{what} {path} already exists; choose another name or allow "
                              f"replacing it ({option})")
    return path


def check_output_folder(folder: str | Path, names: Iterable[str], overwrite: bool = False,
                        option: str = "--overwrite") -> Path:
    """Check, before any work, that a command can write the files ``names`` in ``folder``.

    The folder is created if missing (its parent must exist). A file of ``names`` that
    already exists is replaced only with ``overwrite``.

    Raises
    ------
    FileNotFoundError
        The parent of ``folder`` does not exist.
    FileExistsError
        ``folder`` is a file, or one of the files exists and ``overwrite`` is False.
    """
    folder = Path(folder)
    if folder.exists() and not folder.is_dir():
        raise FileExistsError(f"output folder {folder} is a file, expected a folder")
    if not folder.exists() and not folder.parent.is_dir():
        raise FileNotFoundError(f"output folder {folder}: its parent {str(folder.parent)!r} does not "
                                "exist; create it first")
    existing = sorted(name for name in names if (folder / name).exists())
    if existing and not overwrite:
        raise FileExistsError(f"output folder {folder} already holds {', '.join(existing)}; choose "
                              f"another folder or allow replacing them ({option})")
    folder.mkdir(exist_ok=True)
    return folder


def write_atomic(path: str | Path, write: Callable[[BinaryIO], object]) -> None:
    """Write a file whole or not at all: ``write(handle)`` fills a temporary file beside
    ``path`` (binary, flushed to disk), which then replaces ``path`` (``os.replace``).

    On any failure the temporary file is removed and an existing ``path`` is unchanged.
    A replaced file keeps its permission bits; a new one gets the usual ones (0666 less
    the umask).
    """
    path = Path(path)
    tmp = path.with_name(f".{path.name}.{secrets.token_hex(4)}.tmp")
    mode = os.stat(path).st_mode & 0o7777 if path.exists() else None
    try:
        with open(tmp, "xb") as handle:
            write(handle)
            handle.flush()
            os.fsync(handle.fileno())
        if mode is not None:
            os.chmod(tmp, mode)
        os.replace(tmp, path)
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise


def write_text(path: str | Path, text: str) -> None:
    """Write ``text`` as UTF-8, newlines as given, whole or not at all (:func:`write_atomic`)."""
    write_atomic(path, lambda handle: handle.write(text.encode("utf-8")))
