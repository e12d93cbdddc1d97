"""Validation of real-valued arrays shared by the geometry modules."""
from __future__ import annotations

import numpy as np


def finite_array(a, name: str, shape_text: str, ndim: int | None = None,
                 last: int | None = None) -> np.ndarray:
    """``a`` as a C-ordered float64 array, or a ValueError naming ``name``.

    Parameters
    ----------
    a : array_like
        Real numbers (integers are converted); strings, booleans, complex, object and
        masked arrays (whose mask would be ignored) are refused.
    name : str
        The argument's name, for messages.
    shape_text : str
        The expected shape in words, for messages (``"(n, 3) metres"``).
    ndim : int, optional
        Required number of dimensions.
    last : int, optional
        Required length of the last axis.
    """
    if isinstance(a, np.ma.MaskedArray):
        raise ValueError(f"{name} is a masked array; its mask would be ignored: give a plain "
                         f"array of {shape_text}")
    try:
        arr = np.asarray(a)
    except (ValueError, TypeError) as exc:  # ragged nested lists
        raise ValueError(f"{name} is not an array of numbers ({exc}); expected {shape_text}") from None
    if arr.dtype.kind not in "iuf":
        raise ValueError(f"{name} has dtype {arr.dtype}, expected real numbers")
    arr = np.asarray(arr, dtype=np.float64, order="C")
    if (ndim is not None and arr.ndim != ndim) or (last is not None and (
            arr.ndim == 0 or arr.shape[-1] != last)):
        raise ValueError(f"{name} has shape {arr.shape}, expected {shape_text}")
    if not np.isfinite(arr).all():
        where = tuple(int(x) for x in np.argwhere(~np.isfinite(arr))[0])
        raise ValueError(f"{name}{list(where) if where else ''} = {float(arr[where])!r}: "
                         f"must be finite")
    return arr
