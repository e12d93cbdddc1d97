"""fuzzcore.jit: the one Numba configuration, and every kernel module compiled with it."""
import importlib
import math
import pathlib

import numba
import pytest

from fuzzcore.jit import FASTMATH_SETS, OPTIONS, SYNTHETIC_IMAGE, kernel

ROOT = pathlib.Path(__file__).resolve().parents[2]
KERNEL_MODULES = sorted(
    ".".join(path.relative_to(ROOT).with_suffix("").parts)
    for package in ("fuzzcore", "monitor") for path in (ROOT / package).rglob("_*kernels.py")
)


def test_kernel_modules_found():
    assert KERNEL_MODULES == [
        "fuzzcore._kernels", "fuzzcore.tune._objective_kernels", "fuzzcore.verification._kernels",
        "monitor._alignment_kernels",
        "monitor.depth._geometric_kernels", "monitor.depth._retrieval_kernels",
        "monitor.depth._visibility_kernels",
        "monitor.geometry._box_kernels",
        "monitor.geometry._camera_kernels", "monitor.synthetic._degrade_kernels",
        "monitor.synthetic._raycast_kernels",
    ]


@pytest.mark.parametrize("name", KERNEL_MODULES)
def test_every_kernel_uses_the_options(name):
    module = importlib.import_module(name)
    dispatchers = [v for v in vars(module).values()
                   if isinstance(v, numba.core.registry.CPUDispatcher) and v.__module__ == name]
    assert dispatchers, name
    for d in dispatchers:
        for key, value in OPTIONS.items():
            if key == "cache":  # not a target option: the dispatcher holds a cache or not
                assert type(d._cache).__name__ == "FunctionCache", (name, d.__name__)
            else:
                assert d.targetoptions[key] == value, (name, d.__name__, key)
        fastmath = d.targetoptions.get("fastmath") or set()
        assert fastmath is not True and not {"nnan", "ninf", "fast"} & set(fastmath)
        assert not fastmath or frozenset(fastmath) in FASTMATH_SETS
    # nothing compiles around the shared decorator
    source = module.__loader__.get_source(name)
    assert "njit" not in source and "numba.jit" not in source and "fastmath={" not in source


def test_declared_fastmath_keeps_nan_and_inf():
    for flags in FASTMATH_SETS:
        assert not {"nnan", "ninf", "fast"} & flags


def test_undeclared_fastmath_refused():
    with pytest.raises(ValueError, match=r"fastmath=\['nnan'\] is not declared in fuzzcore.jit"):
        kernel(fastmath=frozenset({"nnan"}))
    with pytest.raises(ValueError, match="not declared"):
        kernel(fastmath=frozenset({"reassoc"}))  # a subset of a declared set is still a new set


@kernel
def _divide(a, b):
    return a / b


@kernel(inline=True, fastmath=SYNTHETIC_IMAGE)
def _lt(a, b):
    return a < b


@kernel(fastmath=SYNTHETIC_IMAGE)
def _less(a, b):
    return _lt(a, b)


def test_division_by_zero_is_ieee_and_never_raises():
    assert _divide(1.0, 0.0) == math.inf
    assert _divide(-1.0, 0.0) == -math.inf
    assert math.isnan(_divide(0.0, 0.0))
    assert math.isnan(_divide(math.nan, 2.0))


def test_declared_fastmath_keeps_comparisons_with_nan_and_inf():
    # nnan would let the compiler assume NaN never occurs and fold these comparisons
    assert not _less(math.nan, 1.0) and not _less(1.0, math.nan)
    assert _less(1.0, math.inf) and not _less(math.inf, math.inf)
