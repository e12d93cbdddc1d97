"""fuzzcore.bench: numpy's percentiles, the measured variants, JSON round trip, comparison."""
import gc
import json

import numba
import numpy as np
import pytest

import fuzzcore
from fuzzcore import bench as B

RULES = "rules/fuzzrisk.yaml"


@pytest.fixture(scope="module")
def fis():
    return fuzzcore.load(RULES).warmup()


@pytest.fixture(scope="module")
def small(fis):
    return B.latency(fis, calls=300, evaluate_samples=2000, evaluate_rounds=2, measure_fresh_process=False)


# --------------------------------------------------------------------------- percentiles
def test_percentile_by_hand():
    x = np.arange(1.0, 11.0)  # 1..10
    # p90: h = (10 - 1) * 0.9 = 8.1, x[8] = 9, x[9] = 10 -> 9 + (10 - 9) * 0.1 = 9.1
    assert B.percentile(x, 90.0) == pytest.approx(9.1, abs=1e-12)
    # p50 of 1, 2, 3, 4: h = 3 * 0.5 = 1.5, g >= 0.5 -> 3 - (3 - 2) * 0.5 = 2.5
    assert B.percentile(np.array([1.0, 2.0, 3.0, 4.0]), 50.0) == 2.5
    # max is p100 is the last sample; one sample is every percentile
    assert B.percentile(x, 100.0) == 10.0
    assert B.percentile(np.array([7.0]), 99.99) == 7.0
    with pytest.raises(ValueError, match="percentile 101"):
        B.percentile(x, 101)


@pytest.mark.parametrize("n", [1, 2, 3, 7, 10, 999, 1000, 12345])
def test_percentile_equals_numpys_to_the_bit(n):
    rng = np.random.default_rng(n)
    # latencies-like samples: integer nanoseconds with ties and a heavy tail
    samples = np.round(rng.lognormal(7.0, 1.0, n)).astype(np.float64)
    ordered = np.sort(samples)
    qs = list(B.PERCENTILES.values()) + [0.0, 1e-3, 12.5, 33.3, 66.7, 99.999]
    for q in qs:
        assert B.percentile(ordered, q) == np.percentile(samples, q), (n, q)


def test_latency_summary_matches_numpy():
    samples = np.array([120, 95, 3000, 101, 99, 97, 250, 100, 98, 96], dtype=np.int64)
    lat = B.Latency.from_samples("x", "", samples)
    assert lat.count == 10 and lat.mean_ns == samples.mean()
    for name, q in B.PERCENTILES.items():
        assert lat.percentiles_ns[name] == np.percentile(samples, q)
    np.testing.assert_array_equal(lat.samples_ns, samples)  # call order kept
    with pytest.raises(ValueError, match="x: latencies must be"):
        B.Latency.from_samples("x", "", [])


# --------------------------------------------------------------------------- measuring
def test_latency_measures_every_way_of_calling(small):
    assert list(small.latencies) == list(B.CALLS)
    for name, lat in small.latencies.items():
        assert lat.count == 300 and lat.samples_ns.shape == (300,) and (lat.samples_ns > 0).all()
        values = [lat.percentiles_ns[p] for p in B.PERCENTILES]
        assert values == sorted(values) and values[-1] == lat.samples_ns.max()
    assert [t.threads for t in small.throughput] == sorted({1, numba.get_num_threads()})
    assert all(len(t.seconds) == 2 and t.samples == 2000 for t in small.throughput)
    assert small.fresh_process is None and small.system == "fuzzrisk"
    assert small.machine.numpy == np.__version__ and small.machine.logical_cpus >= 1


def test_latency_restores_gc_and_threads(fis):
    threads = numba.get_num_threads()
    gc.disable()
    try:
        B.latency(fis, calls=50, evaluate_samples=600, evaluate_rounds=1, measure_fresh_process=False)
        assert not gc.isenabled()  # a caller's disabled collector stays disabled
    finally:
        gc.enable()
    B.latency(fis, calls=50, evaluate_samples=600, evaluate_rounds=1, measure_fresh_process=False)
    assert gc.isenabled() and gc.get_freeze_count() == 0 and numba.get_num_threads() == threads


def test_latency_rejects_bad_arguments(fis):
    with pytest.raises(ValueError, match="calls = 0, must be an integer >= 1"):
        B.latency(fis, calls=0)
    with pytest.raises(ValueError, match="evaluate_samples = 1.5"):
        B.latency(fis, evaluate_samples=1.5)
    with pytest.raises(ValueError, match="seed = -1"):
        B.latency(fis, seed=-1)
    with pytest.raises(ValueError, match="fis is a str"):
        B.latency(RULES)


def test_fresh_process_loads_and_warms_up():
    fresh = B.fresh_process(RULES)
    assert fresh.import_s > 0 and fresh.load_s > 0 and fresh.warmup_s > 0
    assert fresh.total_s > fresh.import_s + fresh.load_s + fresh.warmup_s
    assert fresh.compiled + fresh.cached >= 4  # infer_one, evaluate_serial/_batch, explain_one at least
    with pytest.raises(FileNotFoundError, match="nope.yaml: no such rule base file"):
        B.fresh_process("nope.yaml")


# --------------------------------------------------------------------------- JSON and comparison
def test_json_round_trip(small):
    data = json.loads(json.dumps(small.to_dict()))
    assert data["schema"] == B.SCHEMA and set(data["latencies"]) == set(B.CALLS)
    back = B.BenchResult.from_dict(data)
    assert back.to_dict() == small.to_dict()
    assert back.latencies["infer"].samples_ns is None  # samples only when asked for
    with_samples = B.BenchResult.from_dict(json.loads(json.dumps(small.to_dict(samples=True))))
    np.testing.assert_array_equal(with_samples.latencies["infer"].samples_ns, small.latencies["infer"].samples_ns)


def test_from_dict_names_what_is_wrong(small):
    data = small.to_dict()
    with pytest.raises(ValueError, match=r"schema 'other/1', expected 'fuzzrisk.bench/1'"):
        B.BenchResult.from_dict({**data, "schema": "other/1"})
    broken = json.loads(json.dumps(data))
    del broken["latencies"]["infer"]["percentiles_ns"]["p99.9"]
    with pytest.raises(ValueError, match=r"latencies.infer.percentiles_ns: missing p99.9"):
        B.BenchResult.from_dict(broken)
    broken = json.loads(json.dumps(data))
    del broken["machine"]["cpu"]
    with pytest.raises(ValueError, match=r"machine: field 'cpu' is missing"):
        B.BenchResult.from_dict(broken)


def _result(infer_ns, per_s_seconds, warmup_s):
    machine = B.Machine("cpu", 2, 2, 2, "3", "2", "0", "linux")
    return B.BenchResult(
        system="s", seed=0, latencies={"infer": B.Latency.from_samples("infer", "", infer_ns)},
        throughput=(B.Throughput(1, 1000, per_s_seconds),),
        fresh_process=B.FreshProcess(0.5, 0.25, warmup_s, 2.0, 0, 5), machine=machine)


def test_compare_gives_new_over_old():
    old = _result([1000, 1000, 2000], (0.001, 0.002, 0.003), 1.0)  # median 2 ms -> 500,000 samples/s
    new = _result([1500, 1500, 1500], (0.004, 0.004, 0.004), 0.5)  # 250,000 samples/s
    rows = {r.what: r for r in new.compare(old)}
    assert rows["infer p50"].ratio == 1.5  # 1500 / 1000
    assert rows["infer max"].ratio == 0.75  # 1500 / 2000
    tp = rows["evaluate, 1 thread(s)"]
    assert (tp.old, tp.new, tp.ratio, tp.higher_is_better) == (500_000.0, 250_000.0, 0.5, True)
    assert rows["fresh process: load + warmup"].ratio == 0.75 / 1.25  # (0.25 + 0.5) / (0.25 + 1.0)
    assert len(rows) == len(B.PERCENTILES) + 2
