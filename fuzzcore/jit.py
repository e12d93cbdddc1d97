"""The one Numba configuration of every kernel in fuzzcore and monitor.

Every private ``_kernels.py`` module compiles its functions with :func:`kernel`, so the
options below hold everywhere and are changed in one place:

- ``cache=True``: compiled kernels are cached beside the sources, so a new process loads
  them instead of compiling (Numba does not notice when a kernel that another module's
  kernel calls has changed: after editing one, delete the ``*.nbi``/``*.nbc`` files).
- ``nogil=True``: a kernel releases the GIL, so callers may run kernels on several threads
  (the tuners do).
- ``error_model="numpy"``: a float division by zero gives IEEE's inf or NaN, as NumPy's and
  MATLAB's do, instead of a test on every division that would raise (kernels never raise)
  and keep LLVM from vectorising the loop.
- No fastmath by default: plain IEEE arithmetic in the order the source writes it, so NaN
  and inf keep their meaning (a NaN input gives a NaN result, never a confident number), a
  result does not depend on how the compiler reorders a sum, and cached and freshly compiled
  kernels give the same bits. ``nnan`` and ``ninf`` (and ``fastmath=True``, which includes
  them) are never allowed.

A kernel that needs fastmath flags names one of the sets declared here, each with its
reason; :func:`kernel` refuses any other set.

>>> from fuzzcore.jit import kernel
>>> @kernel
... def twice(x):
...     return 2.0 * x
"""
from __future__ import annotations

from numba import njit

#: the options every kernel is compiled with (see the module docstring)
OPTIONS = {"cache": True, "nogil": True, "error_model": "numpy"}

#: fastmath flags of the synthetic scene renderer and depth degrader
#: (:mod:`monitor.synthetic`), which draw a stand-in picture of a street, not a measurement:
#: with them the ray cast of benchmarks/bench_raycast.py's 1600x900 frame takes 3.6 ms,
#: without them 5.6 ms (the same depth bits on that frame). Reassociation, contraction to
#: fused multiply-add, approximate functions and reciprocals, no signed zeros: none of them
#: changes what NaN or inf mean (the renderer's sky is an infinite depth).
SYNTHETIC_IMAGE = frozenset({"nsz", "arcp", "contract", "afn", "reassoc"})

#: every fastmath set a kernel may use
FASTMATH_SETS = (SYNTHETIC_IMAGE,)


def kernel(function=None, *, inline: bool = False, parallel: bool = False,
           fastmath: frozenset = frozenset()):
    """Compile ``function`` as a kernel with the project's Numba options.

    Used bare (``@kernel``) or with arguments (``@kernel(inline=True)``).

    Parameters
    ----------
    function : callable, optional
        The function to compile; omitted when the decorator is called with arguments.
    inline : bool
        Inline the kernel into the kernels that call it (Numba's ``inline="always"``), for
        small helpers that run once per element.
    parallel : bool
        Compile with Numba's ``parallel=True`` (``prange`` loops run on its threads).
    fastmath : frozenset of str
        Empty (the default), or one of the sets declared in this module
        (:data:`FASTMATH_SETS`).

    Returns
    -------
    numba dispatcher, or a decorator when ``function`` is None.

    Raises
    ------
    ValueError
        If ``fastmath`` is not one of the declared sets.
    """
    if fastmath and fastmath not in FASTMATH_SETS:
        raise ValueError(f"fastmath={sorted(fastmath)} is not declared in fuzzcore.jit; "
                         f"declare the set there with its reason (declared: "
                         f"{[sorted(s) for s in FASTMATH_SETS]})")
    options = dict(OPTIONS, parallel=parallel, fastmath=set(fastmath) or False)
    if inline:
        options["inline"] = "always"
    decorate = njit(**options)
    return decorate if function is None else decorate(function)
