"""The controller shield: turns the risk stream into a deceleration request (paper, Sec. IV-B).

The paper's shield starts to decelerate the vehicle whenever the monitor's risk exceeds a
threshold (0.5); it is ``ShieldConfig(threshold=0.5, release=0.5, path_half_width=None,
hold_frames=0, walker_horizon=None)``. The default is path-gated with a 5-frame hold (below;
docs/closed-loop.md), and its threshold is 0.3: the risk is a mean over every object the
monitor knows of, so one unseen object among three or more detected ones reads under 0.5,
and the gate, not the risk, tells whether that object is in the way. :class:`Shield` adds
two refinements against chattering on a noisy risk stream:

- hysteresis: once engaged, it stays engaged until the risk falls to ``release`` or below
  (``release == threshold``, the default: no hysteresis);
- a hold: it stays engaged at least ``hold_frames`` frames after the last frame above the
  threshold.

And one against braking for what is not in the way (``path_half_width``): the monitor's risk
says how much of what the depth view sees the detector misses, anywhere in its corridor, and
a detector calibrated to real data misses half of the traffic around the car in most
frames. With a path gate the risk engages the shield only while one of those missed objects
(a depth-view object no detection covers, :attr:`monitor.RiskReport.unseen`) stands in the
ego's path within its reach, the distance it needs to stop at the shield's deceleration plus
a headway and a margin, and it releases (after the hold) when none is left there: as the car
itself brakes for a detected obstacle in its path within its stopping distance, the shield
brakes for an unseen one. A frame without a view (``unseen`` None: an invalid frame or one
the view cannot see through) is not gated: its fail-safe risk engages the shield as before.

A gate asks more of small objects (``confirm_width``, ``confirm_frames``,
``confirm_window``): an unseen object narrower than ``confirm_width`` counts only once it is
confirmed, standing where it stands (the ego's travel allowed for, :func:`consistent`) in
``confirm_frames`` of the last ``confirm_window`` frames, as a tracker confirms a track of
weak evidence before acting on it. The depth artefacts of a monocular network (a patch of
road read too near: a blob, a flake, a reflection) are small and flicker from place to
place, so they engage nothing; a small obstacle stays and counts a frame or two later; a
wide object counts at once.

With ``emergency`` the gate has two stages, as automatic emergency braking grades its
response: an object within the *emergency reach* (the distance to stop at ``emergency``,
plus the headway and the margin) counts at once, as every wide object did with one stage,
and the shield then requests ``emergency``; beyond it, where braking at ``deceleration`` is
still enough, every object counts only once confirmed. A wide patch of road the depth
reads too near for one frame in the far part of the reach brakes nothing; an obstacle
there is confirmed a frame or two later, and one seen only late is met with the harder
braking that its distance calls for.

Near the bumper (``confirm_near``) every object must be confirmed too. A camera sees the
road only from some distance ahead of the bumper on; what stands nearer reaches into the
image's bottom rows, where the depth view cannot see the road beneath it to tell an
obstacle from a patch of road read too near (two thirds of the objects the shield braked
for in hazard-free drives stood there; docs/closed-loop.md). A standing obstacle that near
was in view a frame before, and one stepping in from the side was seen beside the path, so
confirming costs it at most a frame, at a distance where braking at once rarely stops the
car anyway. With ``confirm_near_all`` (an option, off) an object there that floats (below,
``confirm_contact``) must have floated there in every frame of the window, not
``confirm_frames`` of them: the blobs of the depth in the image's bottom rows (flakes in
snow, the grain of a noisy image) float, each in a new place, and one floats where one of
the two frames before had another by chance far more often than in both. A walker or an
obstacle standing there stands on the road, and is confirmed as before.

With ``confirm_edge`` an object that reaches only a little into the path must be confirmed
too, whatever its width. The path's half width adds a margin to the car's for the errors of
where things stand, and an object reaching into that margin alone stands beside the car's
body: most often the side of a car or truck beside the path that the view reads a little
too far in, in a frame that groups it differently from the frames before (a patch of road
at the path's edge, too). Something that comes into the path from the side and that one of
the two frames before showed beside it, no detection covering it, is confirmed at once (one a
detection covered there waits a frame). A walker stepping into the path reaches its edge
first, so the option is off by default (docs/closed-loop.md).

With ``confirm_emerged`` (0.8 by default) an object that came out of the road must be
confirmed too, wherever it stands: one of which that share of the blocks stood where each of
the last two frames saw through to the road beyond (``emerged``,
:meth:`monitor.RiskMonitor.emerged`, the ego's travel since allowed for; the paper's view
does not see the road, and what it does not measure is not asked). A thing standing on the
road was in the frames before, where it stood then, or hidden behind something, or beside
its place (a pedestrian stepping out, a car cutting in); a patch of road the depth reads too
near stood where they saw the road farther on. Such a patch, wide and within the emergency
reach, is what the at-once rule brakes hardest for; an obstacle that the network blended
into the road in both frames before is confirmed when it is seen again.

With ``confirm_contact`` (0.5 by default) an object that touches nothing must be confirmed
too, wherever it stands: one that stands on the road, or on something in front of it, in
fewer than that share of its columns (``contact``,
:attr:`monitor.RiskReport.unseen_contact`). What stands on the road meets it along its
width (a walker at her feet, a car at its wheels and bumper, debris all along); a blob of
the depth read too near in one frame hangs in the air, the road beneath it seen farther.
The view keeps an upright object that touches nothing (the raised rear of a trailer, a
barrier's arm), and such a thing stands there in the next frame too; the blob does not. A
sighting that floats then confirms only one that floats, and one that stands (or cannot
tell: nothing valid beneath it) only one that stands: two blobs in two frames are not one
object, and neither is a blob in one frame and a patch read too near at the image's bottom
edge in the next.

With ``memory`` the gate remembers where the unseen objects that engaged it stand, on the
road (the ego's travel, integrated from its speed, taken off their distance), for
``memory`` seconds after each was last sighted. An unseen object seen where a remembered one
stands, as :func:`consistent` tells, renews it at that place, so a remembered pedestrian
walking out of the path takes the memory with her. A remembered object sighted again keeps
the shield engaged while it lies in the path within reach, at the deceleration its distance
calls for, whatever the frame's risk, and engages it again when the car, moving on, brings it
back within reach. A dark obstacle that the depth view shows in one frame in three is so
braked for through the frames it misses, and the car that stopped short of it does not
creep into it after the hold; an artefact in a new place each frame is sighted once and
left to the hold.

With ``walker_horizon`` (1 s by default) the shield also engages for a walker the detector
reports beside the path who walks into it (:mod:`monitor.walkers`): followed on the road
over the last second, walking towards the centreline, and reaching the path's edge before
the car reaches her (or within the horizon), within reach; it then requests ``emergency``
within the emergency reach, ``deceleration`` beyond it, whatever the frame's risk (the hold
keeps it engaged after). The depth view and the detector see what stands in the path; a
walker stepping in stood beside it a moment before, where only her motion tells she is
coming. The closed loop's baseline planner predicts her path too, but only once its filter
is sure of her speed, for a walker at 1 m/s when she is nearly in the path; this gate acts
on a second of her positions. It acts on what the detector reports, not on what it misses: a
backstop for the planner's walker prediction (docs/closed-loop.md).

With ``unseen_walkers`` as well, it follows the depth view's unseen objects that could be
walkers in the same way (:class:`monitor.walkers.SightingTracks`): no wider than that, standing
on the road (``contact``, :data:`monitor.walkers.STANDING_CONTACT`) and ahead of the bumper by
``confirm_near`` or more. A walker the detector misses steps out from between parked cars into
the depth view's corridor before she reaches the path; a blob of the depth floats and is in a
new place each frame, and the side of a parked car is wider than a walker.

A NaN risk is never "below the threshold": it engages the shield, gate or no gate (the
monitor never produces one; this guards other risk sources).
"""
from __future__ import annotations

import math
import numbers
from collections import deque
from dataclasses import dataclass

import numpy as np

from monitor.config import ShieldConfig
from monitor.walkers import BODY_HALF_WIDTH, STANDING_CONTACT, SightingTracks, WalkerTracks, entering


#: what keeps the shield engaged in a frame (:attr:`ShieldDecision.cause`)
CAUSES = ("risk", "no view", "at once", "confirmed", "remembered", "walker", "unseen walker", "held")


@dataclass(frozen=True)
class ShieldDecision:
    """The shield's output for one frame: whether it brakes, how hard (m/s^2), and why.

    Attributes
    ----------
    engaged : bool
    deceleration : float
        m/s^2, 0.0 when not engaged.
    risk : float
        The frame's risk.
    cause : str
        "" when not engaged, else one of :data:`CAUSES`: ``risk``, the risk above the
        threshold (the paper's shield, or a NaN risk); with a path gate, ``no view``, a frame
        without a view; ``at once``, an unseen object in the path within reach that needs no
        confirmation; ``confirmed``, one that did and got it; ``remembered``, a remembered
        object (``memory``); ``walker``, a walker the detector reports stepping into the path
        (``walker_horizon``); ``unseen walker``, one only the depth view sees
        (``unseen_walkers``); ``held``, kept by the hold (or the hysteresis) after the last
        of those.
    objects : tuple of (x, y_min, y_max)
        With ``at once`` and ``confirmed``, the unseen objects that counted (ego frame,
        metres, as :attr:`monitor.RiskReport.unseen`); with ``walker`` and ``unseen
        walker``, the walkers stepping in within reach, where they stand now (``y`` of her
        track's line, plus and minus :data:`monitor.walkers.BODY_HALF_WIDTH`); empty
        otherwise.
    """

    engaged: bool
    deceleration: float
    risk: float
    cause: str = ""
    objects: tuple = ()


def describe_shield(config: ShieldConfig) -> str:
    """One line saying which shield ``config`` is, for reports: ``threshold 0.3, path gate
    1.25 m, hold 5 frames``, or ``... the risk alone (the paper's)`` without a gate."""
    parts = [f"threshold {config.threshold:g}"]
    if config.release < config.threshold:
        parts.append(f"release {config.release:g}")
    if config.path_half_width is None:
        parts.append("the risk alone (the paper's)")
    else:
        parts.append(f"path gate {config.path_half_width:g} m")
    parts.append(f"hold {config.hold_frames} frames")
    if config.path_half_width is not None and config.confirm_frames > 1:
        which = "objects" if config.confirm_width is None else f"objects under {config.confirm_width:g} m"
        if config.confirm_width is not None:
            zones = ([] if config.emergency is None else ["beyond the emergency reach"]) + \
                ([] if config.confirm_near is None else [f"within {config.confirm_near:g} m of the bumper"]) + \
                ([] if config.confirm_edge is None else [f"reaching under {config.confirm_edge:g} m into the path"]) + \
                ([] if config.confirm_emerged is None else [f"{100 * config.confirm_emerged:g} % out of the road"]) + \
                ([] if config.confirm_contact is None else
                 [f"touching the road in under {100 * config.confirm_contact:g} % of their columns"])
            if zones:
                listed = zones[0] if len(zones) == 1 else f"{', '.join(zones[:-1])} and {zones[-1]}"
                which += f" ({listed}: all)"
        parts.append(f"{which} confirmed in {config.confirm_frames} of {config.confirm_window} frames")
        if config.confirm_near is not None and config.confirm_near_all and config.confirm_contact is not None \
                and config.confirm_window > config.confirm_frames:
            parts[-1] += (f" (what floats within {config.confirm_near:g} m of the bumper: in all "
                          f"{config.confirm_window})")
    if config.path_half_width is not None and config.emergency is not None:
        parts.append(f"emergency {config.emergency:g} m/s^2")
    if config.path_half_width is not None and config.memory is not None:
        parts.append(f"objects remembered {config.memory:g} s")
    if config.walker_horizon is not None:
        seen = "" if config.unseen_walkers is None else \
            f" (unseen ones too: standing objects up to {config.unseen_walkers:g} m wide)"
        parts.append(f"walkers stepping in within {config.walker_horizon:g} s{seen}")
    return ", ".join(parts)


class Shield:
    """Risk in, deceleration request out, one frame at a time.

    Parameters
    ----------
    config : ShieldConfig, optional
        Threshold, release, hold, deceleration and path gate (default: the shipped
        defaults); the ``shield`` section of :class:`monitor.config.MonitorConfig`.

    Examples
    --------
    >>> shield = Shield(ShieldConfig(threshold=0.6, release=0.3, hold_frames=0, path_half_width=None,
    ...                              walker_horizon=None))
    >>> shield.update(0.7).engaged, shield.update(0.4).engaged, shield.update(0.2).engaged
    (True, True, False)
    >>> gated = Shield()  # 1 m wide in the path 12 m ahead, then beside it: the hold keeps 5 frames
    >>> ahead, beside = [[12.0, -0.5, 0.5]], [[12.0, 2.0, 3.0]]
    >>> [gated.update(0.8, speed=8.0, unseen=u, time=0.1 * k, walkers=[], contact=[1.0]).engaged
    ...  for k, u in enumerate([ahead] + [beside] * 6)]  # no walker; each stands on the road
    [True, True, True, True, True, True, False]
    >>> small = Shield()  # 0.1 m wide, 10 m ahead: counts once it stood there in 2 of 3 frames
    >>> [small.update(0.8, speed=8.0, unseen=[[10.0 - 0.8 * k, 0.0, 0.1]], time=0.1 * k,
    ...               walkers=[], contact=[1.0]).engaged for k in range(3)]
    [False, True, True]
    """

    def __init__(self, config: ShieldConfig = ShieldConfig()):
        if not isinstance(config, ShieldConfig):
            raise ValueError(f"config is a {type(config).__name__} ({config!r}), expected a "
                             "ShieldConfig, e.g. Shield(ShieldConfig(threshold=0.5)) or "
                             "Shield(load_config().shield)")
        self.config = config
        self.reset()

    def reset(self) -> None:
        """Forget the history (a new drive)."""
        self.engaged = False
        self._since_trigger = 0
        self._decel = self.config.deceleration  # requested while engaged: the last trigger's
        # (time, unseen, which of them float) of past frames
        self._history = deque(maxlen=self.config.confirm_window - 1)
        self._odometer = 0.0  # metres the ego travelled (speed times the frames' intervals)
        self._time = None  # the last frame's time
        # remembered objects: x, y_min, y_max where last sighted, its time, the odometer then,
        # the number of sightings
        self._memory = np.zeros((0, 6))
        self._walkers = WalkerTracks()  # the detector's walkers (walker_horizon)
        self._sightings = SightingTracks()  # the depth view's (unseen_walkers)

    def reach(self, speed: float, deceleration: float | None = None) -> float:
        """Metres ahead of the front bumper in which an unseen object counts at ``speed``
        m/s: the braking distance at ``deceleration`` m/s^2 (default: the config's
        ``deceleration``; its ``emergency`` gives the emergency reach), plus ``headway``
        seconds of travel and the ``margin``."""
        c = self.config
        decel = c.deceleration if deceleration is None else deceleration
        return speed * speed / (2.0 * decel) + speed * c.headway + c.margin

    def update(self, risk: float, speed: float | None = None, unseen=None,
               time: float | None = None, emerged=None, walkers=None, contact=None) -> ShieldDecision:
        """The decision for the next frame.

        Parameters
        ----------
        risk : float
            The monitor's risk (a real number; NaN engages).
        speed : float, optional
            The ego's speed, m/s (>= 0); needed with a path gate, ignored without.
        unseen : ndarray of shape (k, 3) or None
            The report's :attr:`~monitor.RiskReport.unseen` (``x, y_min, y_max`` per object,
            ego frame, metres); None for a frame without a view. Read only with a path gate.
        time : float, optional
            The frame's time, seconds, increasing; needed with a path gate that confirms
            (``confirm_frames > 1``, the default), remembers (``memory``) or watches walkers
            (``walker_horizon``), ignored otherwise.
        emerged : ndarray of shape (k,), optional
            :meth:`monitor.RiskMonitor.emerged` of the frame's report: one share in [0, 1]
            (or NaN: not known) per row of ``unseen``; None: not given, which a path gate
            that confirms with ``confirm_emerged`` refuses for a frame with a view. Read
            only by such a gate.
        walkers : ndarray of shape (w, 2), optional
            ``x, y`` (ego frame, metres, ``x > 0``) of the walkers the detector reports in the
            frame (:func:`monitor.walkers.walker_positions`); needed with ``walker_horizon``,
            which refuses None, and read only then.
        contact : ndarray of shape (k,), optional
            The report's :attr:`~monitor.RiskReport.unseen_contact`: one share in [0, 1] (or
            NaN: not measured) per row of ``unseen``; None: not given, which a path gate that
            confirms with ``confirm_contact`` refuses for a frame with a view. Read only by
            such a gate.
        """
        if isinstance(risk, bool) or not isinstance(risk, numbers.Real):
            raise ValueError(f"risk = {risk!r}, expected a number (a risk in [0, 1], or NaN)")
        risk = float(risk)
        c = self.config
        decel, kept, why, counted = c.deceleration, 0.0, "risk", ()
        if c.path_half_width is not None:
            decel, kept, why, counted = self._in_path(speed, unseen, time, risk > c.threshold, emerged, contact)
        walker, stepping, who = 0.0, (), "walker"
        if c.walker_horizon is not None:
            if walkers is None:
                raise ValueError(f"walkers = None: a shield that watches walkers (walker_horizon = "
                                 f"{c.walker_horizon:g} s) needs the frame's walkers, (w, 2) rows x, y "
                                 "(monitor.walkers.walker_positions of the frame's detections)")
            walker, stepping = self._walker(float(speed), walkers, self._walkers)
            if c.unseen_walkers is not None:
                unseen_walker, unseen_stepping = self._walker(float(speed), self._standing(unseen, contact),
                                                              self._sightings)
                if unseen_walker > walker:
                    walker, stepping, who = unseen_walker, unseen_stepping, "unseen walker"
        cause = ""
        if math.isnan(risk) or (risk > c.threshold and decel > 0.0):
            self.engaged, self._since_trigger = True, 0
            self._decel = max(decel, c.deceleration, walker)
            cause = "risk" if math.isnan(risk) else why
        elif walker > 0.0:
            self.engaged, self._since_trigger, self._decel = True, 0, walker
            cause, counted = who, stepping
        elif self.engaged:
            self._since_trigger += 1
            if kept > 0.0:
                self._decel, cause = max(self._decel, kept), "remembered"
            elif (risk <= c.release or decel == 0.0) and self._since_trigger > c.hold_frames:
                self.engaged = False
            else:
                cause = "held"
        elif kept > 0.0:  # a remembered object came within reach again: no new hold
            self.engaged, self._since_trigger, self._decel = True, c.hold_frames, kept
            cause = "remembered"
        if cause not in ("at once", "confirmed", "walker", "unseen walker"):
            counted = ()
        return ShieldDecision(self.engaged, self._decel if self.engaged else 0.0, risk, cause, counted)

    def _in_path(self, speed, unseen, time, triggers: bool, emerged,
                 contact) -> tuple[float, float, str, tuple]:
        """The deceleration an unseen object in the path within reach calls for, m/s^2:
        ``emergency`` for one within the emergency reach, ``deceleration`` for one beyond
        it or for a frame without a view to tell, 0.0 for none. One narrower than
        ``confirm_width``, with ``emergency`` one beyond the emergency reach, one within
        ``confirm_near`` of the bumper, one reaching less than ``confirm_edge`` into the
        path, one whose ``emerged`` share reaches ``confirm_emerged``, and one whose
        ``contact`` is under ``confirm_contact``, count only once confirmed. Second, with a
        memory, the deceleration the remembered objects call for where they stand now (0.0
        without); the counting objects of a frame that ``triggers`` (its risk above the
        threshold) are remembered. Third and fourth, why the first would engage the shield
        (``no view``, ``at once``, ``confirmed``; "" for nothing) and the objects that count,
        as :class:`ShieldDecision` gives them."""
        c = self.config
        if isinstance(speed, bool) or not isinstance(speed, numbers.Real) or not speed >= 0 \
                or not math.isfinite(speed):
            raise ValueError(f"speed = {speed!r}: a shield with a path gate needs the ego's speed, "
                             "a finite number of m/s >= 0")
        if unseen is not None:
            unseen = np.asarray(unseen, dtype=np.float64)
            if unseen.ndim != 2 or unseen.shape[1] != 3 or not np.isfinite(unseen).all():
                raise ValueError(f"unseen has shape {unseen.shape}: expected finite (k, 3) rows "
                                 "x, y_min, y_max (RiskReport.unseen)")
        if emerged is None and unseen is not None and c.confirm_emerged is not None and c.confirm_frames > 1:
            raise ValueError(f"emerged = None: a shield that confirms what came out of the road (confirm_emerged "
                             f"= {c.confirm_emerged:g}) needs a share per unseen object, RiskMonitor.emerged "
                             "of a monitor whose config sets shield.confirm_emerged too")
        if contact is None and unseen is not None and c.confirm_contact is not None and c.confirm_frames > 1:
            raise ValueError(f"contact = None: a shield that confirms what touches nothing (confirm_contact = "
                             f"{c.confirm_contact:g}) needs a share per unseen object, RiskReport.unseen_contact")
        emerged = _shares(emerged, unseen, "emerged", "RiskMonitor.emerged")
        contact = _shares(contact, unseen, "contact", "RiskReport.unseen_contact")
        if c.confirm_frames > 1 or c.memory is not None or c.walker_horizon is not None:
            if isinstance(time, bool) or not isinstance(time, numbers.Real) or not math.isfinite(time) \
                    or (self._time is not None and not time > self._time):
                last = f" (the last frame's was {self._time!r})" if self._time is not None else ""
                raise ValueError(f"time = {time!r}{last}: a shield whose gate confirms (confirm_frames > 1), "
                                 "remembers (memory) or watches walkers (walker_horizon) needs each frame's "
                                 "time, finite seconds, increasing")
            time = float(time)
            if self._time is not None:
                self._odometer += float(speed) * (time - self._time)
            self._time = time
        if c.memory is not None:  # forget what was not sighted for too long
            self._memory = self._memory[time - self._memory[:, 3] <= c.memory]
        why, counted = "", ()
        floats = np.zeros(0 if unseen is None else unseen.shape[0], dtype=bool)
        if c.confirm_contact is not None and contact is not None:
            floats = contact < c.confirm_contact  # NaN: not measured, does not float
        if unseen is None:
            decel, why = c.deceleration, "no view"
        else:
            w = c.path_half_width
            x, y_min, y_max = unseen.T
            inside = (x - c.front <= self.reach(float(speed))) & (y_max >= -w) & (y_min <= w)
            near = unseen[inside]
            urgent = np.zeros(near.shape[0], dtype=bool)
            if c.emergency is not None:
                urgent = near[:, 0] - c.front <= self.reach(float(speed), c.emergency)
            asked = np.zeros(near.shape[0], dtype=bool)  # those that must be confirmed
            if c.confirm_frames > 1:  # those that must be seen standing there often enough
                width = math.inf if c.confirm_width is None else c.confirm_width
                asked = near[:, 2] - near[:, 1] < width
                if c.emergency is not None:
                    asked |= ~urgent
                if c.confirm_near is not None:
                    asked |= near[:, 0] - c.front < c.confirm_near
                if c.confirm_edge is not None:
                    asked |= np.minimum(near[:, 2], w) - np.maximum(near[:, 1], -w) < c.confirm_edge
                if c.confirm_emerged is not None:
                    asked |= emerged[inside] >= c.confirm_emerged  # NaN: not known, not asked
                asked |= floats[inside]
            unconfirmed = asked.copy()
            if unconfirmed.any():
                hits = np.zeros(near.shape[0], dtype=np.int64)
                afloat = floats[inside]
                # a sighting that floats confirms one that floats, one that stands one that stands
                for t, then, then_afloat in self._history:
                    dt = time - t
                    hits[afloat] += consistent(near[afloat], then[then_afloat], dt, speed)
                    hits[~afloat] += consistent(near[~afloat], then[~then_afloat], dt, speed)
                need = np.full(near.shape[0], c.confirm_frames - 1)
                if c.confirm_near is not None and c.confirm_near_all:
                    need[(near[:, 0] - c.front < c.confirm_near) & afloat] = c.confirm_window - 1
                unconfirmed &= hits < need
            counts = ~unconfirmed
            if c.memory is not None:
                self._renew(unseen, time)
                if triggers:
                    self._remember(near[counts], time)
            decel = c.emergency if np.any(counts & urgent) else c.deceleration if counts.any() else 0.0
            if counts.any():
                why = "at once" if np.any(counts & ~asked) else "confirmed"
                counted = tuple(tuple(row) for row in near[counts].tolist())
        if c.confirm_frames > 1:
            self._history.append((time, np.zeros((0, 3)) if unseen is None else unseen, floats))
        return decel, (0.0 if c.memory is None else self._remembered(float(speed))), why, counted

    def _standing(self, unseen, contact) -> np.ndarray:
        """The unseen objects that could be walkers (``unseen_walkers``), as (s, 2) rows ``x,
        y`` (the middle of their span): no wider than ``unseen_walkers``, standing on the road
        (``contact`` at least :data:`monitor.walkers.STANDING_CONTACT`; NaN, not measured,
        does not stand) and ahead of the bumper by ``confirm_near`` or more, where the view
        sees the road beneath them; none for a frame without a view. Call after
        :meth:`_in_path`, which validated ``unseen`` and ``contact``."""
        c = self.config
        if unseen is None:
            return np.zeros((0, 2))
        if contact is None:
            raise ValueError(f"contact = None: a shield that follows unseen walkers (unseen_walkers = "
                             f"{c.unseen_walkers:g} m) needs a share per unseen object, RiskReport.unseen_contact")
        x, y_min, y_max = np.asarray(unseen, dtype=np.float64).reshape(-1, 3).T
        standing = (y_max - y_min <= c.unseen_walkers) & (np.asarray(contact, dtype=np.float64) >= STANDING_CONTACT)
        standing &= x - c.front >= (0.0 if c.confirm_near is None else c.confirm_near)
        return np.stack([x, 0.5 * (y_min + y_max)], axis=1)[standing]

    def _walker(self, speed: float, walkers, tracks) -> tuple[float, tuple]:
        """The deceleration the walkers stepping into the path within reach call for, m/s^2
        (0.0 for none): ``emergency`` for one within the emergency reach, else
        ``deceleration``; and those walkers as :attr:`ShieldDecision.objects` gives them.
        Adds the frame's ``walkers`` to ``tracks`` (:class:`monitor.walkers.WalkerTracks`;
        after :meth:`_in_path` moved the odometer to this frame)."""
        c = self.config
        tracks = tracks.update(walkers, self._time, self._odometer)
        stepping = tracks[entering(tracks, c.path_half_width, c.front, speed, c.walker_horizon)]
        stepping = stepping[stepping[:, 0] - c.front <= self.reach(speed)]
        x, y = stepping[:, 0], stepping[:, 1]
        objects = tuple(zip(x.tolist(), (y - BODY_HALF_WIDTH).tolist(), (y + BODY_HALF_WIDTH).tolist()))
        if c.emergency is not None and np.any(x - c.front <= self.reach(speed, c.emergency)):
            return c.emergency, objects
        return (c.deceleration if len(x) else 0.0), objects

    def _renew(self, sightings: np.ndarray, time: float) -> None:
        """Renew, at the sighting, each remembered object where one of ``sightings`` (k, 3)
        stands (the ego's travel since it was last sighted allowed for)."""
        for row in self._memory:
            dt = time - row[3]
            match = np.flatnonzero(consistent(sightings, row[None, :3], dt, (self._odometer - row[4]) / dt))
            if match.size:
                row[:] = (*sightings[match[0]], time, self._odometer, row[5] + 1)

    def _remember(self, objects: np.ndarray, time: float) -> None:
        """Remember ``objects`` (k, 3), sighted at ``time``, but those that renewed a
        remembered object."""
        fresh = self._memory[:, 3] == time
        new = objects[~consistent(objects, self._memory[fresh, :3], 0.0, 0.0)] if fresh.any() else objects
        rows = np.column_stack([new, np.full(len(new), time), np.full(len(new), self._odometer),
                                np.ones(len(new))])
        self._memory = np.vstack([self._memory, rows])

    def _remembered(self, speed: float) -> float:
        """The deceleration the remembered objects sighted more than once call for where they
        stand now (the ego's travel since each was sighted taken off its distance): as for a
        counting unseen object; those now behind the bumper are forgotten."""
        c = self.config
        x = self._memory[:, 0] - (self._odometer - self._memory[:, 4])
        self._memory = self._memory[x >= c.front]
        x = x[x >= c.front]
        inside = (self._memory[:, 2] >= -c.path_half_width) & (self._memory[:, 1] <= c.path_half_width)
        ahead = x[inside & (self._memory[:, 5] > 1)] - c.front
        if c.emergency is not None and np.any(ahead <= self.reach(speed, c.emergency)):
            return c.emergency
        return c.deceleration if np.any(ahead <= self.reach(speed)) else 0.0


#: Metres of depth error ``consistent`` allows along the line of sight, at any distance.
MATCH_ABS_M = 0.5
#: Metres an object's lateral span may move between frames besides its own motion: the span
#: comes from the object's pixel columns, which the depth error hardly moves within the
#: path (a 15 % depth error moves a point 1 m beside the path's centre by 0.15 m); its
#: blocks come and go at its edges.
MATCH_LATERAL_M = 0.3
#: Relative depth error ``consistent`` allows (of the distance).
MATCH_REL = 0.15
#: Speed of an object's own motion ``consistent`` allows, m/s (a person walking briskly).
OBJECT_SPEED = 2.0


def _shares(values, unseen: np.ndarray | None, name: str, source: str) -> np.ndarray | None:
    """``values`` (``emerged`` or ``contact``) as (k,) float64, one share in [0, 1] or NaN per
    row of ``unseen`` (k, 3); None stays None. ValueError naming ``name`` and its ``source``
    otherwise (values given for a frame without a view among them)."""
    if values is None:
        return None
    values = np.asarray(values, dtype=np.float64)
    k = None if unseen is None else unseen.shape[0]
    if values.shape != (k,) or np.any(np.abs(values - 0.5) > 0.5):
        raise ValueError(f"{name} = {values.tolist()}: expected one share in [0, 1] (or NaN) per "
                         f"row of unseen, shape ({k},) ({source})")
    return values


def consistent(now: np.ndarray, then: np.ndarray, dt: float, speed: float) -> np.ndarray:
    """Does each object of ``now`` stand where one of ``then`` stood ``dt`` seconds before,
    if it stands still (or nearly)?

    Parameters
    ----------
    now, then : ndarray of shape (k, 3) / (m, 3)
        ``x, y_min, y_max`` per object, ego frame, metres.
    dt : float
        Seconds between the two frames (> 0).
    speed : float
        The ego's speed, m/s: in ``dt`` it came ``speed * dt`` closer to what stands still.

    Returns
    -------
    ndarray of shape (k,), bool
        True where some object of ``then`` has ``x`` within ``MATCH_ABS_M + MATCH_REL * x
        + OBJECT_SPEED * dt`` of ``now``'s ``x + speed * dt``, and a lateral span that
        overlaps ``now``'s widened by ``MATCH_LATERAL_M + OBJECT_SPEED * dt``. Traffic moving
        along with the ego drifts out of that over a few frames, as a depth artefact does
        at once.
    """
    x, lo, hi = (now[:, k, None] for k in range(3))
    tol_x = MATCH_ABS_M + MATCH_REL * x + OBJECT_SPEED * dt
    tol_y = MATCH_LATERAL_M + OBJECT_SPEED * dt
    tx, tlo, thi = (then[None, :, k] for k in range(3))
    along = np.abs(tx - (x + speed * dt)) <= tol_x
    across = (tlo <= hi + tol_y) & (thi >= lo - tol_y)
    return np.any(along & across, axis=1)
