"""Ray Data gives the local results in the local order (a local Ray instance, 2 CPUs)."""
import importlib.util

import numpy as np
import pytest

from monitor.cli import main
from monitor.offline.ray_backend import check_address
from recording_fixture import mean_model, read_rows, write_images, write_prior, write_recording

pytestmark = pytest.mark.skipif(
    importlib.util.find_spec("ray") is None or importlib.util.find_spec("pyarrow") is None,
    reason="Ray with Ray Data is not installed (optional extra: pip install -e '.[ray]')")


@pytest.fixture(scope="module")
def ray_instance():
    import ray
    ray.init(num_cpus=2, include_dashboard=False, log_to_driver=False)
    yield ray
    ray.shutdown()


@pytest.fixture(scope="module")
def recording(tmp_path_factory):
    root = tmp_path_factory.mktemp("rayrec")
    frames = write_recording(root / "drive", n_frames=10)
    write_recording(root / "short", condition="night", seed=8, n_frames=2)
    return root, write_prior(root / "prior.npy", frames)


def test_ray_and_local_give_the_same_reports_in_the_same_order(ray_instance, recording, tmp_path):
    root, prior = recording
    argv = ["monitor", "--recording", str(root / "drive"), str(root / "short"), "--prior", str(prior)]
    assert main(argv + ["-o", str(tmp_path / "local")]) == 0
    assert main(argv + ["-o", str(tmp_path / "ray"), "--ray", "auto", "--workers", "2"]) == 0
    local, on_ray = read_rows(tmp_path / "local"), read_rows(tmp_path / "ray")
    assert list(on_ray) == ["drive.jsonl", "short.jsonl"] and len(on_ray["drive.jsonl"]) == 10
    assert on_ray == local


def test_depth_network_stage_on_ray_equals_local(ray_instance, tmp_path):
    frames = write_recording(tmp_path / "cam", n_frames=3, depth=False)
    write_images(tmp_path / "cam", frames)
    argv = ["monitor", "--recording", str(tmp_path / "cam"), "--prior", str(write_prior(tmp_path / "p.npy", frames)),
            "--depth-model", str(mean_model(tmp_path / "m.onnx")), "--depth-batch", "2", "--depth-device", "cpu"]
    assert main(argv + ["-o", str(tmp_path / "local")]) == 0
    assert main(argv + ["-o", str(tmp_path / "ray"), "--ray", "auto"]) == 0
    assert read_rows(tmp_path / "ray") == read_rows(tmp_path / "local")


def test_eval_features_on_ray_equal_local(ray_instance, recording, tmp_path):
    root, prior = recording
    argv = ["features", "--split", "all", "--recording", str(root / "drive"), "--prior", str(prior)]
    assert main(argv + ["-o", str(tmp_path / "local.csv")]) == 0
    assert main(argv + ["-o", str(tmp_path / "ray.csv"), "--ray", "auto"]) == 0
    assert (tmp_path / "ray.csv").read_text() == (tmp_path / "local.csv").read_text()


def test_prior_on_ray_equals_local(ray_instance, tmp_path):
    rng = np.random.default_rng(1)
    depth = tmp_path / "depth"
    depth.mkdir()
    for k in range(40):
        np.save(depth / f"{k:03d}.npy", rng.uniform(2.0, 50.0, size=(4, 5)).astype(np.float32))
    assert main(["prior", "build", str(depth), "-o", str(tmp_path / "a.npy")]) == 0
    assert main(["prior", "build", str(depth), "-o", str(tmp_path / "b.npy"), "--ray", "auto",
                 "--workers", "2"]) == 0
    np.testing.assert_array_equal(np.load(tmp_path / "a.npy"), np.load(tmp_path / "b.npy"))


def test_an_address_that_does_not_answer_is_named():
    with pytest.raises(ValueError, match="--ray 127.0.0.1:1: no Ray cluster answers there"):
        check_address("127.0.0.1:1")
    with pytest.raises(ValueError, match="--ray 'head-node': expected 'auto' or a cluster address HOST:PORT"):
        check_address("head-node")
