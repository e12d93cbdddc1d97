"""The monitor's configuration: one YAML file, defaults shipped in the package.

The configuration is a tree of frozen dataclasses that mirrors the YAML file: one class
per section (``alignment``, ``detections``, ``retrieval`` with one subsection per depth
view, ``visibility``, ``risk``, ``shield``) and the scalars at the top (``max_range``).
:func:`load_config` reads ``monitor/default_config.yaml`` and overlays a user file that
names only what it changes; the file's keys are read generically from the dataclasses'
fields and types, so a new field is a new key with nothing else to keep in step. A section's field that has the name of a
top-level field (``retrieval.paper.max_range``) is not a key of its own: it takes the
top-level value, so one range limit holds everywhere.

Errors are :class:`ConfigError` naming the file and the key path
(``risk.fail_safe = '1.0', must be a number``). Duplicate keys, unknown keys, wrong types,
values out of range and nesting deeper than :data:`fuzzcore.strict_yaml.MAX_DEPTH` are errors
(the file is read by :func:`fuzzcore.strict_yaml.load`, as rule files are).
"""
from __future__ import annotations

import math
import numbers
import types
import typing
from dataclasses import dataclass, field, fields, is_dataclass, replace
from pathlib import Path
from typing import Any

from fuzzcore import strict_yaml
from monitor.alignment import (DEFAULT_ALPHA, check_matching, check_objects, check_thresholds,
                               check_weighting)
from monitor.depth.geometric import GeometricParams
from monitor.depth.retrieval import RetrievalParams
from monitor.depth.visibility import VisibilityParams
from monitor.geometry.boxes import DEFAULT_RANGE_M
from monitor.geometry.camera import DISTANCES

DEFAULT_CONFIG_PATH = Path(__file__).with_name("default_config.yaml")


class ConfigError(ValueError):
    """A configuration file or value that cannot be used; the message names file and key."""


def _number(value: Any, name: str) -> float:
    """``value`` as a float, or a ValueError naming ``name`` (bool and str are not numbers)."""
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        hint = ""
        if isinstance(value, str):
            try:
                float(value)
                hint = " (YAML 1.1 reads a number without a dot, such as 1e3, as text: write 1.0e3)"
            except ValueError:
                pass
        raise ValueError(f"{name} = {value!r}, must be a number{hint}")
    return float(value)


def _unit(value: Any, name: str) -> float:
    value = _number(value, name)
    if not 0.0 <= value <= 1.0:
        raise ValueError(f"{name} = {value!r}, must be in [0, 1]")
    return value


def _set(obj, name: str, value: Any) -> None:
    object.__setattr__(obj, name, value)


@dataclass(frozen=True)
class AlignmentConfig:
    """How S meets P (``matching``, one of :data:`monitor.alignment.MATCHINGS`), the
    thresholds alpha and beta (their meaning per matching: :func:`monitor.alignment.align`),
    how the per-object terms become IoU~ and RDD~ (``weighting``, one of
    :data:`monitor.alignment.WEIGHTINGS`) and which objects they run over (``objects``, one
    of :data:`monitor.alignment.OBJECTS`; the detections within the configuration's
    ``max_range`` with ``"known"``).

    The rules for their values are :func:`monitor.alignment.check_thresholds`,
    :func:`monitor.alignment.check_weighting`, :func:`monitor.alignment.check_matching`
    and :func:`monitor.alignment.check_objects`.
    """

    alpha: float = DEFAULT_ALPHA
    beta: float = 1.0
    weighting: str = "mean"
    matching: str = "coverage"
    objects: str = "known"

    def __post_init__(self):
        alpha, beta = check_thresholds(self.alpha, self.beta)
        _set(self, "alpha", alpha)
        _set(self, "beta", beta)
        check_weighting(self.weighting)
        check_matching(self.matching)
        check_objects(self.objects, self.weighting)


@dataclass(frozen=True)
class DetectionsConfig:
    """How the detector's 3D boxes become P.

    Attributes
    ----------
    min_score : float in [0, 1]
        Detections scoring below it are dropped before projection.
    distance : str
        How a detection's d is measured, one of :data:`monitor.geometry.camera.DISTANCES`
        (see :func:`monitor.geometry.camera.project_boxes`).
    """

    min_score: float = 0.3
    distance: str = "camera_depth"

    def __post_init__(self):
        _set(self, "min_score", _unit(self.min_score, "min_score"))
        if self.distance not in DISTANCES:
            raise ValueError(f"distance = {self.distance!r}, must be one of {', '.join(DISTANCES)}")


#: the depth views ``retrieval.method`` can name
RETRIEVAL_METHODS = ("paper", "geometric")


@dataclass(frozen=True)
class RetrievalConfig:
    """The depth view: which one, and each one's parameters.

    Attributes
    ----------
    method : str
        One of :data:`RETRIEVAL_METHODS`: ``paper`` (the paper's retrieval,
        :mod:`monitor.depth.retrieval`) or ``geometric`` (objects on the road in the
        driving corridor, :mod:`monitor.depth.geometric`).
    max_range : float
        Metres; set from the top-level ``max_range`` (not a key), passed on to both views.
    paper : RetrievalParams
    geometric : GeometricParams
    """

    method: str = "geometric"
    max_range: float = DEFAULT_RANGE_M
    paper: RetrievalParams = field(default_factory=RetrievalParams)
    geometric: GeometricParams = field(default_factory=GeometricParams)

    def __post_init__(self):
        if self.method not in RETRIEVAL_METHODS:
            raise ValueError(f"method = {self.method!r}, must be one of {', '.join(RETRIEVAL_METHODS)}")
        for name, kind in (("paper", RetrievalParams), ("geometric", GeometricParams)):
            value = getattr(self, name)
            if not isinstance(value, kind):
                raise ValueError(f"{name} is a {type(value).__name__}, expected a {kind.__name__}")
            if value.max_range != self.max_range:
                _set(self, name, replace(value, max_range=self.max_range))


@dataclass(frozen=True)
class RiskConfig:
    """Risks the monitor reports without the rule base.

    Attributes
    ----------
    fail_safe : float in [0, 1]
        Risk of an invalid frame (safe default 1.0).
    no_objects : float in [0, 1]
        Risk when the depth view finds no safety-critical object in range.
    no_view : float in [0, 1]
        Risk of a frame the depth view cannot see through (blocked, no ground, a hidden
        region: :mod:`monitor.depth.visibility`); safe default 1.0.
    no_rule_fired : float in [0, 1]
        Risk when no rule of the rule base fired for the frame's features (the rule base
        has no answer there); safe default 1.0.
    """

    fail_safe: float = 1.0
    no_objects: float = 0.5
    no_view: float = 1.0
    no_rule_fired: float = 1.0

    def __post_init__(self):
        for name in ("fail_safe", "no_objects", "no_view", "no_rule_fired"):
            _set(self, name, _unit(getattr(self, name), name))


@dataclass(frozen=True)
class ShieldConfig:
    """The shield's settings (see :class:`monitor.shield.Shield`).

    Attributes
    ----------
    threshold : float in [0, 1]
        Engage when the risk is above it (the paper's: 0.5).
    release : float in [0, threshold]
        Disengage when the risk is at or below it (``release == threshold``: no hysteresis).
    hold_frames : int >= 0
        Frames to stay engaged after the last frame above ``threshold``.
    deceleration : float > 0
        Requested deceleration while engaged, m/s^2.
    path_half_width : float > 0 or None
        None: the paper's shield (with ``walker_horizon`` None, which needs a path gate),
        the risk alone decides. A number (metres): the risk engages the shield only while a
        depth-view object no detection covers stands in the ego's path (laterally within
        this of the ego's centreline) within its reach (:meth:`monitor.shield.Shield.reach`);
        frames without a view are not gated.
    headway : float >= 0
        Seconds of travel the reach adds to the braking distance (the delay from frame to
        brakes, and then some).
    margin : float >= 0
        Metres the reach adds beyond that.
    front : float >= 0
        Metres from the ego origin (nuScenes': the rear axle) to the front bumper, where the
        reach starts.
    confirm_frames : int >= 1
        With a path gate: an unseen object narrower than ``confirm_width`` counts (engages
        the shield, and the hold) only once confirmed: it stood where it stands (a standing
        object, the ego's travel allowed for) in this many of the last ``confirm_window``
        frames, this one included (1: every object counts at once).
    confirm_window : int >= confirm_frames
        See ``confirm_frames``.
    confirm_width : float >= 0 or None
        Metres: the lateral span (:attr:`monitor.RiskReport.unseen`'s ``y_max - y_min``)
        under which an unseen object must be confirmed; None: every object must be.
    emergency : float > deceleration, or None
        With a path gate, a second stage (m/s^2): an unseen object within the *emergency
        reach* (the braking distance at this deceleration, plus headway and margin) counts
        at once, whatever its width beyond ``confirm_width``, and the shield requests this
        deceleration; beyond it, within the reach, every object counts only once confirmed
        and the shield requests ``deceleration``. None: one stage, wide objects count at
        once anywhere in the reach.
    confirm_near : float >= 0 or None
        With a path gate that confirms: metres ahead of the front bumper within which every
        unseen object counts only once confirmed, whatever its width. A camera sees the road
        from some distance ahead of the bumper (nuScenes' front camera from 2.5 m, its lowest
        row); what stands nearer reaches into the image's bottom rows, where the depth view
        cannot see the road beneath it, and a standing obstacle there was in view in the
        frame before. None: no such zone.
    confirm_near_all : bool
        With ``confirm_near`` and ``confirm_contact``: an object within ``confirm_near`` that
        floats counts once it floated where it stands in every one of the last
        ``confirm_window`` frames (True), not ``confirm_frames`` of them (False, the
        default). The blobs of the depth in the image's bottom rows float, each in a new
        place: one floats where one of the two frames before had another by chance, in both
        of them rarely. What stands there (a walker stepping in, an obstacle) is confirmed
        as before. Measured on the pedestrian and hazard-free kinds only
        (``docs/closed-loop.md``, eighteenth entry): an option, off.
    confirm_edge : float >= 0 or None
        With a path gate that confirms: metres; an unseen object whose span reaches less than
        this into the path (the part of ``y_min, y_max`` within ``path_half_width`` of the
        centreline) counts only once confirmed, whatever its width. Such an edge lies in the
        margin the path adds to the car's half width, beside the car's body. None: not asked.
    confirm_emerged : float in [0, 1] or None
        With a path gate that confirms: an unseen object of which at least this share of
        the blocks stood where each of the last two frames saw through to the road beyond
        (:meth:`monitor.RiskMonitor.emerged`, the geometric view's rule 9) counts only once
        confirmed, wherever it stands. Something standing on the road was in view a frame
        before (or hidden, or beside its place); a patch of road the depth reads too near
        comes out of the road. 0.8 by default (``docs/closed-loop.md``, seventeenth entry of
        29 November 2026); None: not asked. The paper's view does not see the road: its
        objects are not measured (NaN), and what is not measured is not asked. The geometric
        view keeps each frame's blocks for it only when it is set.
    confirm_contact : float in [0, 1] or None
        With a path gate that confirms: an unseen object that stands on the road (or on
        something in front of it) in fewer than this share of its columns
        (:attr:`monitor.RiskReport.unseen_contact`, the geometric view's rule 5) counts only
        once confirmed, wherever it stands, and a sighting that floats confirms only one that
        floats (one that stands, or cannot tell, only one that stands or cannot tell). What
        stands on the road meets it along its width; a blob of the depth read too near in one
        frame floats, and is no evidence that the patch read too near at the image's bottom
        edge in the next frame stands there. The paper's view does not measure it (NaN), and
        what is not measured does not float. None: not asked.
    memory : float > 0 or None
        With a path gate, seconds the shield remembers where the unseen objects that engaged
        it stand (on the road, the ego's travel allowed for). An unseen object seen where a
        remembered one stands (:func:`monitor.shield.consistent`) renews it there; once
        sighted again, a remembered object that lies in the path within reach keeps the
        shield engaged (or engages it again) whatever the frame shows. One not sighted for
        this long is forgotten. None: no memory, the hold alone keeps the shield engaged.
    walker_horizon : float > 0 or None
        With a path gate, seconds: a walker the detector reports (:mod:`monitor.walkers`,
        tracked on the road) who walks towards the path from beside it and, at her lateral
        speed, reaches its edge (her half width beside it) within the time the car needs to
        reach her or this horizon, whichever is sooner, engages the shield whatever the risk
        when she stands within reach (``emergency`` within the emergency reach). The shield
        then needs each frame's walkers (:meth:`monitor.shield.Shield.update`). None: no
        walker gate.
    unseen_walkers : float >= 0 or None
        With the walker gate, metres: an unseen object no wider than this that stands on the
        road (its contact, :attr:`monitor.RiskReport.unseen_contact`, at least
        :data:`monitor.walkers.STANDING_CONTACT`), beyond ``confirm_near`` of the bumper, is
        followed as a walker too (:class:`monitor.walkers.SightingTracks`), and engages the
        shield as a detected one does: a walker the detector misses is seen by the depth
        view. The shield then needs each frame's contact. None: only the detector's walkers.
        Read only with the walker gate.
    """

    threshold: float = 0.3
    release: float = 0.3
    hold_frames: int = 5
    deceleration: float = 3.0
    path_half_width: float | None = 1.25
    headway: float = 0.5
    margin: float = 2.0
    front: float = 3.8
    confirm_frames: int = 2
    confirm_window: int = 3
    confirm_width: float | None = 0.3
    emergency: float | None = 6.0
    confirm_near: float | None = 2.5
    confirm_near_all: bool = False
    confirm_edge: float | None = None
    confirm_emerged: float | None = 0.8
    confirm_contact: float | None = 0.5
    memory: float | None = 1.0
    walker_horizon: float | None = 1.0
    unseen_walkers: float | None = 1.0

    def __post_init__(self):
        _set(self, "threshold", _unit(self.threshold, "threshold"))
        _set(self, "release", _unit(self.release, "release"))
        if self.release > self.threshold:
            raise ValueError(f"release = {self.release} must be <= threshold = {self.threshold}")
        for name, least in (("hold_frames", 0), ("confirm_frames", 1), ("confirm_window", 1)):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, numbers.Integral) or value < least:
                raise ValueError(f"{name} = {value!r}, must be an integer >= {least}")
            _set(self, name, int(value))
        if self.confirm_window < self.confirm_frames:
            raise ValueError(f"confirm_window = {self.confirm_window} must be >= confirm_frames = "
                             f"{self.confirm_frames}")
        deceleration = _number(self.deceleration, "deceleration")
        if not (math.isfinite(deceleration) and deceleration > 0):
            raise ValueError(f"deceleration = {self.deceleration!r}, must be > 0 m/s^2")
        _set(self, "deceleration", deceleration)
        if self.path_half_width is not None:
            width = _number(self.path_half_width, "path_half_width")
            if not (math.isfinite(width) and width > 0):
                raise ValueError(f"path_half_width = {self.path_half_width!r}, must be > 0 metres "
                                 "(or null: no path gate)")
            _set(self, "path_half_width", width)
        for name, null in (("confirm_width", "every unseen object is confirmed"),
                           ("confirm_near", "no zone near the bumper"),
                           ("confirm_edge", "no edge is asked")):
            if getattr(self, name) is not None:
                value = _number(getattr(self, name), name)
                if not (math.isfinite(value) and value >= 0):
                    raise ValueError(f"{name} = {getattr(self, name)!r}, must be >= 0 metres (or null: {null})")
                _set(self, name, value)
        if not isinstance(self.confirm_near_all, bool):
            raise ValueError(f"confirm_near_all = {self.confirm_near_all!r}, must be true or false")
        for name in ("confirm_emerged", "confirm_contact"):
            if getattr(self, name) is not None:
                _set(self, name, _unit(getattr(self, name), name))
        for name, unit in (("headway", "seconds"), ("margin", "metres"), ("front", "metres")):
            value = _number(getattr(self, name), name)
            if not (math.isfinite(value) and value >= 0):
                raise ValueError(f"{name} = {getattr(self, name)!r}, must be >= 0 {unit}")
            _set(self, name, value)
        if self.emergency is not None:
            emergency = _number(self.emergency, "emergency")
            if not (math.isfinite(emergency) and emergency > deceleration):
                raise ValueError(f"emergency = {self.emergency!r}, must be > deceleration = {deceleration:g} "
                                 "m/s^2 (or null: one stage)")
            _set(self, "emergency", emergency)
        if self.memory is not None:
            memory = _number(self.memory, "memory")
            if not (math.isfinite(memory) and memory > 0):
                raise ValueError(f"memory = {self.memory!r}, must be > 0 seconds (or null: no memory)")
            _set(self, "memory", memory)
        if self.walker_horizon is not None:
            horizon = _number(self.walker_horizon, "walker_horizon")
            if not (math.isfinite(horizon) and horizon > 0):
                raise ValueError(f"walker_horizon = {self.walker_horizon!r}, must be > 0 seconds (or null: no "
                                 "walker gate)")
            if self.path_half_width is None:
                raise ValueError(f"walker_horizon = {horizon:g} needs a path gate (path_half_width), which is "
                                 "null: set both, or walker_horizon to null (as the paper's shield has it)")
            _set(self, "walker_horizon", horizon)
        if self.unseen_walkers is not None:
            width = _number(self.unseen_walkers, "unseen_walkers")
            if not (math.isfinite(width) and width >= 0):
                raise ValueError(f"unseen_walkers = {self.unseen_walkers!r}, must be >= 0 metres (or null: only "
                                 "the detector's walkers)")
            _set(self, "unseen_walkers", width)


@dataclass(frozen=True)
class MonitorConfig:
    """Every tunable of :class:`monitor.RiskMonitor`, as the sections of its YAML file.

    Attributes
    ----------
    alignment : AlignmentConfig
    max_range : float
        Metres; S (and G in evaluation) beyond it are ignored. ``retrieval.max_range`` (and
        so both views' ``max_range``) always equals it.
    detections : DetectionsConfig
    retrieval : RetrievalConfig
        The depth view and its parameters.
    visibility : VisibilityParams
        When a frame cannot be seen through (:mod:`monitor.depth.visibility`);
        ``visibility.max_range`` always equals ``max_range``.
    risk : RiskConfig
    shield : ShieldConfig
    """

    alignment: AlignmentConfig = field(default_factory=AlignmentConfig)
    max_range: float = DEFAULT_RANGE_M
    detections: DetectionsConfig = field(default_factory=DetectionsConfig)
    retrieval: RetrievalConfig = field(default_factory=RetrievalConfig)
    visibility: VisibilityParams = field(default_factory=VisibilityParams)
    risk: RiskConfig = field(default_factory=RiskConfig)
    shield: ShieldConfig = field(default_factory=ShieldConfig)

    def __post_init__(self):
        hints = _hints(MonitorConfig)
        for f in fields(self):
            kind, value = hints[f.name], getattr(self, f.name)
            if is_dataclass(kind) and not isinstance(value, kind):
                raise ValueError(f"{f.name} is a {type(value).__name__}, expected a {kind.__name__}")
        max_range = _number(self.max_range, "max_range")
        if not (math.isfinite(max_range) and max_range > 0):
            raise ValueError(f"max_range = {self.max_range!r}, must be a finite number of metres > 0")
        _set(self, "max_range", max_range)
        for name in ("retrieval", "visibility"):
            if getattr(self, name).max_range != max_range:
                _set(self, name, replace(getattr(self, name), max_range=max_range))


# ----------------------------------------------------------------------------- reading
def _read(path: Path) -> dict:
    try:
        text = path.read_bytes().decode("utf-8")
    except UnicodeDecodeError as exc:
        raise ConfigError(f"{path}: not UTF-8 text (byte {exc.start}: {exc.reason})") from None
    try:
        data = strict_yaml.load(text)
    except strict_yaml.YamlError as exc:
        where = f", {exc.place}" if exc.place else ""
        raise ConfigError(f"{path}{where}: not a valid configuration: {exc.detail}") from None
    if data is None:
        return {}
    if not isinstance(data, dict):
        raise ConfigError(f"{path}: expected a mapping of sections, got {type(data).__name__}")
    return data


def _hints(cls) -> dict[str, Any]:
    return typing.get_type_hints(cls)


def _value(value: Any, kind: Any, where: str) -> Any:
    """A scalar of the file checked against its field's type (float, int, bool, str, or X | None)."""
    if isinstance(kind, types.UnionType) or typing.get_origin(kind) is typing.Union:
        options = typing.get_args(kind)
        if value is None and type(None) in options:
            return None
        (kind,) = [k for k in options if k is not type(None)]
    if kind is float:
        return _number(value, where)
    if kind is int:
        if isinstance(value, bool) or not isinstance(value, int):
            raise ValueError(f"{where} = {value!r}, must be an integer")
        return value
    if kind is bool:
        if not isinstance(value, bool):
            raise ValueError(f"{where} = {value!r}, must be true or false")
        return value
    if kind is str:
        if not isinstance(value, str):
            raise ValueError(f"{where} = {value!r}, must be text")
        return value
    raise TypeError(f"{where}: no reader for fields of type {kind!r}")  # a new field type


def _section(cls, defaults: dict, user: dict, path: str, inherited: frozenset = frozenset()) -> Any:
    """An instance of the dataclass ``cls`` from its default and user mappings.

    Fields named in ``inherited`` are not keys: the enclosing section sets them.
    """
    hints = _hints(cls)
    names = [f.name for f in fields(cls) if f.name not in inherited]
    unknown = [key for key in user if key not in names]
    if unknown:
        raise ValueError(f"unknown key {path}{unknown[0]!s}; expected one of "
                         f"{', '.join(path + n for n in names)}")
    kwargs: dict[str, Any] = {}
    nested = [n for n in names if is_dataclass(hints[n])]
    for name in names:
        if name in nested:
            continue
        source = user if name in user else defaults
        if name in source:
            kwargs[name] = _value(source[name], hints[name], path + name)
    for name in nested:
        sub = user.get(name, {})
        if not isinstance(sub, dict):
            raise ValueError(f"{path}{name} = {sub!r}, must be a mapping of keys")
        sub_cls = hints[name]
        shared = frozenset(f.name for f in fields(sub_cls)) & (frozenset(names) | inherited)
        kwargs[name] = _section(sub_cls, defaults.get(name, {}), sub, f"{path}{name}.", shared)
    try:
        return cls(**kwargs)
    except ValueError as exc:
        raise ValueError(f"{path}{exc}") from None


def load_config(path: str | Path | None = None) -> MonitorConfig:
    """The shipped defaults, overlaid with the file at ``path`` when given.

    Raises
    ------
    FileNotFoundError
        No file at ``path``.
    ConfigError
        Naming the file and the key path: unknown or duplicate keys, wrong types, values
        out of range, a file that is not UTF-8 YAML or is nested too deeply.
    """
    defaults = _read(DEFAULT_CONFIG_PATH)
    source, user = DEFAULT_CONFIG_PATH, {}
    if path is not None:
        source = Path(path)
        if not source.is_file():
            raise FileNotFoundError(f"{source}: no such configuration file")
        user = _read(source)
    try:
        return _section(MonitorConfig, defaults, user, "")
    except ValueError as exc:
        raise ConfigError(f"{source}: {exc}") from None
