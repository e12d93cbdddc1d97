"""Run one function over many work items, in this process, a process pool or on Ray, in order.

:func:`ordered_map` takes a *spec*: a picklable object whose ``build()`` returns the
function to apply (a :class:`~monitor.offline.run.RunSpec` builds a chunk processor: the
rule base is loaded and the Numba kernels compiled once per worker, not once per item).
Results come back in the order of the items whatever the backend, so a run gives the same
output serially, on ``workers`` processes or on Ray.

- ``workers == 1`` and no Ray: everything in this process;
- ``workers > 1``: a ``spawn`` process pool, each worker building the function once; at
  most ``2 * workers`` items are in flight, so a long list of items is never all pickled
  and queued at once; on an error the items in flight finish before the error is raised;
- ``ray``: ``"auto"`` (a running cluster, or a local one) or a cluster address; the items
  go through Ray Data's ``map_batches`` with a callable class on an actor pool
  (:mod:`monitor.offline.ray_backend`; Ray is an optional extra: ``pip install -e ".[ray]"``).
"""
from __future__ import annotations

import multiprocessing
from collections import deque
from typing import Any, Callable, Iterable, Iterator

#: the worker's function, built once per process by the pool's initializer (or the error
#: that building it raised: an initializer that raises would make the pool restart workers
#: forever, so the error is raised by the first call instead)
_WORKER_FN: Callable | None = None
_WORKER_ERROR: BaseException | None = None


def _init_worker(spec) -> None:
    global _WORKER_FN, _WORKER_ERROR
    try:
        _WORKER_FN = spec.build()
    except Exception as exc:  # noqa: BLE001 -- re-raised, unchanged, by every call
        _WORKER_ERROR = exc


def _call_worker(item):
    if _WORKER_ERROR is not None:
        raise _WORKER_ERROR
    return _WORKER_FN(item)


def check_workers(workers: int) -> int:
    """``workers`` as a process count; an error for anything but an integer >= 1."""
    if isinstance(workers, bool) or not isinstance(workers, int) or workers < 1:
        raise ValueError(f"--workers {workers!r}: expected an integer >= 1 (processes)")
    return workers


def ordered_map(spec, items: Iterable, *, workers: int = 1, ray: str | None = None,
                ray_options: dict | None = None) -> Iterator[Any]:
    """``spec.build()(item)`` for every item, yielded in the order of ``items``.

    Parameters
    ----------
    spec : object with ``build() -> callable``
        Picklable (it is sent to the workers).
    items : iterable
        Picklable work items.
    workers : int >= 1
        Local processes (ignored with ``ray``; Ray's actor pool takes ``workers`` actors).
    ray : str or None
        ``"auto"`` or a Ray cluster address.
    ray_options : dict, optional
        Passed to :func:`monitor.offline.ray_backend.ray_map` (e.g. ``num_cpus``).
    """
    check_workers(workers)
    if ray is not None:
        from monitor.offline.ray_backend import ray_map  # Ray is optional: imported only when asked for
        yield from ray_map(spec, items, address=ray, actors=workers, **(ray_options or {}))
        return
    if workers == 1:
        fn = spec.build()
        for item in items:
            yield fn(item)
        return
    pool = multiprocessing.get_context("spawn").Pool(workers, initializer=_init_worker, initargs=(spec,))
    try:
        pending: deque = deque()
        for item in items:
            pending.append(pool.apply_async(_call_worker, (item,)))
            if len(pending) >= 2 * workers:
                yield pending.popleft().get()
        while pending:
            yield pending.popleft().get()
    except BaseException as exc:
        if not isinstance(exc, (Exception, GeneratorExit)):  # Ctrl-C: the workers stop now
            pool.terminate()
        raise
    finally:
        # An error (or a consumer that stops early) closes the pool and lets the tasks in
        # flight (at most 2 * workers) finish. Pool.terminate() kills the workers, and one
        # killed while it puts a result on the shared result queue holds the queue's lock for
        # good: the pool's task handler then waits on it forever (CPython issue #96995; it
        # hung this way once in the test suite).
        pool.close()
        pool.join()
