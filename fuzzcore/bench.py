"""How fast a fuzzy system answers on this machine: tail latency, throughput, start-up.

A real-time budget is about the tail, not the median. :func:`latency` times ``fis.infer``
call by call over distinct inputs after a warm-up and reports the distribution (p50, p90,
p99, p99.9, p99.99, max), beside the cost of a plain Python call timed the same way in the
same run (the floor: the clock and the call itself), with the garbage collector running
and frozen; ``infer`` with numpy scalars and by name; ``evaluate`` throughput on one thread
and on all of Numba's threads; and the compile or cache-load time of a fresh process. The
result names the machine, round-trips through JSON (:meth:`BenchResult.to_dict`,
:meth:`BenchResult.from_dict`) and compares with an earlier run (:meth:`BenchResult.compare`).

>>> import fuzzcore, fuzzcore.bench
>>> fis = fuzzcore.load("rules/fuzzrisk.yaml")
>>> result = fuzzcore.bench.latency(fis, calls=100_000)             # doctest: +SKIP
>>> result.latencies["infer"].percentiles_ns["p99.9"]                # doctest: +SKIP
2012.0

Percentiles
-----------
:func:`percentile` is numpy's default (``np.percentile(x, q)``, method ``"linear"``,
Hyndman and Fan's type 7), to the bit: on the n sorted samples ``x[0] <= ... <= x[n-1]``,
``h = (n - 1) * (q / 100)``, ``i = floor(h)``, ``g = h - i`` and the percentile is
``x[i] + (x[i+1] - x[i]) * g`` (written ``x[i+1] - (x[i+1] - x[i]) * (1 - g)`` when
``g >= 0.5``, as numpy does); ``x[n-1]`` when ``h >= n - 1``. ``max`` is p100. With fewer
than ``100 / (100 - q)`` samples a high percentile lies between the largest samples: p99.99
needs 10,000 calls to mean anything.
"""
from __future__ import annotations

import gc
import json
import math
import os
import platform
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable, Mapping, Sequence

import numba
import numpy as np

from .errors import RuleBaseError
from .io import save
from .system import FuzzySystem

#: reported percentiles: name -> q in [0, 100] (``max`` is p100)
PERCENTILES: dict[str, float] = {"p50": 50.0, "p90": 90.0, "p99": 99.0, "p99.9": 99.9,
                                 "p99.99": 99.99, "max": 100.0}

#: the ways of calling that :func:`latency` times, in report order: name -> description
CALLS: dict[str, str] = {
    "floor": "a plain Python function, same arguments (the clock and a call)",
    "infer": "fis.infer(x, y): Python floats",
    "infer_gc_frozen": "fis.infer(x, y): Python floats, garbage collector frozen and disabled",
    "infer_numpy": "fis.infer(x, y): numpy float64 scalars",
    "infer_by_name": "fis.infer(name=x, ...): Python floats by name",
}

#: the JSON schema written by :meth:`BenchResult.to_dict`
SCHEMA = "fuzzrisk.bench/1"

#: calls per variant before moving to the next one; variants take turns block by block,
#: so a load change on a shared machine touches all of them alike
BLOCK = 2000


def percentile(sorted_values: np.ndarray, q: float) -> float:
    """numpy's default percentile (method ``"linear"``) of already sorted samples.

    Parameters
    ----------
    sorted_values : ndarray of shape (n,), n >= 1
        Ascending, no NaN.
    q : float
        In [0, 100].

    Returns
    -------
    float
        Equal to ``np.percentile(sorted_values, q)`` (see the module docstring).
    """
    n = len(sorted_values)
    if n == 0 or not 0.0 <= q <= 100.0:
        raise ValueError(f"percentile {q!r} of {n} samples: expected q in [0, 100] and at least one sample")
    h = (n - 1) * (q / 100.0)
    if h >= n - 1:
        return float(sorted_values[n - 1])
    i = math.floor(h)
    a, b = float(sorted_values[i]), float(sorted_values[i + 1])
    g = h - i
    return b - (b - a) * (1.0 - g) if g >= 0.5 else a + (b - a) * g


def _positive_int(value: Any, name: str) -> int:
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < 1:
        raise ValueError(f"{name} = {value!r}, must be an integer >= 1")
    return int(value)


def _field(data: Mapping, key: str, where: str) -> Any:
    if not isinstance(data, Mapping):
        raise ValueError(f"{where}: expected an object, got {type(data).__name__}")
    if key not in data:
        raise ValueError(f"{where}: field {key!r} is missing")
    return data[key]


@dataclass(frozen=True, eq=False)
class Latency:
    """The latency distribution of one way of calling.

    Attributes
    ----------
    name : str
    description : str
    count : int
        Timed calls.
    mean_ns : float
    percentiles_ns : dict of str to float
        One entry per :data:`PERCENTILES` key, nanoseconds.
    samples_ns : ndarray of shape (count,), float64, or None
        Each call's latency in call order, nanoseconds; None when read back from JSON
        written without samples.
    """

    name: str
    description: str
    count: int
    mean_ns: float
    percentiles_ns: dict
    samples_ns: np.ndarray | None = None

    @classmethod
    def from_samples(cls, name: str, description: str, samples_ns) -> "Latency":
        """Summarise per-call latencies (nanoseconds, at least one, all finite)."""
        samples = np.asarray(samples_ns, dtype=np.float64)
        if samples.ndim != 1 or samples.size == 0 or not np.isfinite(samples).all():
            raise ValueError(f"{name}: latencies must be a non-empty 1-D array of finite "
                             f"nanoseconds, got shape {samples.shape}")
        ordered = np.sort(samples)
        return cls(name=name, description=description, count=int(samples.size),
                   mean_ns=float(samples.mean()),
                   percentiles_ns={k: percentile(ordered, q) for k, q in PERCENTILES.items()},
                   samples_ns=samples)

    def to_dict(self, samples: bool = False) -> dict:
        out = {"name": self.name, "description": self.description, "count": self.count,
               "mean_ns": self.mean_ns, "percentiles_ns": dict(self.percentiles_ns)}
        if samples and self.samples_ns is not None:
            out["samples_ns"] = self.samples_ns.tolist()
        return out

    @classmethod
    def from_dict(cls, data: Mapping, where: str = "latency") -> "Latency":
        percentiles = _field(data, "percentiles_ns", where)
        missing = [k for k in PERCENTILES if k not in percentiles]
        if missing:
            raise ValueError(f"{where}.percentiles_ns: missing {', '.join(missing)}")
        samples = data.get("samples_ns")
        return cls(name=_field(data, "name", where), description=_field(data, "description", where),
                   count=int(_field(data, "count", where)), mean_ns=float(_field(data, "mean_ns", where)),
                   percentiles_ns={k: float(percentiles[k]) for k in PERCENTILES},
                   samples_ns=None if samples is None else np.asarray(samples, dtype=np.float64))


@dataclass(frozen=True)
class Throughput:
    """``fis.evaluate`` on one batch, timed over several rounds.

    Attributes
    ----------
    threads : int
        Numba threads the kernels ran on.
    samples : int
        Batch size.
    seconds : tuple of float
        Wall time of each round.
    """

    threads: int
    samples: int
    seconds: tuple

    @property
    def median_per_s(self) -> float:
        """Samples per second at the median round."""
        return self.samples / float(np.median(self.seconds))

    @property
    def best_per_s(self) -> float:
        """Samples per second at the fastest round."""
        return self.samples / min(self.seconds)

    def to_dict(self) -> dict:
        return {"threads": self.threads, "samples": self.samples, "seconds": list(self.seconds),
                "median_per_s": self.median_per_s, "best_per_s": self.best_per_s}

    @classmethod
    def from_dict(cls, data: Mapping, where: str = "throughput") -> "Throughput":
        return cls(threads=int(_field(data, "threads", where)), samples=int(_field(data, "samples", where)),
                   seconds=tuple(float(s) for s in _field(data, "seconds", where)))


@dataclass(frozen=True)
class FreshProcess:
    """Start-up of a new Python process that loads the rule base and warms it up.

    Attributes
    ----------
    import_s, load_s, warmup_s : float
        ``import fuzzcore``, ``fuzzcore.load(path)`` and ``fis.warmup()``, seconds.
    total_s : float
        Wall time of the whole process, interpreter start included.
    compiled, cached : int
        Kernel specialisations compiled in that process / loaded from Numba's on-disk
        cache: ``compiled > 0`` means ``warmup_s`` is a compile time, not a cache load.
    """

    import_s: float
    load_s: float
    warmup_s: float
    total_s: float
    compiled: int
    cached: int

    def to_dict(self) -> dict:
        return {k: getattr(self, k) for k in self.__dataclass_fields__}

    @classmethod
    def from_dict(cls, data: Mapping, where: str = "fresh_process") -> "FreshProcess":
        return cls(**{k: _field(data, k, where) for k in cls.__dataclass_fields__})


@dataclass(frozen=True)
class Machine:
    """Where a measurement ran.

    Attributes
    ----------
    cpu : str
        CPU model (``/proc/cpuinfo``; ``platform.processor()`` elsewhere).
    logical_cpus : int
        Logical CPUs of the machine.
    usable_cpus : int
        Those this process may run on (its CPU affinity).
    numba_threads : int
        Numba's thread count for the run ("all threads").
    python, numpy, numba, platform : str
        Versions and operating system.
    """

    cpu: str
    logical_cpus: int
    usable_cpus: int
    numba_threads: int
    python: str
    numpy: str
    numba: str
    platform: str

    @classmethod
    def here(cls) -> "Machine":
        """This machine, now."""
        usable = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count()
        return cls(cpu=_cpu_model(), logical_cpus=os.cpu_count() or 0, usable_cpus=usable or 0,
                   numba_threads=numba.get_num_threads(), python=platform.python_version(),
                   numpy=np.__version__, numba=numba.__version__, platform=platform.platform())

    def to_dict(self) -> dict:
        return {k: getattr(self, k) for k in self.__dataclass_fields__}

    @classmethod
    def from_dict(cls, data: Mapping, where: str = "machine") -> "Machine":
        return cls(**{k: _field(data, k, where) for k in cls.__dataclass_fields__})

    def __str__(self) -> str:
        return (f"{self.cpu}, {self.usable_cpus} of {self.logical_cpus} CPUs usable, "
                f"{self.numba_threads} Numba threads; Python {self.python}, numpy {self.numpy}, "
                f"numba {self.numba}; {self.platform}")


def _cpu_model() -> str:
    try:
        with open("/proc/cpuinfo", encoding="utf-8") as f:
            for line in f:
                if line.startswith("model name"):
                    return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or platform.machine() or "unknown"


@dataclass(frozen=True)
class Ratio:
    """One figure of two runs: ``ratio = new / old``; ``higher_is_better`` says which way is good."""

    what: str
    unit: str
    old: float
    new: float
    higher_is_better: bool

    @property
    def ratio(self) -> float:
        return self.new / self.old if self.old else math.inf


@dataclass(frozen=True, eq=False)
class BenchResult:
    """What :func:`latency` measured.

    Attributes
    ----------
    system : str
        The fuzzy system's name.
    seed : int
        Seed of the inputs.
    latencies : dict of str to Latency
        Keys of :data:`CALLS`, in that order.
    throughput : tuple of Throughput
        ``evaluate`` on one thread, then on all threads (one entry when that is one).
    fresh_process : FreshProcess or None
        None when not measured.
    machine : Machine
    """

    system: str
    seed: int
    latencies: dict
    throughput: tuple
    fresh_process: FreshProcess | None
    machine: Machine

    def to_dict(self, samples: bool = False) -> dict:
        """A JSON-ready dict (schema :data:`SCHEMA`); per-call samples only if ``samples``."""
        return {"schema": SCHEMA, "system": self.system, "seed": self.seed,
                "latencies": {k: v.to_dict(samples) for k, v in self.latencies.items()},
                "throughput": [t.to_dict() for t in self.throughput],
                "fresh_process": None if self.fresh_process is None else self.fresh_process.to_dict(),
                "machine": self.machine.to_dict()}

    @classmethod
    def from_dict(cls, data: Mapping, where: str = "bench result") -> "BenchResult":
        """Read back :meth:`to_dict`; a wrong schema or a missing field is an error naming it."""
        schema = _field(data, "schema", where)
        if schema != SCHEMA:
            raise ValueError(f"{where}: schema {schema!r}, expected {SCHEMA!r}")
        latencies = _field(data, "latencies", where)
        if not isinstance(latencies, Mapping):
            raise ValueError(f"{where}.latencies: expected an object")
        fresh = _field(data, "fresh_process", where)
        return cls(
            system=_field(data, "system", where), seed=int(_field(data, "seed", where)),
            latencies={k: Latency.from_dict(v, f"{where}.latencies.{k}") for k, v in latencies.items()},
            throughput=tuple(Throughput.from_dict(t, f"{where}.throughput[{i}]")
                             for i, t in enumerate(_field(data, "throughput", where))),
            fresh_process=None if fresh is None else FreshProcess.from_dict(fresh, f"{where}.fresh_process"),
            machine=Machine.from_dict(_field(data, "machine", where), f"{where}.machine"))

    @classmethod
    def read(cls, path: str | Path) -> "BenchResult":
        """Read a result saved as JSON (``fuzzrisk bench --json > old.json``)."""
        path = Path(path)
        if not path.is_file():
            raise FileNotFoundError(f"{path}: no such bench result file")
        try:
            data = json.loads(path.read_text(encoding="utf-8"))
        except (json.JSONDecodeError, UnicodeDecodeError) as exc:
            raise ValueError(f"{path}: not a JSON bench result ({exc})") from None
        return cls.from_dict(data, str(path))

    def compare(self, old: "BenchResult") -> list[Ratio]:
        """This run against an ``old`` one: every figure both have, ``new / old``."""
        rows = []
        for name, lat in self.latencies.items():
            before = old.latencies.get(name)
            if before is not None:
                rows += [Ratio(f"{name} {p}", "ns", before.percentiles_ns[p], lat.percentiles_ns[p], False)
                         for p in PERCENTILES]
        for tp in self.throughput:
            before = next((t for t in old.throughput if t.threads == tp.threads), None)
            if before is not None:
                rows.append(Ratio(f"evaluate, {tp.threads} thread(s)", "samples/s",
                                  before.median_per_s, tp.median_per_s, True))
        if self.fresh_process is not None and old.fresh_process is not None:
            rows.append(Ratio("fresh process: load + warmup", "s",
                              old.fresh_process.load_s + old.fresh_process.warmup_s,
                              self.fresh_process.load_s + self.fresh_process.warmup_s, False))
        return rows


# --------------------------------------------------------------------------- measuring
def _plain(*args):
    return 0.0


def _time_block(fn: Callable, inputs: Sequence, by_name: bool, out: list, start: int) -> None:
    """Time ``fn`` on each input, writing nanoseconds to ``out[start:]``."""
    clock = time.perf_counter_ns
    i = start
    if by_name:
        for kw in inputs:
            t0 = clock()
            fn(**kw)
            out[i] = clock() - t0
            i += 1
    else:
        for args in inputs:
            t0 = clock()
            fn(*args)
            out[i] = clock() - t0
            i += 1


def _check_answers(fis: FuzzySystem, X: np.ndarray, variants: dict) -> None:
    """Every way of calling gives ``evaluate``'s answer, before any of them is timed."""
    want = fis.evaluate(X)
    for name, (fn, inputs, by_name) in variants.items():
        if fn is _plain:
            continue
        for k, x in enumerate(inputs[:len(X)]):
            got = np.atleast_1d(fn(**x) if by_name else fn(*x))
            if not np.array_equal(got, want[k], equal_nan=True):
                raise RuntimeError(f"{name} gives {got.tolist()} for input {k}, evaluate gives "
                                   f"{want[k].tolist()}: the call paths disagree")


def _calls(fis: FuzzySystem, calls: int, variants: dict) -> dict[str, Latency]:
    """Time every variant over the same inputs, block by block in turns."""
    _check_answers(fis, np.array([list(x) for x in variants["infer"][1][:100]]), variants)
    warm = min(calls, BLOCK)
    for fn, inputs, by_name in variants.values():
        _time_block(fn, inputs[:warm], by_name, [0] * warm, 0)
    times = {name: [0] * calls for name in variants}
    was_enabled = gc.isenabled()
    for start in range(0, calls, BLOCK):
        stop = min(start + BLOCK, calls)
        for name, (fn, inputs, by_name) in variants.items():
            frozen = name == "infer_gc_frozen"
            if frozen:
                gc.freeze()
                gc.disable()
            try:
                _time_block(fn, inputs[start:stop], by_name, times[name], start)
            finally:
                if frozen:
                    gc.unfreeze()
                    if was_enabled:
                        gc.enable()
    return {name: Latency.from_samples(name, CALLS[name], times[name]) for name in variants}


def _throughput(fis: FuzzySystem, samples: int, rounds: int, seed: int) -> tuple[Throughput, ...]:
    rng = np.random.default_rng([seed, 1])
    X = _uniform(fis, samples, rng)
    everyone = numba.get_num_threads()
    out = []
    try:
        for threads in sorted({1, everyone}):
            numba.set_num_threads(threads)
            fis.evaluate(X)  # warm-up round
            seconds = []
            for _ in range(rounds):
                t0 = time.perf_counter()
                fis.evaluate(X)
                seconds.append(time.perf_counter() - t0)
            out.append(Throughput(threads=threads, samples=samples, seconds=tuple(seconds)))
    finally:
        numba.set_num_threads(everyone)
    return tuple(out)


_FRESH = """\
import json, sys, time
t0 = time.perf_counter()
import fuzzcore
from fuzzcore import _kernels
t1 = time.perf_counter()
fis = fuzzcore.load(sys.argv[1])
t2 = time.perf_counter()
fis.warmup()
t3 = time.perf_counter()
stats = [f.stats for f in vars(_kernels).values() if hasattr(f, "stats")]
print(json.dumps({"import_s": t1 - t0, "load_s": t2 - t1, "warmup_s": t3 - t2,
                  "compiled": sum(sum(s.cache_misses.values()) for s in stats),
                  "cached": sum(sum(s.cache_hits.values()) for s in stats)}))
"""


def fresh_process(path: str | Path) -> FreshProcess:
    """Start a new Python process that imports this fuzzcore, loads ``path`` and warms it up.

    With Numba's cache filled this is the cache-load time a restarted monitor pays; with
    it empty, the compile time (:attr:`FreshProcess.compiled` tells which).
    """
    path = Path(path)
    if not path.is_file():
        raise FileNotFoundError(f"{path}: no such rule base file")
    package_root = str(Path(__file__).resolve().parents[1])
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(
        p for p in (package_root, os.environ.get("PYTHONPATH")) if p))
    t0 = time.perf_counter()
    done = subprocess.run([sys.executable, "-c", _FRESH, str(path)], env=env, capture_output=True,
                          text=True)
    total = time.perf_counter() - t0
    if done.returncode != 0:
        raise RuntimeError(f"the fresh process loading {path} failed:\n{done.stderr.strip()[-2000:]}")
    return FreshProcess(total_s=total, **json.loads(done.stdout.strip().splitlines()[-1]))


def _fresh_from_system(fis: FuzzySystem) -> FreshProcess:
    """:func:`fresh_process` on ``fis`` written to a temporary rule base (YAML, else .fis)."""
    with tempfile.TemporaryDirectory() as tmp:
        for suffix in (".yaml", ".fis"):
            path = Path(tmp) / f"system{suffix}"
            try:
                save(fis, path)
            except RuleBaseError:
                continue
            return fresh_process(path)
    raise ValueError(f"{fis.name}: neither YAML nor .fis can hold this system; pass its file as path")


def _uniform(fis: FuzzySystem, n: int, rng: np.random.Generator) -> np.ndarray:
    lo = np.array([v.range[0] for v in fis.inputs])
    hi = np.array([v.range[1] for v in fis.inputs])
    return lo + (hi - lo) * rng.random((n, len(fis.inputs)))


def latency(fis: FuzzySystem, calls: int = 200_000, *, seed: int = 0, evaluate_samples: int = 1_000_000,
            evaluate_rounds: int = 5, path: str | Path | None = None,
            measure_fresh_process: bool = True) -> BenchResult:
    """Measure a fuzzy system's call latency, throughput and start-up on this machine.

    Parameters
    ----------
    fis : FuzzySystem
    calls : int >= 1
        Timed calls per way of calling (:data:`CALLS`), each on a distinct input drawn
        uniformly from the input ranges; the ways take turns in blocks of :data:`BLOCK`
        calls after a warm-up of one block each. Every way's answer is first checked
        against ``fis.evaluate``.
    seed : int
        Seed of the inputs.
    evaluate_samples : int >= 1
        Batch size for the ``evaluate`` throughput (on 1 thread and on all Numba threads;
        the thread count is restored afterwards).
    evaluate_rounds : int >= 1
        Timed rounds per thread count, after one warm-up round.
    path : str or Path, optional
        The rule base file the fresh process loads (default: ``fis`` written to a
        temporary file).
    measure_fresh_process : bool
        Measure the start-up of a fresh process (:func:`fresh_process`).

    Returns
    -------
    BenchResult
    """
    if not isinstance(fis, FuzzySystem):
        raise ValueError(f"fis is a {type(fis).__name__}, expected a fuzzcore.FuzzySystem")
    calls = _positive_int(calls, "calls")
    evaluate_samples = _positive_int(evaluate_samples, "evaluate_samples")
    evaluate_rounds = _positive_int(evaluate_rounds, "evaluate_rounds")
    if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or seed < 0:
        raise ValueError(f"seed = {seed!r}, must be an integer >= 0")
    fresh = None
    if measure_fresh_process:  # first: a fresh process compiling must not race our timings
        fresh = fresh_process(path) if path is not None else _fresh_from_system(fis)
    fis.warmup()
    X = _uniform(fis, calls, np.random.default_rng([int(seed), 0]))
    floats = [tuple(row) for row in X.tolist()]
    variants = {
        "floor": (_plain, floats, False),
        "infer": (fis.infer, floats, False),
        "infer_gc_frozen": (fis.infer, floats, False),
        "infer_numpy": (fis.infer, [tuple(row) for row in X], False),
        "infer_by_name": (fis.infer, [dict(zip(fis.input_names, row)) for row in floats], True),
    }
    latencies = _calls(fis, calls, variants)
    return BenchResult(system=fis.name, seed=int(seed), latencies=latencies,
                       throughput=_throughput(fis, evaluate_samples, evaluate_rounds, int(seed)),
                       fresh_process=fresh, machine=Machine.here())
