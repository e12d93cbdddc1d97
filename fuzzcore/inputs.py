"""What may enter the engine as a number: real numbers, one check for every entry point.

:func:`real_array` is the gate of :meth:`FuzzySystem.infer`, ``evaluate`` and ``explain`` and
of the tuners' data. It refuses what NumPy would quietly turn into a plausible float64:
``None`` (NaN), text (``'0.4'`` parses), ``bool`` (1.0), complex numbers (the imaginary part
dropped), ``datetime64``/``timedelta64`` (nanosecond counts), masked arrays (the mask
ignored) and object arrays; and an integer or long double too large for a float64 (which
would become inf). A NaN or infinite float is a real number and passes: the engine has
documented answers for both.

:data:`REAL_SCALARS` are the exact scalar types that convert with ``float()`` and need no
further check, so the scalar path can test ``type(x) in REAL_SCALARS`` and nothing else.
"""
from __future__ import annotations

from typing import Any

import numpy as np

#: scalar types (exact, not subclasses) that are real numbers ``float()`` converts without loss
#: of meaning; Python ``int`` may still overflow (``float(10**400)`` raises OverflowError)
REAL_SCALARS = frozenset({
    float, int, np.float64, np.float32, np.float16,
    np.int8, np.int16, np.int32, np.int64, np.uint8, np.uint16, np.uint32, np.uint64,
})


def _shown(value: Any) -> str:
    text = repr(value)
    return text if len(text) <= 60 else f"{text[:40]}...{text[-12:]} ({len(text)} characters)"


def real_array(value: Any, what: str) -> np.ndarray:
    """``value`` as a float64 ndarray (0-d for a scalar), if it holds real numbers only.

    Parameters
    ----------
    value : real number or array_like of real numbers
    what : str
        Names the value in messages, e.g. ``"input 'iou'"``.

    Raises
    ------
    TypeError
        ``value`` is None, text, bool, complex, a date or time span, a masked array, or an
        array whose elements are not all real numbers.
    ValueError
        A number too large for a float64 (an integer beyond 1.8e308, a long double that
        would become inf).

    An object array (a list mixing floats and integers beyond int64 makes one) is accepted
    when every element is of a type in :data:`REAL_SCALARS`.
    """
    if value is None:
        raise TypeError(f"{what} is None; expected a real number or an array of real numbers")
    if isinstance(value, (str, bytes)):
        raise TypeError(f"{what} is text ({_shown(value)}); expected a real number (convert text with float() "
                        "where you read it, so that a bad value fails there)")
    if isinstance(value, np.ma.MaskedArray):
        raise TypeError(f"{what} is a masked array ({np.ma.count_masked(value)} of {value.size} values masked); "
                        "the engine would ignore the mask: pass value.filled(np.nan) to have masked values "
                        "give NaN, or drop them")
    if isinstance(value, int) and not isinstance(value, bool):
        try:
            float(value)
        except OverflowError:
            raise ValueError(f"{what} = {_shown(value)} is too large for a float64 (|x| < 1.8e308)") from None
    try:
        array = np.asarray(value)
    except (TypeError, ValueError) as exc:
        raise TypeError(f"{what} ({_shown(value)}) is not a number or an array of numbers: {exc}") from None
    kind = array.dtype.kind
    if kind in "fiu":
        if kind == "f" and array.dtype.itemsize > 8:
            with np.errstate(over="ignore"):
                converted = array.astype(np.float64)
            overflow = np.isinf(converted) & np.isfinite(array)
            if overflow.any():
                raise ValueError(f"{what} holds {array[overflow].ravel()[0]!r}, too large for a float64 "
                                 "(|x| < 1.8e308)")
            return converted
        return array.astype(np.float64, copy=False)
    if kind == "O":  # e.g. a list mixing floats and Python ints beyond int64: real if every element is
        flat = array.ravel()
        for k, element in enumerate(flat):
            if type(element) not in REAL_SCALARS:
                raise TypeError(f"{what} holds {_shown(element)} (element {k} of the flattened array, a "
                                f"{type(element).__name__}); expected real numbers")
        converted = np.empty(flat.shape[0])
        for k, element in enumerate(flat):
            try:
                converted[k] = float(element)
            except OverflowError:
                raise ValueError(f"{what} holds {_shown(element)} (element {k} of the flattened array), too large "
                                 "for a float64 (|x| < 1.8e308)") from None
        return converted.reshape(array.shape)
    what_it_is = {
        "b": "boolean", "c": "complex (the imaginary part would be dropped)",
        "M": "a date (datetime64)", "m": "a time span (timedelta64)",
        "U": "text", "S": "bytes",
    }.get(kind, f"of dtype {array.dtype}")
    raise TypeError(f"{what} is {what_it_is}: {_shown(value)}; expected real numbers")
