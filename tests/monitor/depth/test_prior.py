"""The streaming inverse-depth prior and `fuzzrisk prior build`."""
from __future__ import annotations

import argparse
import tracemalloc

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from monitor.cli import prior as prior_command
from monitor.depth.files import save_depth_png
from monitor.depth.prior import InverseDepthPrior, build_prior, check_prior, load_prior, save_prior


def _frames(n, shape=(5, 7), seed=0, invalid_share=0.2):
    rng = np.random.default_rng(seed)
    frames = []
    for _ in range(n):
        depth = rng.uniform(1.0, 60.0, size=shape).astype(np.float32)
        holes = rng.random(shape) < invalid_share
        depth[holes] = rng.choice(np.array([np.nan, np.inf, 0.0, -3.0], np.float32), size=int(holes.sum()))
        frames.append(depth)
    return frames


def _reference(frames):
    """Slow and obvious: per pixel, the mean of 1/d over the frames where d is valid."""
    height, width = frames[0].shape
    out = np.full((height, width), np.nan)
    for i in range(height):
        for j in range(width):
            values = [1.0 / float(f[i, j]) for f in frames if np.isfinite(f[i, j]) and f[i, j] > 0]
            if values:
                out[i, j] = sum(values) / len(values)
    return out


@given(st.integers(1, 12), st.integers(0, 2**31 - 1), st.floats(0.0, 0.9))
def test_mean_over_valid_samples_matches_the_slow_reference(n, seed, share):
    frames = _frames(n, seed=seed, invalid_share=share)
    acc = build_prior((f"f{k}", d) for k, d in enumerate(frames))
    prior = acc.mean()
    assert prior.dtype == np.float32 and acc.n_frames == n
    expected = _reference(frames)
    np.testing.assert_array_equal(np.isnan(prior), np.isnan(expected))
    np.testing.assert_allclose(prior, expected, rtol=1e-6, equal_nan=True)
    valid_counts = sum((np.isfinite(f) & (f > 0)).astype(int) for f in frames)
    np.testing.assert_array_equal(acc.count, valid_counts)


def test_a_pixel_never_valid_is_nan_and_a_hole_does_not_pull_the_mean_down():
    a = np.array([[2.0, np.nan]], np.float32)
    b = np.array([[np.nan, 0.0]], np.float32)
    c = np.array([[4.0, -1.0]], np.float32)
    prior = build_prior([("a", a), ("b", b), ("c", c)]).mean()
    assert prior[0, 0] == pytest.approx((1 / 2 + 1 / 4) / 2)  # the NaN of b is not a sample
    assert np.isnan(prior[0, 1])


def test_memory_does_not_grow_with_frames():
    shape = (120, 160)
    acc = InverseDepthPrior()
    for depth in _frames(3, shape):
        acc.add(depth)
    more = _frames(20, shape, seed=1)  # 20 frames of 120 * 160 * 4 = 76,800 bytes
    tracemalloc.start()
    try:
        before = tracemalloc.get_traced_memory()[0]
        for depth in more:
            acc.add(depth)
        grown = tracemalloc.get_traced_memory()[0] - before
    finally:
        tracemalloc.stop()
    assert grown < more[0].nbytes  # accumulated in place: not even one frame kept


def test_size_mismatch_names_the_frame():
    frames = [("good", np.ones((4, 6), np.float32)), ("bad.png", np.ones((5, 6), np.float32))]
    with pytest.raises(ValueError, match=r"bad.png: depth map is 6x5 \(W x H\), the prior is 6x4"):
        build_prior(frames)


def test_wrong_kind_of_map_and_no_frames():
    with pytest.raises(ValueError, match="f: shape .*expected a floating-point"):
        InverseDepthPrior().add(np.ones((4, 6), np.uint16), name="f")
    with pytest.raises(ValueError, match="no depth maps given"):
        build_prior([])
    with pytest.raises(ValueError, match="no frames yet"):
        InverseDepthPrior().mean()


def test_save_load_round_trip_and_checks(tmp_path):
    prior = build_prior([("a", _frames(1)[0])]).mean()
    save_prior(tmp_path / "p.npy", prior)
    np.testing.assert_array_equal(load_prior(tmp_path / "p.npy"), prior)
    with pytest.raises(FileNotFoundError, match="fuzzrisk prior build"):
        load_prior(tmp_path / "none.npy")
    with pytest.raises(ValueError, match=r"first at row, col \(0, 1\): -0.2\d*, inf or negative"):
        check_prior(np.array([[0.1, -0.2]], np.float32))
    with pytest.raises(ValueError, match="expected a floating-point"):
        check_prior(np.ones((3,), np.float32))


def _run_cli(argv):
    parser = argparse.ArgumentParser()
    prior_command.add_arguments(parser)
    return prior_command.run(parser.parse_args(argv))


def test_cli_build_from_a_mixed_folder(tmp_path, capsys):
    frames = _frames(4, shape=(6, 8), seed=5)
    folder = tmp_path / "depth"
    folder.mkdir()
    for k, depth in enumerate(frames[:3]):
        np.save(folder / f"{k:04d}.npy", depth)
    png = np.where(np.isfinite(frames[3]) & (frames[3] > 0), frames[3], np.nan).astype(np.float32)
    save_depth_png(folder / "0003.png", png)
    out = tmp_path / "prior.npy"
    assert _run_cli(["build", str(folder), "-o", str(out)]) == 0
    stored = frames[:3] + [np.round(png * 256) / 256]  # the PNG stores 1/256 m steps
    np.testing.assert_allclose(np.load(out), _reference(stored), rtol=1e-6, equal_nan=True)
    assert "prior of 4 frames (8x6)" in capsys.readouterr().out


def test_cli_refuses_mismatched_sizes_and_empty_folders(tmp_path):
    folder = tmp_path / "depth"
    folder.mkdir()
    with pytest.raises(ValueError, match="no depth maps"):
        _run_cli(["build", str(folder), "-o", str(tmp_path / "p.npy")])
    np.save(folder / "a.npy", np.ones((4, 4), np.float32))
    np.save(folder / "b.npy", np.ones((4, 5), np.float32))
    with pytest.raises(ValueError, match=r"b.npy: depth map is 5x4"):
        _run_cli(["build", str(folder), "-o", str(tmp_path / "p.npy")])
    assert not (tmp_path / "p.npy").exists()


def test_cli_is_registered(tmp_path, capsys):
    from monitor import cli

    folder = tmp_path / "depth"
    folder.mkdir()
    np.save(folder / "a.npy", np.full((2, 3), 4.0, np.float32))
    assert cli.main(["prior", "build", str(folder), "-o", str(tmp_path / "p.npy")]) == 0
    np.testing.assert_allclose(np.load(tmp_path / "p.npy"), 0.25)
    assert cli.main(["prior", "build", str(tmp_path / "missing"), "-o", str(tmp_path / "q.npy")]) == 2
    assert "missing does not exist" in capsys.readouterr().err
