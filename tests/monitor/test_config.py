"""The monitor's configuration: nested sections read from YAML, and every kind of bad file."""
from dataclasses import FrozenInstanceError, fields, is_dataclass

import numpy as np
import pytest
import yaml

from fuzzcore.strict_yaml import MAX_DEPTH
from monitor.alignment import check_thresholds
from monitor.config import (DEFAULT_CONFIG_PATH, AlignmentConfig, ConfigError, DetectionsConfig,
                            MonitorConfig, RetrievalConfig, RiskConfig, ShieldConfig, load_config)
from monitor.depth.geometric import GeometricParams
from monitor.depth.retrieval import RetrievalParams


def _write(tmp_path, text, name="config.yaml"):
    path = tmp_path / name
    path.write_text(text, encoding="utf-8")
    return path


def test_shipped_defaults_equal_the_code_defaults():
    # the YAML in the package and the dataclass defaults must not drift apart
    assert load_config() == MonitorConfig()


def _mirrors(shipped: dict, section) -> None:
    """Every field of ``section`` is a key of ``shipped`` with its value (sections within
    sections alike), except the inherited max_range below the top."""
    names = {g.name for g in fields(section)}
    if not isinstance(section, MonitorConfig):
        names -= {"max_range"}
    assert set(shipped) == names
    for name in names:
        value = getattr(section, name)
        if is_dataclass(value):
            _mirrors(shipped[name], value)
        else:
            assert shipped[name] == value, name


def test_the_sections_mirror_the_shipped_file():
    _mirrors(yaml.safe_load(DEFAULT_CONFIG_PATH.read_text(encoding="utf-8")), MonitorConfig())


def test_user_file_overrides_only_what_it_names(tmp_path):
    config = load_config(_write(tmp_path, "alignment: {alpha: 0.5}\n"
                                          "shield: {threshold: 0.6, release: 0.4, confirm_near_all: true}\n"
                                          "max_range: 30\nrisk:\n  fail_safe: 0.9\n"
                                          "retrieval: {paper: {depth_percentile: 5}, geometric: {stride: 2}}\n"))
    assert config.alignment == AlignmentConfig(alpha=0.5, beta=1.0, weighting="mean", matching="coverage",
                                                objects="known")
    assert config.shield == ShieldConfig(threshold=0.6, release=0.4, hold_frames=5, deceleration=3.0,
                                         path_half_width=1.25, confirm_near_all=True)
    assert config.risk == RiskConfig(fail_safe=0.9, no_objects=0.5)
    assert config.detections == DetectionsConfig()
    assert config.max_range == 30.0 and isinstance(config.max_range, float)
    # one range limit, everywhere
    assert config.retrieval.paper.max_range == config.retrieval.geometric.max_range == 30.0
    assert config.retrieval.paper.depth_percentile == 5.0 and config.retrieval.paper.canny_low == 40.0
    assert config.retrieval.method == "geometric"
    assert config.retrieval.geometric == GeometricParams(stride=2, max_range=30.0)


def test_the_shipped_file_holds_every_default_of_both_depth_views():
    defaults = load_config().retrieval
    assert defaults.paper == RetrievalParams() and defaults.geometric == GeometricParams()
    assert load_config().retrieval == RetrievalConfig()


def test_an_empty_file_is_the_defaults(tmp_path):
    assert load_config(_write(tmp_path, "# nothing changed\n")) == MonitorConfig()


@pytest.mark.parametrize("text, message", [
    ("alignment: {gamma: 1}\n", r"unknown key alignment\.gamma; expected one of alignment\.alpha, alignment\.beta"),
    ("colour: red\n", "unknown key colour"),
    ("retrieval: {max_range: 5}\n", r"unknown key retrieval\.max_range"),  # the top-level one rules
    ("retrieval: {paper: {max_range: 5}}\n", r"unknown key retrieval\.paper\.max_range"),
    ("retrieval: {method: stereo}\n", r"retrieval\.method = 'stereo', must be one of paper, geometric"),
    ("retrieval: {geometric: {stride: 0}}\n", r"retrieval\.geometric\.stride = 0, must be an integer >= 1"),
    ("retrieval: {downsample: 2}\n", r"unknown key retrieval\.downsample; expected one of retrieval\.method"),
    ("alignment: {alpha: 2}\n", r"alignment\.alpha = 2\.0, expected an IoU threshold in \[0, 1\]"),
    ("alignment: {beta: 0}\n", r"alignment\.beta = 0\.0"),
    ("alignment: {objects: all}\n", r"alignment\.objects = 'all', must be one of depth, known"),
    ("alignment: {weighting: inverse_distance}\n",
     r"alignment\.objects = 'known' with weighting = 'inverse_distance': .*\(weighting: mean\)"),
    ("shield: {threshold: 0.3, release: 0.4}\n", r"shield\.release = 0\.4 must be <= threshold = 0\.3"),
    ("shield: {hold_frames: 1.5}\n", r"shield\.hold_frames = 1\.5, must be an integer"),
    ("shield: {deceleration: -1}\n", r"shield\.deceleration = -1\.0, must be > 0"),
    ("shield: {confirm_near_all: 1}\n", r"shield\.confirm_near_all = 1, must be true or false"),
    ("risk: {fail_safe: '1.0'}\n", r"risk\.fail_safe = '1\.0', must be a number"),
    ("risk: {fail_safe: true}\n", r"risk\.fail_safe = True, must be a number"),
    ("risk: {no_objects: 1.5}\n", r"risk\.no_objects = 1\.5, must be in \[0, 1\]"),
    ("max_range: 1e3\n", r"max_range = '1e3', must be a number \(YAML 1\.1 reads .* write 1\.0e3\)"),
    ("max_range: -5\n", r"max_range = -5"),
    ("max_range: .inf\n", r"max_range = inf"),
    ("detections: {distance: nearest}\n", r"detections\.distance = 'nearest', must be one of camera_depth, ego_closest"),
    ("detections: {distance: 3}\n", r"detections\.distance = 3, must be text"),
    ("detections: {min_score: .nan}\n", r"detections\.min_score = nan, must be in \[0, 1\]"),
    ("retrieval: {paper: {downsample: 3}}\n", r"retrieval\.paper\.downsample = 3, must be one of"),
    ("retrieval: {paper: {blur_size: 5.0}}\n", r"retrieval\.paper\.blur_size = 5\.0, must be an integer"),
    ("retrieval: {paper: {full_scale: x}}\n", r"retrieval\.paper\.full_scale = 'x', must be a number"),
    ("shield: 0.5\n", r"shield = 0\.5, must be a mapping"),
    ("shield:\n", r"shield = None, must be a mapping"),
    ("- alignment\n", "expected a mapping of sections, got list"),
    ("alignment: {alpha: [0.3\n", "not a valid configuration"),
    ("risk:\n  fail_safe: 1.0\n  fail_safe: 0.0\n", r"line 3: .*duplicate key 'fail_safe' \(first at line 2\)"),
    ("max_range: 20\nalignment: {}\nmax_range: 30\n", r"line 3: .*duplicate key 'max_range'"),
    ("a: !!python/object/apply:os.system [echo hi]\n", "not a valid configuration"),
])
def test_bad_files_name_the_file_and_the_key(tmp_path, text, message):
    path = _write(tmp_path, text)
    with pytest.raises(ConfigError, match=message) as err:
        load_config(path)
    assert str(err.value).startswith(str(path))


def test_deep_nesting_is_an_error_not_a_recursion_error(tmp_path):
    path = _write(tmp_path, "alignment: " + "[" * 5000 + "]" * 5000 + "\n")  # 10 kB
    with pytest.raises(ConfigError, match=f"line 1: not a valid configuration: lists or mappings nested more than {MAX_DEPTH} levels"):
        load_config(path)
    path = _write(tmp_path, "x: " + "{a: " * 3000 + "1" + "}" * 3000 + "\n")
    with pytest.raises(ConfigError, match="nested more than"):
        load_config(path)


def test_files_that_are_not_utf8_yaml(tmp_path):
    path = tmp_path / "binary.yaml"
    path.write_bytes(b"risk: {fail_safe: \xff\xfe}\n")
    with pytest.raises(ConfigError, match=r"binary\.yaml: not UTF-8 text \(byte 18"):
        load_config(path)
    with pytest.raises(FileNotFoundError, match="no such configuration file"):
        load_config(tmp_path / "missing.yaml")


def test_alignment_limits_have_one_owner():
    # the configuration accepts exactly what align() accepts
    for alpha, beta in [(0.0, 1e-9), (1.0, 5.0), (0.3, 0.2)]:
        assert (AlignmentConfig(alpha, beta).alpha, AlignmentConfig(alpha, beta).beta) == check_thresholds(alpha, beta)
    for alpha, beta in [(-0.1, 0.2), (1.1, 0.2), (0.3, 0.0), (0.3, np.inf), (np.nan, 0.2), ("0.3", 0.2)]:
        with pytest.raises(ValueError) as from_align:
            check_thresholds(alpha, beta)
        with pytest.raises(ValueError) as from_config:
            AlignmentConfig(alpha, beta)
        assert str(from_align.value) == str(from_config.value)


def test_sections_are_frozen_and_checked_when_built_in_code():
    with pytest.raises(FrozenInstanceError):
        MonitorConfig().max_range = 3.0
    with pytest.raises(ValueError, match="retrieval is a dict, expected a RetrievalConfig"):
        MonitorConfig(retrieval={"downsample": 1})
    with pytest.raises(ValueError, match="paper is a dict, expected a RetrievalParams"):
        RetrievalConfig(paper={"downsample": 1})
    config = MonitorConfig(max_range=35, retrieval=RetrievalConfig(paper=RetrievalParams(downsample=1)))
    assert config.retrieval.paper == RetrievalParams(downsample=1, max_range=35.0)
    assert config.retrieval.geometric == GeometricParams(max_range=35.0)
    assert ShieldConfig(hold_frames=np.int64(3)).hold_frames == 3  # numpy integers are integers
    assert type(ShieldConfig(hold_frames=np.int64(3)).hold_frames) is int
    with pytest.raises(ValueError, match="threshold = '0.5', must be a number"):
        ShieldConfig(threshold="0.5")
    with pytest.raises(ValueError, match="hold_frames = True"):
        ShieldConfig(hold_frames=True)
