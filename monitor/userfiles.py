"""Files users give and files users own: arrays read without trusting their headers,
arrays and figures written whole or not at all.

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
:func:`write_npy` and :func:`save_figure` write arrays and figures whole or not at all
(:func:`fuzzcore.outputs.write_atomic`); outputs are checked before the work with
:func:`fuzzcore.outputs.check_output` and written as text with
:func:`fuzzcore.outputs.write_text`.
"""
from __future__ import annotations

import struct
import tokenize
from pathlib import Path

import numpy as np

from fuzzcore.outputs import write_atomic

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


def write_npy(path: str | Path, array: np.ndarray) -> None:
    """Write one array as ``.npy`` whole or not at all (:func:`fuzzcore.outputs.write_atomic`);
    no pickling."""
    write_atomic(path, lambda handle: np.save(handle, array, allow_pickle=False))


def save_figure(fig, path: str | Path, dpi: int) -> None:
    """Save a Matplotlib figure whole or not at all (:func:`fuzzcore.outputs.write_atomic`);
    the format follows the suffix of ``path``."""
    path = Path(path)
    write_atomic(path, lambda handle: fig.savefig(handle, format=path.suffix.lstrip(".").lower() or "png", dpi=dpi))
