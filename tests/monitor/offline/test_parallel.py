"""ordered_map on a process pool, and the prior built in parts on several workers."""
import numpy as np
import pytest

from monitor.cli import main
from monitor.depth.prior import PRIOR_PART_FILES, load_prior, prior_of_files
from monitor.offline.parallel import ordered_map


class Square:
    """A spec: build() gives the function (here: x -> x * x, with the worker's state)."""

    def build(self):
        return lambda x: x * x


class Broken:
    def build(self):
        raise ValueError("model.onnx: cannot be loaded")


def test_a_pool_gives_the_results_in_order():
    items = list(range(23))
    assert list(ordered_map(Square(), items, workers=2)) == [x * x for x in items]
    assert list(ordered_map(Square(), items)) == [x * x for x in items]


def test_a_worker_that_cannot_start_raises_its_error_once():
    with pytest.raises(ValueError, match="model.onnx: cannot be loaded"):
        list(ordered_map(Broken(), [1, 2, 3], workers=2))


def test_an_error_or_an_early_stop_ends_the_pool_without_terminating_it(monkeypatch):
    """Pool.terminate() may kill a worker while it holds the result queue's lock, and the pool
    then waits forever (CPython issue #96995): the pool is closed and joined instead."""
    import multiprocessing.pool
    terminated = []
    monkeypatch.setattr(multiprocessing.pool.Pool, "terminate", lambda pool: terminated.append(pool))
    with pytest.raises(ValueError, match="model.onnx: cannot be loaded"):
        list(ordered_map(Broken(), range(10), workers=2))
    squares = ordered_map(Square(), range(100), workers=2)
    assert [next(squares) for _ in range(3)] == [0, 1, 4]
    squares.close()  # a consumer that stops early
    assert terminated == []


@pytest.mark.parametrize("workers", [0, -1, 1.5, True])
def test_workers_must_be_a_positive_count(workers):
    with pytest.raises(ValueError, match=f"--workers {workers!r}: expected an integer >= 1"):
        list(ordered_map(Square(), [1], workers=workers))


@pytest.fixture(scope="module")
def depth_files(tmp_path_factory):
    folder = tmp_path_factory.mktemp("depth")
    rng = np.random.default_rng(7)
    n = 2 * PRIOR_PART_FILES + 5  # three parts
    maps = rng.uniform(1.0, 60.0, size=(n, 6, 8)).astype(np.float32)
    maps[rng.random(maps.shape) < 0.1] = np.nan  # invalid pixels are not samples
    for k, m in enumerate(maps):
        np.save(folder / f"{k:04d}.npy", m)
    return folder, maps


def test_the_prior_of_parts_on_two_workers_is_the_serial_prior_bit_for_bit(depth_files):
    folder, maps = depth_files
    paths = sorted(folder.glob("*.npy"))
    serial = prior_of_files(paths, 256.0)
    pooled = prior_of_files(paths, 256.0, workers=2)
    assert serial.n_frames == pooled.n_frames == len(maps)
    np.testing.assert_array_equal(serial.mean(), pooled.mean())
    np.testing.assert_array_equal(serial.count, np.isfinite(maps).sum(axis=0))
    # the reference: the mean of 1/D over the valid samples, in float64
    with np.errstate(divide="ignore"):
        expected = np.nanmean(1.0 / maps.astype(np.float64), axis=0)
    np.testing.assert_allclose(serial.mean(), expected, rtol=1e-6)


def test_prior_build_command_takes_workers(depth_files, tmp_path):
    folder, _ = depth_files
    assert main(["prior", "build", str(folder), "-o", str(tmp_path / "a.npy")]) == 0
    assert main(["prior", "build", str(folder), "-o", str(tmp_path / "b.npy"), "--workers", "2"]) == 0
    np.testing.assert_array_equal(load_prior(tmp_path / "a.npy"), load_prior(tmp_path / "b.npy"))
