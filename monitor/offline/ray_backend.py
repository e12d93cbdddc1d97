"""The same work on a Ray cluster with Ray Data (``--ray auto|ADDRESS``): optional, ``pip install -e ".[ray]"``.

- :func:`ray_map`: items through one ``map_batches`` stage of callable-class actors, each
  building its function once from a spec (``prior build``);
- :func:`ray_run`: the monitor's chunks expanded to one row per frame, then a depth stage
  for frames with camera images (the ONNX network on GPU actors when the cluster has GPUs,
  ``batch_size`` images per call) and a monitor stage on CPU actors that each load the rule
  base and compile the kernels once.

Both keep the order of the items (``preserve_order`` on the current Ray Data context), so
the results are those of a local run, in the same order. ``address="auto"`` connects to a
running cluster or starts a local one; any other address must answer, or the error names
it. Ray already initialised in this process (e.g. ``ray.init(num_cpus=2)`` in a test) is
used as it is.
"""
from __future__ import annotations

import dataclasses
import socket
from typing import Iterable, Iterator

import numpy as np

from monitor.offline.run import CHUNK_FRAMES, Chunk, FrameResult, RunSpec, resolve_depths


def _ray():
    try:
        import ray
        import ray.data  # noqa: F401 -- Ray Data, not only Ray core
    except ImportError:
        raise ValueError("--ray needs Ray with Ray Data: pip install -e \".[ray]\" (or pip install "
                         "'ray[data]')") from None
    return ray


#: seconds to wait for a cluster address to accept a connection (Ray itself waits minutes)
CONNECT_TIMEOUT_S = 5.0


def check_address(address: str) -> None:
    """An error naming ``address`` unless it is ``HOST:PORT`` (or ``ray://HOST:PORT``) and a TCP
    connection to it opens within :data:`CONNECT_TIMEOUT_S` (Ray's own attempt would hang for minutes)."""
    hostport = address.split("://", 1)[1] if "://" in address else address
    host, _, port = hostport.rpartition(":")
    if not host or not port.isdigit():
        raise ValueError(f"--ray {address!r}: expected 'auto' or a cluster address HOST:PORT "
                         "(e.g. 10.0.0.5:6379, or ray://10.0.0.5:10001 for Ray Client)")
    try:
        socket.create_connection((host, int(port)), timeout=CONNECT_TIMEOUT_S).close()
    except OSError as exc:
        raise ValueError(f"--ray {address}: no Ray cluster answers there ({exc}); start one with "
                         "'ray start --head', give its address, or use --ray auto") from None


def connect(address: str):
    """Initialise Ray (unless it is) against ``address``; the ``ray`` module."""
    ray = _ray()
    if ray.is_initialized():
        return ray
    if address != "auto":
        check_address(address)
    try:
        ray.init(address=None if address == "auto" else address, include_dashboard=False,
                 log_to_driver=False, ignore_reinit_error=True)
    except Exception as exc:  # Ray raises ConnectionError, RuntimeError, ... for a cluster it cannot reach
        raise ValueError(f"--ray {address}: no Ray cluster answers there ({type(exc).__name__}: {exc}); "
                         "start one ('ray start --head'), give its address, or use --ray auto") from None
    return ray


def _ordered(ray) -> None:
    context = ray.data.DataContext.get_current()
    context.execution_options.preserve_order = True
    context.enable_progress_bars = False  # the command has its own


def _objects(values) -> np.ndarray:
    out = np.empty(len(values), dtype=object)
    out[:] = values
    return out


class _Apply:
    """Ray Data callable class: ``spec.build()`` once per actor, applied to column ``item``."""

    def __init__(self, spec):
        self.fn = spec.build()

    def __call__(self, batch: dict) -> dict:
        return {"result": _objects([self.fn(item) for item in batch["item"]])}


def ray_map(spec, items: Iterable, *, address: str, actors: int, num_cpus: float = 1) -> Iterator:
    """``spec.build()(item)`` for every item on ``actors`` Ray actors, in order."""
    ray = connect(address)
    _ordered(ray)
    items = list(items)
    if not items:
        return
    ds = ray.data.from_items([{"item": item} for item in items])
    ds = ds.map_batches(_Apply, fn_constructor_args=(spec,), batch_size=1, batch_format="numpy",
                        compute=ray.data.ActorPoolStrategy(size=actors), num_cpus=num_cpus)
    for row in ds.iter_rows():
        yield row["result"]


def _expand(row: dict) -> list[dict]:
    """One chunk -> one row per frame record (frames of a scene source generated here)."""
    chunk: Chunk = row["chunk"]
    return [{"record": record, "condition": chunk.condition} for record in chunk.frame_records()]


class _DepthStage:
    """Ray Data callable class: the depth network, built once per (GPU) actor."""

    def __init__(self, depth_model):
        self.image_depth = depth_model.build()

    def __call__(self, batch: dict) -> dict:
        depths = resolve_depths(list(batch["record"]), self.image_depth)
        return {**batch, "depth": _objects([d for d, _ in depths]), "source": _objects([s for _, s in depths])}


class _MonitorStage:
    """Ray Data callable class: the monitor, its rule base loaded and kernels compiled once per actor."""

    def __init__(self, spec: RunSpec):
        self.processor = spec.build()

    def __call__(self, batch: dict) -> dict:
        records = list(batch["record"])
        if "depth" in batch:
            depths = list(zip(batch["depth"], batch["source"]))
        else:
            depths = resolve_depths(records, None)
        results = []
        for record, depth, condition in zip(records, depths, batch["condition"]):
            results += self.processor.observe([record], [depth], condition)
        return {"result": _objects(results)}


def ray_run(spec: RunSpec, chunks: list[Chunk], *, address: str, actors: int,
            depth_actors: int | None = None) -> Iterator[list[FrameResult]]:
    """The frames of ``chunks`` through Ray Data, results in order, in lists of up to a chunk's size.

    Parameters
    ----------
    spec : RunSpec
    chunks : list of Chunk
    address : str
        ``"auto"`` or a Ray cluster address.
    actors : int
        Monitor (CPU) actors.
    depth_actors : int or None
        Depth network actors (with ``spec.depth_model``): default one per GPU of the cluster,
        else one CPU actor.
    """
    ray = connect(address)
    _ordered(ray)
    if not chunks:
        return
    # the expansion asks for no CPU of its own: the actor pools may hold every CPU of a small
    # cluster, and a stage that waits for a free CPU before them would never run
    ds = ray.data.from_items([{"chunk": chunk} for chunk in chunks]).flat_map(_expand, num_cpus=0)
    if spec.depth_model is not None:
        gpus = int(ray.cluster_resources().get("GPU", 0))
        n = depth_actors if depth_actors is not None else max(1, gpus)
        ds = ds.map_batches(_DepthStage, fn_constructor_args=(spec.depth_model,),
                            batch_size=spec.depth_model.batch_size, batch_format="numpy",
                            compute=ray.data.ActorPoolStrategy(size=n), num_gpus=1 if gpus else 0, num_cpus=1)
    ds = ds.map_batches(_MonitorStage, fn_constructor_args=(dataclasses.replace(spec, depth_model=None),),
                        batch_size=CHUNK_FRAMES, batch_format="numpy",
                        compute=ray.data.ActorPoolStrategy(size=actors), num_cpus=1)
    for batch in ds.iter_batches(batch_size=CHUNK_FRAMES, batch_format="numpy"):
        yield list(batch["result"])
