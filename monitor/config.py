"""The monitor's configuration: one YAML file, defaults shipped in the package.

:func:`load_config` reads ``monitor/default_config.yaml`` and overlays a user file that
names only what it changes. Unknown keys, wrong types and values out of range are errors
naming the file and the key.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field, fields, replace
from pathlib import Path
from typing import Any

import yaml

from monitor.alignment import DEFAULT_ALPHA, DEFAULT_BETA
from monitor.geometry.boxes import DEFAULT_RANGE_M
from monitor.depth.retrieval import RetrievalParams

DEFAULT_CONFIG_PATH = Path(__file__).with_name("default_config.yaml")
DISTANCE_MODES = ("camera_depth", "ego_closest")


def _unit(value: float, name: str) -> None:
    if not (math.isfinite(value) and 0.0 <= value <= 1.0):
        raise ValueError(f"{name} = {value!r}, must be in [0, 1]")


@dataclass(frozen=True)
class ShieldConfig:
    """See :class:`monitor.shield.Shield`."""

    threshold: float = 0.5
    release: float = 0.5
    hold_frames: int = 0
    deceleration: float = 3.0

    def __post_init__(self):
        _unit(self.threshold, "shield.threshold")
        _unit(self.release, "shield.release")
        if self.release > self.threshold:
            raise ValueError(f"shield.release = {self.release} must be <= shield.threshold = {self.threshold}")
        if isinstance(self.hold_frames, bool) or not isinstance(self.hold_frames, int) or self.hold_frames < 0:
            raise ValueError(f"shield.hold_frames = {self.hold_frames!r}, must be an integer >= 0")
        if not (math.isfinite(self.deceleration) and self.deceleration > 0):
            raise ValueError(f"shield.deceleration = {self.deceleration!r}, must be > 0 m/s^2")


@dataclass(frozen=True)
class MonitorConfig:
    """Every tunable of :class:`monitor.RiskMonitor`.

    Attributes
    ----------
    alpha, beta : float
        Matching thresholds: a pair counts if IoU > alpha and |RDD| < beta.
    max_range : float
        Metres; S (and G in evaluation) beyond it are ignored.
    min_score : float
        Detections scoring below it are dropped before projection.
    distance : {"camera_depth", "ego_closest"}
        How a detection's d is measured (see :func:`monitor.geometry.camera.project_boxes`).
    retrieval : RetrievalParams
        The depth view's parameters; its ``max_range`` always equals ``max_range`` here.
    fail_safe_risk : float
        Risk of an invalid frame (safe default 1.0).
    no_objects_risk : float
        Risk when the depth view finds no safety-critical object in range.
    shield : ShieldConfig
    """

    alpha: float = DEFAULT_ALPHA
    beta: float = DEFAULT_BETA
    max_range: float = DEFAULT_RANGE_M
    min_score: float = 0.3
    distance: str = "camera_depth"
    retrieval: RetrievalParams = field(default_factory=RetrievalParams)
    fail_safe_risk: float = 1.0
    no_objects_risk: float = 0.0
    shield: ShieldConfig = field(default_factory=ShieldConfig)

    def __post_init__(self):
        if not (math.isfinite(self.alpha) and 0.0 <= self.alpha < 1.0):
            raise ValueError(f"alignment.alpha = {self.alpha!r}, must be in [0, 1)")
        if not (math.isfinite(self.beta) and 0.0 < self.beta <= 1.0):
            raise ValueError(f"alignment.beta = {self.beta!r}, must be in (0, 1]")
        if not (math.isfinite(self.max_range) and self.max_range > 0):
            raise ValueError(f"max_range = {self.max_range!r}, must be a finite number of metres > 0")
        _unit(self.min_score, "detections.min_score")
        if self.distance not in DISTANCE_MODES:
            raise ValueError(f"detections.distance = {self.distance!r}, must be one of {DISTANCE_MODES}")
        _unit(self.fail_safe_risk, "risk.fail_safe")
        _unit(self.no_objects_risk, "risk.no_objects")
        if self.retrieval.max_range != self.max_range:
            object.__setattr__(self, "retrieval", replace(self.retrieval, max_range=self.max_range))


# YAML section -> {key: MonitorConfig attribute}; None marks a nested dataclass section
_LAYOUT = {
    "alignment": {"alpha": "alpha", "beta": "beta"},
    "max_range": "max_range",
    "detections": {"min_score": "min_score", "distance": "distance"},
    "retrieval": None,
    "risk": {"fail_safe": "fail_safe_risk", "no_objects": "no_objects_risk"},
    "shield": None,
}
_NESTED = {"retrieval": RetrievalParams, "shield": ShieldConfig}


def _read(path: Path) -> dict:
    try:
        data = yaml.safe_load(path.read_text(encoding="utf-8"))
    except yaml.YAMLError as exc:
        raise ValueError(f"{path}: not valid YAML: {exc}") from None
    if data is None:
        return {}
    if not isinstance(data, dict):
        raise ValueError(f"{path}: expected a mapping of sections, got {type(data).__name__}")
    return data


def _merge(base: dict, update: dict, path: Path) -> dict:
    merged = {k: (dict(v) if isinstance(v, dict) else v) for k, v in base.items()}
    for key, value in update.items():
        if key not in _LAYOUT:
            raise ValueError(f"{path}: unknown key {key!r}; expected one of {', '.join(_LAYOUT)}")
        if isinstance(merged.get(key), dict):
            if not isinstance(value, dict):
                raise ValueError(f"{path}: {key} must be a mapping, got {value!r}")
            unknown = sorted(set(value) - set(merged[key]))
            if unknown:
                raise ValueError(f"{path}: unknown key(s) {key}.{', '.join(unknown)}; "
                                 f"expected {', '.join(sorted(merged[key]))}")
            merged[key].update(value)
        else:
            merged[key] = value
    return merged


def _number(value: Any, where: str) -> Any:
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise ValueError(f"{where} = {value!r}, must be a number")
    return value


def load_config(path: str | Path | None = None) -> MonitorConfig:
    """The shipped defaults, overlaid with the file at ``path`` when given."""
    data = _read(DEFAULT_CONFIG_PATH)
    source = DEFAULT_CONFIG_PATH
    if path is not None:
        source = Path(path)
        if not source.is_file():
            raise FileNotFoundError(f"{source}: no such configuration file")
        data = _merge(data, _read(source), source)
    kwargs: dict[str, Any] = {}
    try:
        for section, layout in _LAYOUT.items():
            value = data[section]
            if layout is None:
                cls = _NESTED[section]
                names = {f.name for f in fields(cls)}
                unknown = sorted(set(value) - names)
                if unknown:
                    raise ValueError(f"unknown key(s) {section}.{', '.join(unknown)}")
                kwargs[section] = cls(**value)
            elif isinstance(layout, str):
                kwargs[layout] = _number(value, section)
            else:
                for key, attr in layout.items():
                    v = value[key]
                    kwargs[attr] = v if isinstance(v, str) else _number(v, f"{section}.{key}")
        return MonitorConfig(**kwargs)
    except (ValueError, TypeError) as exc:
        raise ValueError(f"{source}: {exc}") from None
