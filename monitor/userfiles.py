"""Files users give and files users own: arrays read without trusting their headers, and
outputs checked before the work and written whole or not at all.

Reading
-------
:func:`read_npy` reads a ``.npy`` array after checking what its header declares against
the file: the declared shape times the item size must be exactly the bytes that follow the
header, and the element count must not exceed a limit (:data:`MAX_PIXELS` by default), so
that a 192-byte file declaring (30000, 30000) is an error naming the file, not a 3.6 GB
allocation. :func:`check_png_size` reads a PNG's declared width and height from its header
(the IHDR chunk) and refuses images with more than :data:`MAX_PIXELS` pixels before a
decoder allocates them (a 777 kB PNG of 20000 x 20000 pixels would need 3 GB).

Writing
-------
:func:`check_output` checks, before a command starts its work, that a file can be written
where the user asked: the suffix is one the command writes, the folder exists, the path is
not one of the command's inputs (``os.path.samefile``: links are seen through) and an
existing file is replaced only when the user allowed it. :func:`write_atomic` writes a file
beside its target and renames it over the target (``os.replace``), so a failure at any
point leaves the old file as it was and never a half-written one.
"""
from __future__ import annotations

import os
import secrets
import struct
import tokenize
from pathlib import Path
from typing import BinaryIO, Callable, Iterable

import numpy as np

#: Largest element count :func:`read_npy` and :func:`check_png_size` accept by default:
#: 50 million pixels (an 8K frame is 33 million; 200 MB as float32).
MAX_PIXELS = 50_000_000

_PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"
_NPY_MAGIC = b"\x93NUMPY"
_ZIP_MAGIC = b"PK\x03\x04"


def read_npy(path: str | Path, what: str = "array file", max_elements: int = MAX_PIXELS) -> np.ndarray:
    """Read one array from a ``.npy`` file, checking its header against the file first.

    Parameters
    ----------
    path : str or Path
        The file.
    what : str
        What the file is, for messages (``"depth file"``, ``"prior file"``).
    max_elements : int
        Largest element count accepted (the product of the declared shape).

    Returns
    -------
    ndarray
        The array as stored (shape and dtype of the header); never an object array.

    Raises
    ------
    ValueError
        Naming the file: an empty or cut-short file, an archive (``.npz``), a header numpy
        cannot parse, an object (pickled) dtype, a declared shape whose data size differs
        from the bytes in the file, or more than ``max_elements`` elements.
    """
    path = Path(path)
    size = path.stat().st_size
    with open(path, "rb") as handle:
        start = handle.read(len(_NPY_MAGIC))
        if start.startswith(_ZIP_MAGIC):
            raise ValueError(f"{what} {path}: holds an archive (.npz), expected one .npy array")
        if start != _NPY_MAGIC:
            raise ValueError(f"{what} {path}: not a .npy file ({size} bytes; a .npy file starts "
                             "with \\x93NUMPY)")
        handle.seek(0)
        try:
            version = np.lib.format.read_magic(handle)
            if version == (1, 0):
                shape, fortran, dtype = np.lib.format.read_array_header_1_0(handle)
            elif version == (2, 0):
                shape, fortran, dtype = np.lib.format.read_array_header_2_0(handle)
            else:
                raise ValueError(f"format version {version[0]}.{version[1]}, expected 1.0 or 2.0")
        except (ValueError, EOFError, SyntaxError, TypeError, RecursionError, tokenize.TokenError) as exc:
            # numpy parses the header's text with ast.literal_eval (and tokenize)
            raise ValueError(f"{what} {path}: not a readable .npy header ({type(exc).__name__}: {exc})") from None
        if dtype.hasobject:
            raise ValueError(f"{what} {path}: dtype {dtype} holds Python objects (pickled data), "
                             "expected numbers")
        count = 1
        for n in shape:
            count *= n
        declared = count * dtype.itemsize
        present = size - handle.tell()
        if declared != present:
            problem = "cut short" if present < declared else "followed by extra bytes"
            raise ValueError(
                f"{what} {path}: the header declares shape {shape} of {dtype} ({declared} bytes of "
                f"data) but the file holds {present} bytes after the header: {problem}"
            )
        if count > max_elements:
            raise ValueError(f"{what} {path}: shape {shape} has {count} elements, more than the "
                             f"limit of {max_elements}")
        data = np.fromfile(handle, dtype=dtype, count=count) if count else np.empty(0, dtype=dtype)
    return data.reshape(shape, order="F" if fortran else "C")


def check_png_size(path: str | Path, what: str = "image file", max_pixels: int = MAX_PIXELS) -> tuple[int, int]:
    """The declared ``(height, width)`` of a PNG, read from its header without decoding it.

    Raises
    ------
    ValueError
        Naming the file: not a PNG (signature or IHDR chunk missing), a zero size, or more
        than ``max_pixels`` pixels.
    """
    path = Path(path)
    with open(path, "rb") as handle:
        header = handle.read(24)
    if len(header) < 24 or not header.startswith(_PNG_SIGNATURE) or header[12:16] != b"IHDR":
        raise ValueError(f"{what} {path}: not a PNG image (no PNG signature and IHDR header)")
    width, height = struct.unpack(">II", header[16:24])
    if width == 0 or height == 0:
        raise ValueError(f"{what} {path}: the header declares {width} x {height} pixels")
    if width * height > max_pixels:
        raise ValueError(f"{what} {path}: the header declares {width} x {height} = {width * height} "
                         f"pixels, more than the limit of {max_pixels}")
    return height, width


def check_output(path: str | Path, suffixes: tuple[str, ...], inputs: Iterable[str | Path] = (),
                 overwrite: bool = False, option: str = "--overwrite", what: str = "output") -> Path:
    """Check, before any work, that a file can be written at ``path``; return it as a Path.

    Parameters
    ----------
    path : str or Path
        Where the file will be written.
    suffixes : tuple of str
        The suffixes the writer produces (lower case, with the dot), e.g. ``(".npy",)``.
    inputs : iterable of str or Path
        Files and folders the work reads: ``path`` must be none of them, under any name,
        and must not lie inside an input folder.
    overwrite : bool
        Whether an existing file at ``path`` may be replaced.
    option : str
        How the user allows replacing, for the message.
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
    if path.suffix.lower() not in suffixes:
        raise ValueError(f"{what} {path}: suffix {path.suffix!r}, expected {' or '.join(suffixes)}")
    if not path.parent.is_dir():
        raise FileNotFoundError(f"{what} {path}: the folder {str(path.parent)!r} does not exist; "
                                "create it first")
    if path.is_dir():
        raise FileExistsError(f"{what} {path} is a folder, expected a file name")
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
    A replaced file keeps its permission bits.
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
    """Write UTF-8 text atomically (:func:`write_atomic`)."""
    write_atomic(path, lambda handle: handle.write(text.encode("utf-8")))


def write_npy(path: str | Path, array: np.ndarray) -> None:
    """Write one array as ``.npy`` atomically (:func:`write_atomic`); no pickling."""
    write_atomic(path, lambda handle: np.save(handle, array, allow_pickle=False))


def save_figure(fig, path: str | Path, dpi: int) -> None:
    """Save a Matplotlib figure atomically (:func:`write_atomic`); the format follows the
    suffix of ``path``."""
    path = Path(path)
    write_atomic(path, lambda handle: fig.savefig(handle, format=path.suffix.lstrip(".").lower() or "png", dpi=dpi))
