"""The engine on the paper's rule base (``rules/fuzzrisk.yaml``): one call, a million samples,
compile time, and the peers.

Run: ``python -m pytest benchmarks/bench_engine.py --benchmark-only -q``
(``-k "not compile"`` leaves out the two compile-time measurements, which start fresh
Python processes; the cold one compiles every kernel, about a minute).

Targets (issue 2): ``fis.infer(iou, rdd)`` <= 1.5 us median, warm; ``fis.evaluate`` on
1,000,000 samples >= 20 million samples/s on this 2-core machine. Issue 15: with NumPy
scalars (what any NumPy computation of IoU~ gives) <= 1 us, by name <= 1.5 us, measured as
ratios to the Python-float call in the same run (group ``infer, scalar types``).

Groups, answers checked before timing, fixed seeds:

- ``infer, one sample``: ``fis.infer`` against the tests' per-sample NumPy reference
  evaluator (``tests/reference.py``) and, when installed, scikit-fuzzy, simpful and
  pyfuzzylite (:mod:`peers`, which also says how their centroids differ).
- ``evaluate, 1,000,000 samples``: ``fis.evaluate`` (parallel), the serial kernel alone
  (one core), and a straightforward vectorised NumPy implementation (:func:`numpy_mamdani`).
  ``extra_info`` has samples/s from the median and the best round.
- ``evaluate, 10,000 samples``: fuzzcore against the peers' vectorised paths.
- ``compile``: the first ``warmup()`` with an empty Numba cache (cold) and with the cache
  filled (a fresh process loading the compiled kernels), each in a new process.

The machine's two cores are shared with other work, so wall-clock numbers are noisy: each
group's medians and their ratios are printed at the end, and the ``evaluate`` tests also
record CPU time per sample (``extra_info["cpu_ns_per_sample"]``, all threads).
"""
from __future__ import annotations

import os
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np
import pytest

import fuzzcore
from fuzzcore import _kernels as K

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests"))
sys.path.insert(0, str(Path(__file__).resolve().parent))
import peers  # noqa: E402
from reporting import write_report  # noqa: E402
import reference  # noqa: E402

#: scikit-fuzzy 0.5 calls np.maximum with a positional output, which numpy 2 deprecates
pytestmark = pytest.mark.filterwarnings("ignore::DeprecationWarning:skfuzzy")

RULES = ROOT / "rules" / "fuzzrisk.yaml"
N_BIG, N_PEERS = 1_000_000, 10_000
POINT = (0.4, 0.3)  # IoU~, RDD~: four rules fire
_MEDIANS: dict[str, dict[str, float]] = {}


@pytest.fixture(scope="module")
def fis():
    return fuzzcore.load(RULES).warmup()


@pytest.fixture(scope="module")
def big(fis):
    return peers.sample_inputs(fis, N_BIG, seed=2025)


@pytest.fixture(scope="module")
def installed(fis):
    return {p.name: p for p in peers.build_peers(fis)[0]}


@pytest.fixture(scope="module", autouse=True)
def report(request):
    yield
    lines = []
    for group, medians in _MEDIANS.items():
        ours = medians.get("fuzzcore")
        lines.append(f"  {group}")
        for name, t in medians.items():
            ratio = f"  x{t / ours:,.1f}" if ours else ""
            lines.append(f"    {name:24s} {t * 1e6:14,.3f} us{ratio}")
    write_report(request, "engine medians (ratios to fuzzcore in the same group):", lines)


def _record(benchmark, group, name):
    _MEDIANS.setdefault(group, {})[name] = benchmark.stats.stats.median


def numpy_mamdani(fis, X, chunk=50_000):
    """The system on ``X`` (n, n_in) -> (n,), the straightforward vectorised NumPy way.

    Memberships by the tests' reference functions, rule strengths by ``np.minimum`` /
    ``np.maximum``, the aggregated sets as an (n, res) array on MATLAB's grid, the centroid
    as ``agg @ y / agg.sum(1)``. Handles what :func:`peers.check_supported` accepts.
    """
    peers.check_supported(fis)
    out = fis.outputs[0]
    lo, hi = out.range
    y = lo + (np.arange(fis.resolution) * (hi - lo)) / (fis.resolution - 1)
    y[-1] = hi
    tables = [reference.membership(t.kind, t.params, y) for t in out.terms]
    result = np.empty(len(X))
    for a in range(0, len(X), chunk):
        x = X[a:a + chunk]
        agg = np.zeros((len(x), len(y)))
        for rule in fis.rules:
            strength = None
            for v, (var, code) in enumerate(zip(fis.inputs, rule.antecedent)):
                if code:
                    term = var.terms[code - 1]
                    mu = reference.membership(term.kind, term.params, x[:, v])
                    combine = np.minimum if rule.connective == "and" else np.maximum
                    strength = mu if strength is None else combine(strength, mu)
            implied = np.minimum(strength[:, None], tables[rule.consequent[0] - 1][None, :])
            np.maximum(agg, implied, out=agg)
        total = agg.sum(axis=1)
        with np.errstate(invalid="ignore", divide="ignore"):
            result[a:a + chunk] = np.where(total > 0, (agg @ y) / total, 0.5 * (lo + hi))
    return result


def test_numpy_mamdani_is_the_reference(fis):
    X = peers.sample_inputs(fis, 300, seed=7)
    np.testing.assert_allclose(numpy_mamdani(fis, X), reference.evaluate(fis, X)[:, 0], rtol=0, atol=1e-12)


# --------------------------------------------------------------------------- one sample
GROUP_ONE = "infer, one sample"


@pytest.mark.benchmark(group=GROUP_ONE, warmup=True)
def test_infer_fuzzcore(benchmark, fis):
    want = reference.evaluate(fis, [POINT])[0, 0]
    assert abs(fis.infer(*POINT) - want) <= 1e-12
    assert fis.infer(iou=POINT[0], rdd=POINT[1]) == fis.infer(*POINT)
    benchmark(fis.infer, *POINT)
    _record(benchmark, GROUP_ONE, "fuzzcore")


@pytest.mark.benchmark(group=GROUP_ONE)
def test_infer_numpy_reference(benchmark, fis):
    assert abs(reference.evaluate(fis, [POINT])[0, 0] - fis.infer(*POINT)) <= 1e-12
    benchmark.pedantic(reference.evaluate, args=(fis, [POINT]), rounds=200, iterations=1, warmup_rounds=5)
    _record(benchmark, GROUP_ONE, "numpy reference")


@pytest.mark.benchmark(group=GROUP_ONE)
@pytest.mark.parametrize("name", list(peers.BUILDERS))
def test_infer_peer(benchmark, fis, installed, name):
    if name not in installed:
        pytest.skip(f"{name} is not installed (optional peer)")
    peer = installed[name]
    x = np.array(POINT)
    assert abs(peer.one(x) - fis.infer(*POINT)) < 1e-2  # centroid rules differ (see peers.py)
    benchmark.pedantic(peer.one, args=(x,), rounds=30, iterations=1, warmup_rounds=2)
    _record(benchmark, GROUP_ONE, name)


# --------------------------------------------------------------------------- scalar types (issue 15)
GROUP_TYPES = "infer, scalar types"
#: (label, the inputs as given, by name?)
SCALAR_CALLS = [
    ("float", POINT, False),
    ("np.float64", tuple(np.float64(v) for v in POINT), False),
    ("np.float32", tuple(np.float32(v) for v in POINT), False),
    ("np.int64", (np.int64(0), np.int64(0)), False),
    ("int", (0, 1), False),
    ("float, by name", POINT, True),
    ("np.float64, by name", tuple(np.float64(v) for v in POINT), True),
]


@pytest.mark.benchmark(group=GROUP_TYPES, warmup=True)
@pytest.mark.parametrize("label, values, by_name", SCALAR_CALLS, ids=[c[0] for c in SCALAR_CALLS])
def test_infer_scalar_types(benchmark, fis, label, values, by_name):
    want = fis.infer(*(float(v) for v in values))
    if by_name:
        kwargs = dict(zip(fis.input_names, values))
        assert fis.infer(**kwargs) == want
        benchmark(fis.infer, **kwargs)
    else:
        assert fis.infer(*values) == want
        benchmark(fis.infer, *values)
    _record(benchmark, GROUP_TYPES, "fuzzcore" if label == "float" else label)


# --------------------------------------------------------------------------- a million samples
GROUP_BIG = "evaluate, 1,000,000 samples"


def _throughput(benchmark, n, cpu):
    stats = benchmark.stats.stats
    benchmark.extra_info["samples_per_s_median"] = round(n / stats.median)
    benchmark.extra_info["samples_per_s_best"] = round(n / stats.min)
    benchmark.extra_info["cpu_ns_per_sample"] = round(cpu / n * 1e9, 1)


@pytest.mark.benchmark(group=GROUP_BIG)
def test_evaluate_fuzzcore(benchmark, fis, big):
    some = big[:20_000]
    np.testing.assert_allclose(fis.evaluate(some)[:, 0], numpy_mamdani(fis, some), rtol=0, atol=1e-12)
    np.testing.assert_array_equal(fis.evaluate(big)[:20_000], fis.evaluate(some))
    benchmark.pedantic(fis.evaluate, args=(big,), rounds=15, iterations=1, warmup_rounds=2)
    _throughput(benchmark, len(big), peers.cpu_seconds(lambda: fis.evaluate(big)))
    _record(benchmark, GROUP_BIG, "fuzzcore")


@pytest.mark.benchmark(group=GROUP_BIG)
def test_evaluate_fuzzcore_one_core(benchmark, fis, big):
    out = np.empty((len(big), 1))
    K.evaluate_serial(big, fis._fblob, fis._iblob, out)
    np.testing.assert_array_equal(out, fis.evaluate(big))
    benchmark.pedantic(K.evaluate_serial, args=(big, fis._fblob, fis._iblob, out), rounds=7, iterations=1,
                       warmup_rounds=1)
    _throughput(benchmark, len(big), peers.cpu_seconds(lambda: K.evaluate_serial(big, fis._fblob, fis._iblob, out), 3))
    _record(benchmark, GROUP_BIG, "fuzzcore, one core")


@pytest.mark.benchmark(group=GROUP_BIG)
def test_evaluate_numpy(benchmark, fis, big):
    result = benchmark.pedantic(numpy_mamdani, args=(fis, big), rounds=3, iterations=1)
    np.testing.assert_allclose(result, fis.evaluate(big)[:, 0], rtol=0, atol=1e-12)
    _throughput(benchmark, len(big), peers.cpu_seconds(lambda: numpy_mamdani(fis, big), 1))
    _record(benchmark, GROUP_BIG, "numpy vectorised")


# --------------------------------------------------------------------------- peers, vectorised
GROUP_PEERS = f"evaluate, {N_PEERS:,} samples"


@pytest.mark.benchmark(group=GROUP_PEERS)
def test_evaluate_small_fuzzcore(benchmark, fis, big):
    X = big[:N_PEERS]
    benchmark.pedantic(fis.evaluate, args=(X,), rounds=50, iterations=1, warmup_rounds=2)
    _record(benchmark, GROUP_PEERS, "fuzzcore")


@pytest.mark.benchmark(group=GROUP_PEERS)
@pytest.mark.parametrize("name", [n for n in peers.BUILDERS if n != "simpful"])  # simpful: no vectorised path
def test_evaluate_small_peer(benchmark, fis, big, installed, name):
    if name not in installed:
        pytest.skip(f"{name} is not installed (optional peer)")
    X = big[:N_PEERS]
    run = installed[name].many
    assert np.max(np.abs(run(X[:500]) - fis.evaluate(X[:500])[:, 0])) < 1e-2  # centroid rules differ
    benchmark.pedantic(run, args=(X,), rounds=3, iterations=1)
    _record(benchmark, GROUP_PEERS, name)


# --------------------------------------------------------------------------- compile time
GROUP_COMPILE = "compile: first warmup() in a new process"
_WARMUP = ("import time, fuzzcore; fis = fuzzcore.load(r'{rules}'); t = time.perf_counter(); fis.warmup(); "
           "print(time.perf_counter() - t)")


def _warmup_seconds(cache_dir):
    env = dict(os.environ, NUMBA_CACHE_DIR=str(cache_dir)) if cache_dir else None
    done = subprocess.run([sys.executable, "-c", _WARMUP.format(rules=RULES)], env=env, capture_output=True,
                          text=True, check=True, cwd=ROOT)
    return float(done.stdout.split()[-1])


@pytest.mark.benchmark(group=GROUP_COMPILE)
def test_compile_cold(benchmark):
    with tempfile.TemporaryDirectory() as empty:
        seconds = benchmark.pedantic(_warmup_seconds, args=(empty,), rounds=1, iterations=1)
    benchmark.extra_info["warmup_s"] = round(seconds, 2)


@pytest.mark.benchmark(group=GROUP_COMPILE)
def test_compile_cached(benchmark):
    _warmup_seconds(None)  # fills the project's cache if needed
    seconds = benchmark.pedantic(_warmup_seconds, args=(None,), rounds=3, iterations=1)
    benchmark.extra_info["warmup_s"] = round(seconds, 2)
