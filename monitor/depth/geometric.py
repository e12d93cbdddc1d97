"""A geometric depth view: what stands on the road inside the corridor the car will drive.

The paper's view (:mod:`monitor.depth.retrieval`) finds objects as edges of the inverse depth
minus a prior of usual scenes; it knows nothing of the camera, so walls, poles and buildings
beside the road become objects, and an unusual road looks like one. This view uses what the
monitor knows, the camera's intrinsics and mounting (:class:`~monitor.geometry.camera.Camera`),
in the manner of the stereo-vision obstacle detectors:

1. **Points.** The depth map is cut into ``stride x stride`` pixel blocks; each block's
   depth is back-projected through the block's centre into the ego frame (x forward, y
   left, z up, origin on the ground). A block's depth is the mean of its valid pixels
   (NaN, inf and <= 0 are left out), or at an edge (depths spread by more than
   ``edge_spread``) its nearest: a mean across an edge would be a point floating between
   the two surfaces, bridging objects. A block without a valid pixel is no point.
2. **Road surface.** Labayrade et al.'s v-disparity (IV 2002) rests on the fact that a
   planar road seen by a pinhole camera has a disparity (an inverse depth) affine in the
   pixel coordinates, a line in the v-disparity image when the camera does not roll; they
   find the line with a Hough transform. With metric depth and a calibrated camera the same
   plane is fitted directly in 3D: RANSAC over the blocks that could be road, then least
   squares on its inliers (twice). The mounting bounds the search: the plane's tilt from the
   ego frame's ground ``z = 0`` is at most ``max_tilt_deg`` and its height at the ego origin
   at most ``max_height_offset`` (a wrong depth scale shows as a height offset, the car's
   pitch and a change of grade as a tilt). Without enough support (``min_ground_fraction``
   of the blocks) the nominal plane ``z = 0`` is used instead and the result says so.
3. **Obstacles.** As in the stixel world (Badino, Franke and Pfeiffer, DAGM 2009), an
   obstacle is what rises above the road in front of the free space: a block whose height
   above the plane is within ``[min_height, max_height]`` and whose camera depth is within
   ``max_range``.
4. **Objects.** Obstacle blocks are grouped on an occupancy grid of the ground (cells of
   ``cell_size`` metres, as the stixel world's free-space grid): 8-connected components of
   occupied cells. A free cell between two things splits them, so an object in front of
   another, or beside it, is its own, while the faces of one object (a car's rear and the
   side seen at a grazing angle, whose depth jumps from one block to the next) stay
   together. A component is an object when at least ``min_points`` of its blocks lie in the
   corridor (lateral offset from the ego path at most the half width, see
   :mod:`monitor.geometry.corridor`); the whole component counts, so a car cutting in gets
   its whole box. Each object's 2D box is the extent of its blocks in pixels and its depth
   the ``depth_percentile`` of its blocks' camera depths, comparable with the detector's
   ``camera_depth`` (the nearest camera depth of a box).
   Before the grouping, structure is taken out: a corridor wide enough to hold the traffic
   beside the car (parked cars, cyclists, pedestrians at the kerb) also reaches the
   street's structure, which is not traffic and which no detector is asked to find. What
   rises higher than ``structure_height`` above the road (buildings, walls, poles, trees:
   taller than any road vehicle) marks its ground cell and the cell's neighbours, and the
   obstacle blocks in marked cells are no obstacles. It works per cell, not per object, so
   a car parked against a wall keeps its own cells (off when ``structure_height`` is None).
5. **What floats is no object.** In v-disparity an obstacle is a vertical segment (one
   inverse depth down its rows) and the road an oblique line (the inverse depth grows
   linearly down the image). A patch of road that a monocular network reads too near (a
   reflection, a drop, a flake, image noise) rises above the plane like an obstacle, but it
   stays a surface along the road: its inverse depth grows down the image as the road's
   does or faster, and the road seen right beneath it is farther than it. An object whose
   inverse depth grows by more than ``max_incline`` of the road's slope (a least-squares fit
   over its blocks' rows) and that touches the road, or something in front of it, in fewer
   than ``min_contact`` of its columns is dropped. Both tests are needed: the top of a low
   box (debris) lies along the road but stands on it, and the raised rear of a trailer has
   the road beneath it but is upright (off when ``max_incline`` is None). What stands on
   the road meets it along its whole width; a patch read too near touches it only where
   the network smears its edge into the road, so ``min_contact`` asks for nine columns in
   ten, and an upright face is kept whatever its contact (a pedestrian's legs, a car's
   clearance). Where nothing valid lies beneath an object (the image's bottom edge cuts
   it, or the depth below is invalid) contact cannot be told: such an object is dropped
   when its inverse depth grows more than ``UNSUPPORTED_INCLINE`` times as fast as the
   road's, faster than the top of any low obstacle; an upright face (near 0) or the top of
   debris is kept. Each object's contact is reported (:attr:`GeometricView.contact`): an
   upright face that touches nothing is kept, as the raised rear of a trailer or a barrier's
   arm must be, but a blob of the depth read too near in one frame, too few rows tall for
   its incline to show, floats the same way, and the shield asks such an object to stand
   in more than one frame before it brakes for it (``ShieldConfig.confirm_contact``).
6. **What hides nothing is no object.** What stands on the road hides what is behind it:
   right above its top the image sees the road far beyond it, the sky, or something
   standing behind it. A patch of road that the depth reads a little too near over a wide
   area (the smooth part of a network's error) rises above the plane without an edge: above
   its top the road goes on at the depth the road would have there. An object that hides
   something (a block farther than ``OCCLUSION_RATIO`` times the road's depth there, or one
   standing above the road, among the first ``EDGE_BLOCKS`` valid blocks above its top) in
   fewer than ``min_occlusion`` of its columns is dropped (off when ``min_occlusion`` is
   None). Something standing above an object counts only for an object with an upright
   face (one of its blocks rises, rule 8): a child in front of a car sees the car's rear
   above her head, at about her depth. Above a flat object (none of its blocks rises) what
   stands is as often the same surface farther on: the smooth error that lifts a patch of
   road 0.2-0.3 m (read 10-15 % too near) goes on up the image, over ``min_height`` in
   places and under it in others, and its far fragments stand right above the near ones.
   So a flat object must hide by its depth; low debris, whose face is too short to rise,
   does (the road behind its top lies 1.2 times farther).
7. **A ledge along the road is no object.** A kerb (0.10-0.15 m) that the depth's noise
   lifts over ``min_height`` in places stands on the road and hides the sidewalk behind
   it, so rules 5 and 6 keep its fragments; in a corridor as wide as the traffic beside
   the car it lies at the lane's edge. What sets it apart is its shape: low, narrow and
   long along the road. An object whose top (the ``TOP_PERCENTILE`` of its blocks' heights
   above the road) is under ``ledge_height``, whose lateral span (``extents``) is under
   ``ledge_width`` and whose span along the ego's x is more than ``LEDGE_ELONGATION`` times
   that is dropped (off when ``ledge_height`` is None). Debris is as low but wider, or as
   long as it is wide; a kerb on a curve spans more across than a straight one, and then
   the rule leaves it in.
8. **Where an object stands is where it rises.** An upright face puts points of many
   heights on one place of the ground (the stixel world's column of one depth); a surface
   read above the road (a patch of road read too near, the road beside a car blended into
   it) puts one height on each place. The grid groups such a surface with the car or the
   truck it touches, and the patch, metres nearer or reaching into the ego's path, would
   move where the object stands. So an object's ``extents`` come from its blocks that
   *rise*: those whose ground cell, or one of the 8 around it, holds points ``min_rise``
   metres or more apart in height, counting the points from half of ``min_height`` up (the
   foot of a face, not the road). An object of which no block rises keeps the extents of
   all its blocks: a flat object is still an object, one that must hide by its depth
   (rule 6; off when ``min_rise`` is None).
9. **What comes out of the road was never there.** Given the road an earlier frame saw
   (:attr:`GeometricView.road_depth`) and how far the ego moved since
   (:meth:`GeometricRetriever.emerged`), each object's blocks (:attr:`GeometricView.points`)
   are put back where they stood then (the ego's travel added to their x) and projected
   into that frame: did its line of sight pass through the block's place to the road
   beyond? A thing standing on the road was in the earlier frame too, where it stood then
   (or hidden behind something, or beside its place: a pedestrian stepping out, a car
   cutting in, moving a fraction of its width between frames): that frame saw it there,
   or something nearer; a patch of road that the depth reads too near in one frame stood
   where the frame before saw the road, farther. ``emerged`` is the share of an object's
   blocks behind whose place the earlier frame saw the road, farther by more than
   ``EMERGED_MARGIN`` (the depth's frame-to-frame scatter on a thing that stood there),
   among those that land on one of its valid blocks. It is evidence, not a verdict (a dark
   obstacle that the network blended into the road in one frame reappears from it in the
   next): the monitor takes the smallest share over the last two frames
   (:meth:`monitor.RiskMonitor.emerged`) and the shield asks such an object to be
   confirmed before it brakes for it (:class:`monitor.shield.Shield`, ``confirm_emerged``).
   It is the free space of Elfes' occupancy grids, a cell seen through before, asked of
   the frames just before.

The result is the set S as the paper's view gives it: float64 (m, 5) rows ``cx, cy, w, h,
d`` (pixels, metres), nearest first, plus what a report needs (:class:`GeometricView`): the
free distance ahead in the corridor, the ground plane and whether it was fitted, the share
of valid pixels.

A frame the view cannot see through raises :class:`BlindViewError` (the monitor turns it
into a fail-safe) instead of reporting "nothing there": more than ``max_invalid_fraction``
of the pixels invalid, more than ``max_corridor_invalid_fraction`` of the pixels that look
at the corridor's road (up to ``max_range``) invalid, or more than ``max_below_fraction`` of
the valid blocks more than ``below_margin`` under the road plane used: seeing through the
road means the mounting or the depth scale is grossly wrong. A surface filling the view
close ahead is an object at that depth, not an error.

Speed: the one pass over all pixels is :func:`~monitor.depth._geometric_kernels.block_points`;
everything after it works on the (H / stride) x (W / stride) blocks. ``stride = 4`` gives
400 x 225 blocks for a 1600 x 900 frame: a pedestrian (0.67 m) at 20 m is still 10 blocks
wide (see ``benchmarks/bench_geometric.py`` for the timings). Call :func:`warmup` once
before a real-time loop.
"""
from __future__ import annotations

import math
import numbers
import threading
from dataclasses import dataclass

import numpy as np

from monitor.depth import _geometric_kernels as kernels
from monitor.geometry.boxes import DEFAULT_RANGE_M
from monitor.geometry.camera import Camera
from monitor.geometry.corridor import Corridor

#: spacing of the corridor's centreline table along x, metres
CORRIDOR_STEP_M = 0.1
#: the road beneath an object touches it when no farther than this many times its depth
CONTACT_RATIO = 1.2
#: what is seen above an object is hidden behind it when farther than this many times the
#: road's depth there: the road behind an object h metres tall, seen from a camera H metres
#: up, lies H / (H - h) times farther than its top (debris 0.3 m tall seen from 1.5 m: 1.25),
#: a patch of road read too near goes on at about the road's depth (1.0)
OCCLUSION_RATIO = 1.1
#: the first this many valid blocks below or above an object are looked at (a blurred
#: edge is one)
EDGE_BLOCKS = 3
#: an object with nothing valid beneath it (cut by the image's bottom edge) is a patch of road
#: read too near when its inverse depth grows down the image more than this many times as
#: fast as the road's: the top of an obstacle h metres tall, seen from a camera H metres up,
#: grows H / (H - h) times as fast (debris 0.3 m tall seen from 1.5 m: 1.25; a surface a
#: third of the camera's height up: 1.5), an upright face not at all
UNSUPPORTED_INCLINE = 1.5
#: an object's top is this percentile of its blocks' heights above the road (a few blocks
#: lifted by the depth's grain do not make it)
TOP_PERCENTILE = 95.0
#: a ledge reaches along the ego's x more than this many times its lateral span (the kerbs'
#: fragments in the benchmark's held-out frames: 2.6 to 11 times)
LEDGE_ELONGATION = 2.0

#: an object's ``emerged`` share is NaN when fewer of its blocks than this land on valid
#: blocks of the earlier frame (it was out of its image, or its depth there was invalid)
MIN_EMERGED_BLOCKS = 3
#: a block came out of the road (rule 9) when the earlier frame saw the road behind its place
#: farther than the block's camera depth there by more than this share; the depth's scatter
#: from frame to frame on a thing that stood there: half its sightings within 6 %
#: (docs/closed-loop.md, 28 November 2026)
EMERGED_MARGIN = 0.1

#: why a frame is blind: BlindViewError.reason -> the parameter whose limit it exceeded
BLIND_REASONS = {
    "invalid": "max_invalid_fraction",
    "corridor_invalid": "max_corridor_invalid_fraction",
    "below_ground": "max_below_fraction",
}


class BlindViewError(ValueError):
    """A frame the geometric view cannot see through (never to be read as "nothing there").

    Attributes
    ----------
    reason : str
        A key of :data:`BLIND_REASONS`: ``"invalid"`` (too many invalid pixels),
        ``"corridor_invalid"`` (too many invalid pixels looking at the corridor's road) or
        ``"below_ground"`` (too many points under the road plane).
    fraction : float
        The measured share, 0..1.
    limit : float
        The parameter's limit that it exceeded.
    """

    def __init__(self, reason: str, fraction: float, limit: float):
        self.reason, self.fraction, self.limit = reason, float(fraction), float(limit)
        what = {
            "invalid": "of the depth map's pixels are invalid (NaN, inf or <= 0)",
            "corridor_invalid": "of the pixels that look at the corridor's road are invalid",
            "below_ground": "of the valid points lie under the road plane (mounting or depth "
                            "scale grossly wrong)",
        }[reason]
        super().__init__(f"{100 * fraction:.1f}% {what}, more than {BLIND_REASONS[reason]} = "
                         f"{100 * limit:.1f}%; the geometric view cannot see this frame")


@dataclass(frozen=True)
class GeometricParams:
    """The geometric view's parameters (metres, pixels, shares 0..1).

    Parameters
    ----------
    stride : int
        Block size, pixels (>= 1): each ``stride x stride`` block is one point.
    edge_spread : float
        A block whose largest valid depth exceeds its smallest by more than this share of
        the smallest (>= 0) is an edge and reads its smallest depth; otherwise its mean.
    min_height, max_height : float
        Metres above the road plane that an obstacle block's point must be within
        (0 <= min_height < max_height): below is road, kerb or debris too low to matter,
        above is what the car passes under.
    corridor_half_width : float
        Half width of the default straight corridor, metres > 0: the ego lane (3.5 m) and
        half of each neighbour, where the traffic that the target 1 - USC~ counts is (1.75 m,
        the car's half width plus a margin, is the ego lane alone: half the recall).
    max_range : float
        Farthest camera depth of an obstacle block and of the corridor's road that must be
        seen, metres, finite > 0 (the paper's 20 m).
    cell_size : float
        Side of the ground grid's cells, metres > 0: things on the ground separated by a
        free cell are different objects.
    depth_percentile : float
        Percentile (0..100) of an object's block depths that is its depth d.
    min_points : int
        Blocks (>= 1) an object must have inside the corridor.
    min_size : float
        Smallest box side, pixels >= 0: a 0.2 m pole 20 m away is 13 px wide in nuScenes'
        front camera; a narrower box is a sliver of a surface seen edge-on (a car's side
        beyond its rear), cut off from its object where the grid sees a gap.
    ground_range : float
        Blocks farther ahead than this ego x (metres > 0) are not road candidates.
    ground_tolerance : float
        Vertical distance (metres > 0) within which a block counts as on the road plane.
    max_tilt_deg : float
        Largest tilt of a fitted road plane from the mounting's ground ``z = 0``, degrees in
        [0, 45).
    max_height_offset : float
        Largest height of a fitted road plane at the ego origin, metres >= 0.
    ransac_iterations : int
        Plane hypotheses (>= 1).
    ransac_score_points : int
        Candidates (>= 3) a hypothesis is scored on (evenly spaced among them).
    min_ground_fraction : float
        Share of all blocks that must support a fitted plane; less falls back to ``z = 0``.
    below_margin : float
        Metres > 0: a block this far under the road plane is impossible.
    max_below_fraction : float
        Largest share of valid blocks under the road by ``below_margin``.
    max_invalid_fraction : float
        Largest share of invalid pixels in the frame.
    max_corridor_invalid_fraction : float
        Largest share of invalid pixels among those that look at the corridor's road within
        ``max_range`` (by the mounting's ground plane).
    seed : int
        Seed (>= 0) of the RANSAC's random triples (the same every frame).
    structure_height : float or None
        Metres above the road (> ``max_height``): the ground cells under a block this high,
        and their neighbours, hold structure, not traffic (None: the rule is off). Road
        vehicles stay under 4.0 m in the EU, 4.1-4.3 m in North America.
    max_incline : float or None
        An object whose inverse depth grows down the image by more than this share of the
        road's (> 0) lies along the road rather than standing on it; None: the rule is off.
    min_contact : float
        Share in [0, 1]: an object that lies along the road (``max_incline``) and stands on
        the road or on something in front of it in fewer than this share of its columns
        (the road beneath it seen no farther than ``CONTACT_RATIO`` times its depth) floats
        above the road, and is not an object. One with nothing valid beneath it floats when
        its incline exceeds the larger of ``max_incline`` and ``UNSUPPORTED_INCLINE``.
    min_occlusion : float or None
        Share in [0, 1]: an object that hides what is behind it (see the module's rule 6; a
        flat one by its depth) in fewer than this share of its columns is a patch of road
        read too near, not an object; None: the rule is off.
    ledge_height, ledge_width : float or None, float
        An object whose top is under ``ledge_height`` metres above the road (``min_height <
        ledge_height <= max_height``), whose lateral span is under ``ledge_width`` metres
        (> 0) and which reaches along the road more than ``LEDGE_ELONGATION`` times that is a
        ledge along the road, a kerb (module, rule 7); ``ledge_height`` None: the rule is off.
    min_rise : float or None
        Metres (> 0): a block rises when the points of its ground cell, or of a neighbour,
        span this much in height, and an object's ``extents`` come from its blocks that
        rise (module, rule 8); None: from all its blocks.
    """

    stride: int = 4
    edge_spread: float = 0.15
    min_height: float = 0.2
    max_height: float = 2.5
    corridor_half_width: float = 3.5
    max_range: float = DEFAULT_RANGE_M
    cell_size: float = 0.3
    depth_percentile: float = 5.0
    min_points: int = 6
    min_size: float = 12.0
    ground_range: float = 30.0
    ground_tolerance: float = 0.15
    max_tilt_deg: float = 6.0
    max_height_offset: float = 0.5
    ransac_iterations: int = 100
    ransac_score_points: int = 2000
    min_ground_fraction: float = 0.02
    below_margin: float = 0.5
    max_below_fraction: float = 0.2
    max_invalid_fraction: float = 0.5
    max_corridor_invalid_fraction: float = 0.5
    seed: int = 0
    structure_height: float | None = 4.2
    max_incline: float | None = 0.5
    min_contact: float = 0.9
    min_occlusion: float | None = 0.25
    ledge_height: float | None = 0.3
    ledge_width: float = 0.4
    min_rise: float | None = 0.15

    def __post_init__(self):
        for name, low in (("stride", 1), ("min_points", 1), ("ransac_iterations", 1),
                          ("ransac_score_points", 3), ("seed", 0)):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < low:
                raise ValueError(f"{name} = {value!r}, must be an integer >= {low}")
        positive = ("max_range", "corridor_half_width", "cell_size", "ground_range",
                    "ground_tolerance", "below_margin")
        for name in positive:
            value = getattr(self, name)
            if not (isinstance(value, (int, float)) and math.isfinite(value) and value > 0):
                raise ValueError(f"{name} = {value!r}, must be a finite number > 0")
        for name in ("edge_spread", "min_height", "max_height", "max_height_offset", "min_size"):
            value = getattr(self, name)
            if not (isinstance(value, (int, float)) and math.isfinite(value) and value >= 0):
                raise ValueError(f"{name} = {value!r}, must be a finite number of metres >= 0")
        if not self.min_height < self.max_height:
            raise ValueError(f"min_height = {self.min_height} and max_height = {self.max_height}: "
                             "min_height must be below max_height (metres above the road)")
        height = self.structure_height
        if height is not None and not (isinstance(height, (int, float)) and not isinstance(height, bool)
                                       and math.isfinite(height) and height > 0):
            raise ValueError(f"structure_height = {height!r}, must be a finite number of metres > 0 "
                             "or None (off)")
        if height is not None and not height > self.max_height:
            raise ValueError(f"structure_height = {height} and max_height = {self.max_height}: "
                             "structure_height must be above max_height (metres above the road)")
        incline = self.max_incline
        if incline is not None and not (isinstance(incline, (int, float)) and not isinstance(incline, bool)
                                        and math.isfinite(incline) and incline > 0):
            raise ValueError(f"max_incline = {incline!r}, must be a finite share of the road's "
                             "inverse-depth slope > 0, or None (off)")
        if not 0 <= self.depth_percentile <= 100:
            raise ValueError(f"depth_percentile = {self.depth_percentile!r}, must be in [0, 100]")
        if not 0 <= self.max_tilt_deg < 45:
            raise ValueError(f"max_tilt_deg = {self.max_tilt_deg!r}, must be in [0, 45) degrees")
        for name in ("min_ground_fraction", "max_below_fraction", "max_invalid_fraction",
                     "max_corridor_invalid_fraction", "min_contact"):
            value = getattr(self, name)
            if not 0 <= value <= 1:
                raise ValueError(f"{name} = {value!r}, must be a share in [0, 1]")
        ledge = self.ledge_height
        if ledge is not None and not (isinstance(ledge, (int, float)) and not isinstance(ledge, bool)
                                      and self.min_height < ledge <= self.max_height):
            raise ValueError(f"ledge_height = {ledge!r}, must be metres above the road over min_height = "
                             f"{self.min_height} and up to max_height = {self.max_height}, or None (off)")
        width = self.ledge_width
        if not (isinstance(width, (int, float)) and not isinstance(width, bool) and math.isfinite(width)
                and width > 0):
            raise ValueError(f"ledge_width = {width!r}, must be a finite number of metres > 0")
        rise = self.min_rise
        if rise is not None and not (isinstance(rise, (int, float)) and not isinstance(rise, bool)
                                     and math.isfinite(rise) and rise > 0):
            raise ValueError(f"min_rise = {rise!r}, must be a finite number of metres > 0, or None "
                             "(extents from all of an object's blocks)")
        occlusion = self.min_occlusion
        if occlusion is not None and not (isinstance(occlusion, (int, float)) and not isinstance(occlusion, bool)
                                          and 0 <= occlusion <= 1):
            raise ValueError(f"min_occlusion = {occlusion!r}, must be a share in [0, 1], or None (off)")


@dataclass(frozen=True)
class GeometricView:
    """What the geometric view saw in one frame.

    Attributes
    ----------
    boxes : ndarray of shape (m, 5), float64
        The objects S: rows ``cx, cy, w, h, d`` (pixels, metres), nearest first; (0, 5) if
        none.
    extents : ndarray of shape (m, 3), float64
        Where each object stands in the ego frame, from its blocks: ``x`` its nearest
        corridor block's ego x, ``y_min, y_max`` the ``depth_percentile`` and the
        ``100 - depth_percentile`` percentile of its blocks' ego y (as robust to stray blocks
        as its depth), metres; rows as ``boxes``. With ``min_rise``, from its blocks that
        rise where it has any (the module's rule 8).
    contact : ndarray of shape (m,), float64
        Per object (rows as ``boxes``), the share in [0, 1] of its columns in which it stands
        on the road or on something in front of it: the first valid blocks beneath its lowest
        block no farther than ``CONTACT_RATIO`` times its depth (rule 5). NaN where no column
        has a valid block beneath it (the image's bottom edge cuts it, or the depth below is
        invalid).
    free_distance : float
        Ego x (metres, from the ego origin) of the nearest obstacle block of an object
        inside the corridor; inf when no object is there within ``max_range``.
    ground : ndarray of shape (3,), float64
        The road plane used, ``z = a x + b y + c`` as ``(a, b, c)`` in the ego frame.
    ground_fitted : bool
        True when ``ground`` was fitted to this frame, False when it is the mounting's
        ``z = 0`` (too little support for a plane within the bounds).
    ground_support : float
        Share of all blocks within ``ground_tolerance`` of the fitted plane (0 for the
        fallback).
    valid_fraction : float
        Share of valid pixels in the frame.
    corridor_valid_fraction : float
        Share of valid pixels among those looking at the corridor's road (1 if none do).
    below_ground_fraction : float
        Share of valid blocks more than ``below_margin`` under the plane used.
    road_depth : ndarray of shape (H / stride, W / stride), float16, or None
        Per block, the camera depth (metres) of the road it showed (less than ``min_height``
        above the plane used and at most ``below_margin`` under it); 0 where it showed
        something else, NaN where it had no valid pixel. A later frame's ``before``
        (rule 9); float16 (2-3 significant digits suffice, and a run keeps one per frame).
        None from a retriever that does not keep the blocks (``keep_blocks``).
    points : tuple of ndarray of shape (n_i, 3), float64
        Per object (rows as ``boxes``), its blocks in the ego frame (``x, y, z``, metres),
        for :meth:`GeometricRetriever.emerged` (rule 9) in a later frame. Empty from a
        retriever that does not keep the blocks.
    """

    boxes: np.ndarray
    extents: np.ndarray
    contact: np.ndarray
    free_distance: float
    ground: np.ndarray
    ground_fitted: bool
    ground_support: float
    valid_fraction: float
    corridor_valid_fraction: float
    below_ground_fraction: float
    road_depth: np.ndarray | None
    points: tuple


class GeometricRetriever:
    """The geometric view for one camera: the parameters, the rays and scratch memory.

    Use one per camera in a frame loop: it reuses its scratch buffers from frame to frame
    (one set per thread, so an instance may be shared between threads).

    Parameters
    ----------
    camera : Camera
        Intrinsics, image size and mounting; its centre must be above the ground.
    params : GeometricParams
    keep_blocks : bool
        Give each view's :attr:`~GeometricView.road_depth` and :attr:`~GeometricView.points`
        (rule 9; the default). Without them (None and empty) a view costs a float16 copy of
        the road's depth less (about 0.3 ms per 1600 x 900 frame) and a run that keeps its
        views keeps 2 bytes per block less.
    """

    def __init__(self, camera: Camera, params: GeometricParams = GeometricParams(), *,
                 keep_blocks: bool = True):
        if not isinstance(camera, Camera):
            raise ValueError(f"camera is a {type(camera).__name__}, expected a Camera")
        if not isinstance(params, GeometricParams):
            raise ValueError(f"params is a {type(params).__name__}, expected GeometricParams")
        if not isinstance(keep_blocks, bool):
            raise ValueError(f"keep_blocks = {keep_blocks!r}, expected True or False")
        self.keep_blocks = keep_blocks
        origin = camera.cam_to_ego[:3, 3]
        if not origin[2] > 0:
            raise ValueError(f"the camera centre is at z = {origin[2]!r} m in the ego frame; it "
                             "must be above the ground plane z = 0")
        self.camera, self.params = camera, params
        s = params.stride
        rows, cols = -(-camera.height // s), -(-camera.width // s)
        self._M = np.ascontiguousarray(camera.cam_to_ego[:3, :3] @ np.linalg.inv(camera.K))
        self._origin = np.ascontiguousarray(origin)
        self._blocks = (rows, cols)
        self._local = threading.local()
        self._uniforms = np.random.default_rng(params.seed).random((params.ransac_iterations, 3))
        # where each block centre's ray meets the nominal ground, and the block sizes
        i0 = np.arange(rows) * s
        j0 = np.arange(cols) * s
        v = 0.5 * (i0 + np.minimum(i0 + s, camera.height))
        u = 0.5 * (j0 + np.minimum(j0 + s, camera.width))
        rays = (self._M[:, 0, None, None] * u[None, None, :] + self._M[:, 1, None, None] * v[None, :, None]
                + self._M[:, 2, None, None])
        with np.errstate(divide="ignore"):
            t = np.where(rays[2] < 0, -origin[2] / rays[2], np.inf)
        self._ground_d = t.ravel()
        self._ground_x = np.where(np.isfinite(t), origin[0] + t * rays[0], np.inf).ravel()
        self._ground_y = np.where(np.isfinite(t), origin[1] + t * rays[1], np.inf).ravel()
        self._block_px = np.outer(np.minimum(i0 + s, camera.height) - i0,
                                  np.minimum(j0 + s, camera.width) - j0).astype(np.int32).ravel()
        # every point within max_range (camera depth) is origin + d * ray, 0 < d <= max_range,
        # with the ray inside the corner rays' rectangle: the ground grid and the corridor
        # table span the extremes of that set (plus a cell)
        corners = np.array([[0, 0, 1], [camera.width, 0, 1], [0, camera.height, 1],
                            [camera.width, camera.height, 1]], dtype=np.float64) @ self._M.T
        low = origin[:2] + params.max_range * np.minimum(corners[:, :2].min(axis=0), 0.0) - params.cell_size
        high = origin[:2] + params.max_range * np.maximum(corners[:, :2].max(axis=0), 0.0) + params.cell_size
        self._grid_origin = (float(low[0]), float(low[1]))
        self._grid_shape = tuple(int(n) for n in np.ceil((high - low) / params.cell_size))
        self._x_end = float(max(high[0], CORRIDOR_STEP_M))
        self._default_corridor = Corridor(params.corridor_half_width)
        self._default_table = self._default_corridor.table(self._x_end, CORRIDOR_STEP_M)
        self._default_footprint = self._footprint(self._default_corridor, self._default_table)

    def _footprint(self, corridor: Corridor, table) -> tuple[np.ndarray, int]:
        """The blocks that look at ``corridor``'s road within ``max_range`` (by the mounting's
        ground plane), and how many pixels they hold."""
        out = np.empty(self._ground_d.size, dtype=np.int64)
        n = kernels.footprint_blocks(self._ground_x, self._ground_y, self._ground_d,
                                     self.params.max_range, *table, CORRIDOR_STEP_M,
                                     corridor.half_width, out)
        return out[:n].copy(), int(self._block_px[out[:n]].sum())

    def _scratch(self) -> threading.local:
        """This thread's buffers (made on its first frame)."""
        local = self._local
        if not hasattr(local, "points"):
            rows, cols = self._blocks
            local.points = np.empty((4, rows, cols), dtype=np.float32)  # x, y, z, d
            local.invalid_px = np.empty((rows, cols), dtype=np.int32)
            local.obstacle = np.empty((rows, cols), dtype=np.uint8)
            local.corridor = np.empty((rows, cols), dtype=np.uint8)
            local.tall = np.empty((rows, cols), dtype=np.uint8)
            local.road = np.empty((rows, cols), dtype=np.float32)  # GeometricView.road_depth
            local.object_points = np.empty((rows * cols, 3), dtype=np.float64)
            local.labels = np.empty((rows, cols), dtype=np.int32)
            local.candidates = np.empty(rows * cols, dtype=np.int64)
            local.grid = np.empty(self._grid_shape, dtype=np.int32)
            local.low = np.empty(self._grid_shape, dtype=np.float32)  # heights per cell (rule 8)
            local.high = np.empty(self._grid_shape, dtype=np.float32)
            local.grid_ids = np.empty(self._grid_shape, dtype=np.int32)
        return local

    def __call__(self, depth: np.ndarray, corridor: Corridor | None = None) -> np.ndarray:
        """The objects S of one depth map: :meth:`view`'s ``boxes``."""
        return self.view(depth, corridor).boxes

    def view(self, depth: np.ndarray, corridor: Corridor | None = None) -> GeometricView:
        """What stands on the road inside the corridor, for one depth map.

        Parameters
        ----------
        depth : ndarray of shape (H, W), float32
            Camera-frame depth, metres, of the camera's size; NaN, inf and <= 0 are invalid.
        corridor : Corridor, optional
            This frame's corridor (the ego's path and half width); default straight ahead
            with ``params.corridor_half_width``.

        Returns
        -------
        GeometricView

        Raises
        ------
        BlindViewError
            The frame cannot be seen through (see the module's description).
        ValueError
            A depth map of the wrong type or size, or a corridor that is not a Corridor.
        """
        depth = self._check_depth(depth)
        params, cam = self.params, self.camera
        if corridor is None:
            corridor, table = self._default_corridor, self._default_table
            footprint = self._default_footprint
        elif isinstance(corridor, Corridor):
            table = corridor.table(self._x_end, CORRIDOR_STEP_M)
            footprint = self._footprint(corridor, table)
        else:
            raise ValueError(f"corridor is a {type(corridor).__name__}, expected a Corridor or None")
        centre_y, tan_heading = table
        scratch = self._scratch()
        xs, ys, zs, ds = scratch.points
        n_invalid = kernels.block_points(depth, params.stride, params.edge_spread, self._M,
                                         self._origin, xs, ys, zs, ds, scratch.invalid_px)
        invalid_fraction = n_invalid / depth.size
        if invalid_fraction > params.max_invalid_fraction:
            raise BlindViewError("invalid", invalid_fraction, params.max_invalid_fraction)
        blocks, n_px = footprint
        corridor_invalid = int(scratch.invalid_px.ravel()[blocks].sum()) / n_px if n_px else 0.0
        if corridor_invalid > params.max_corridor_invalid_fraction:
            raise BlindViewError("corridor_invalid", corridor_invalid,
                                 params.max_corridor_invalid_fraction)

        x, y, z, d = (a.ravel() for a in scratch.points)
        ground, support = self._fit_ground(x, y, z, d, scratch.candidates)
        a, b, c = ground
        n_valid, n_below = kernels.classify(
            x, y, z, d, a, b, c, params.min_height, params.max_height, params.max_range,
            params.below_margin, centre_y, tan_heading, CORRIDOR_STEP_M, corridor.half_width,
            math.inf if params.structure_height is None else params.structure_height,
            scratch.obstacle.ravel(), scratch.corridor.ravel(), scratch.tall.ravel(), scratch.road.ravel())
        below = n_below / n_valid if n_valid else 0.0
        if below > params.max_below_fraction:
            raise BlindViewError("below_ground", below, params.max_below_fraction)

        if params.structure_height is not None:
            kernels.clear_structure(xs, ys, scratch.tall, *self._grid_origin, params.cell_size,
                                    scratch.grid, scratch.obstacle, scratch.corridor)
        n = kernels.label_objects(xs, ys, scratch.obstacle, *self._grid_origin, params.cell_size,
                                  scratch.grid, scratch.grid_ids, scratch.labels)
        stats = kernels.object_stats(scratch.labels, n, scratch.corridor, ds, xs, ys, params.min_points,
                                     params.depth_percentile, params.depth_percentile)
        s = params.stride
        x0, y0 = stats[:, 2] * s, stats[:, 0] * s
        x1 = np.minimum((stats[:, 3] + 1) * s, cam.width)
        y1 = np.minimum((stats[:, 1] + 1) * s, cam.height)
        boxes = np.column_stack([0.5 * (x0 + x1), 0.5 * (y0 + y1), x1 - x0, y1 - y0, stats[:, 7]])
        keep = np.isfinite(stats[:, 7]) & (boxes[:, 2] >= params.min_size) \
            & (boxes[:, 3] >= params.min_size)
        if params.ledge_height is not None:
            keep &= ~self._ledges(scratch.labels, keep, stats[:, 9] - stats[:, 8], scratch.points, ground)
        extents = stats[:, [6, 8, 9]]
        flat = np.zeros(keep.size, dtype=bool)  # rule 8: none of its blocks rises
        if params.min_rise is not None and keep.any():
            index = np.full(keep.size, -1, dtype=np.int64)
            index[keep] = np.arange(int(keep.sum()))
            standing = kernels.standing(scratch.labels, index, scratch.corridor, xs, ys, zs, ds,
                                        np.array(ground, dtype=np.float64), 0.5 * params.min_height,
                                        params.max_height, *self._grid_origin, params.cell_size,
                                        scratch.low, scratch.high, params.min_rise, params.depth_percentile,
                                        int(stats[keep, 0].min()), int(stats[keep, 1].max()))
            extents[keep] = standing[:, :3]
            flat[keep] = standing[:, 3] == 0
        contact = np.full(keep.size, np.nan)
        if keep.any():
            dropped, contact[keep] = self._no_object(scratch.labels, keep, scratch.points, ground, flat[keep])
            keep[keep] = ~dropped
        order = np.argsort(boxes[keep, 4], kind="stable")
        points, road_depth = (), None
        if self.keep_blocks:
            row_of = np.full(n + 1, -1, dtype=np.int64)  # component -> row of boxes; label -1 -> -1
            row_of[np.flatnonzero(keep)[order]] = np.arange(order.size)
            offsets = np.empty(order.size + 1, dtype=np.int64)
            kernels.object_points(scratch.labels, row_of, xs, ys, zs, order.size, scratch.object_points, offsets)
            points = tuple(scratch.object_points[offsets[k]:offsets[k + 1]].copy() for k in range(order.size))
            road_depth = scratch.road.astype(np.float16)
        return GeometricView(
            boxes=boxes[keep][order],
            extents=extents[keep][order],
            contact=contact[keep][order],
            free_distance=float(stats[keep, 6].min()) if keep.any() else math.inf,
            ground=np.array(ground, dtype=np.float64),
            ground_fitted=support > 0,
            ground_support=support,
            valid_fraction=1.0 - invalid_fraction,
            corridor_valid_fraction=1.0 - corridor_invalid,
            below_ground_fraction=below,
            road_depth=road_depth,
            points=points,
        )

    def emerged(self, points, before: np.ndarray, travel: float) -> np.ndarray:
        """Rule 9: per object, the share of its blocks behind whose place an earlier frame
        saw the road.

        Parameters
        ----------
        points : sequence of ndarray of shape (n_i, 3)
            Objects' blocks in the ego frame now (:attr:`GeometricView.points`, or some of them).
        before : ndarray of shape (H / stride, W / stride), float16
            The earlier frame's :attr:`GeometricView.road_depth`.
        travel : float
            Metres the ego moved forward (along its x) since the earlier frame; negative
            when it backed.

        Returns
        -------
        ndarray of shape (len(points),), float64
            The share in [0, 1] of the blocks, among those that land on valid blocks of
            ``before``, that land on road farther than their own camera depth then by more
            than ``EMERGED_MARGIN``; NaN where fewer than ``MIN_EMERGED_BLOCKS`` land on valid
            blocks (out of its image, or invalid there).
        """
        if not (isinstance(before, np.ndarray) and before.dtype == np.float16 and before.shape == self._blocks):
            what = f"an array of {before.dtype} {before.shape}" if isinstance(before, np.ndarray) \
                else f"a {type(before).__name__}"
            raise ValueError(f"before is {what}, expected the road an earlier frame's view of this camera "
                             f"saw (GeometricView.road_depth: float16 {self._blocks})")
        if isinstance(travel, bool) or not isinstance(travel, numbers.Real) or not math.isfinite(travel):
            raise ValueError(f"travel = {travel!r}, expected the finite metres the ego moved since before's frame")
        m = len(points)
        if m == 0:
            return np.zeros(0)
        which = np.repeat(np.arange(m), [len(p) for p in points])
        moved = np.concatenate(points) + np.array([float(travel), 0.0, 0.0])
        cam = moved @ self.camera.ego_to_cam[:3, :3].T + self.camera.ego_to_cam[:3, 3]
        ahead = cam[:, 2] > 0
        uv = (cam[ahead] @ self.camera.K[:2].T) / cam[ahead, 2:3]
        s = self.params.stride
        i, j = np.floor(uv[:, 1] / s), np.floor(uv[:, 0] / s)
        inside = (i >= 0) & (i < before.shape[0]) & (j >= 0) & (j < before.shape[1])
        road = before[i[inside].astype(np.int64), j[inside].astype(np.int64)].astype(np.float64)
        which = which[ahead][inside]
        valid = np.bincount(which[~np.isnan(road)], minlength=m)
        beyond = np.bincount(which[road > cam[ahead][inside, 2] * (1.0 + EMERGED_MARGIN)], minlength=m)
        with np.errstate(invalid="ignore", divide="ignore"):
            return np.where(valid >= MIN_EMERGED_BLOCKS, beyond / valid, np.nan)

    def _ledges(self, labels, keep, across, points, ground) -> np.ndarray:
        """Which components are ledges along the road (rule 7), bool (n,): among the kept
        ones (``keep``, bool (n,)) narrower than ``ledge_width`` (``across``, their lateral
        spans, metres), those lower than ``ledge_height`` and longer than
        ``LEDGE_ELONGATION`` times their span."""
        p = self.params
        out = np.zeros(keep.size, dtype=bool)
        narrow = np.flatnonzero(keep & (across < p.ledge_width))
        if narrow.size:
            index = np.full(keep.size, -1, dtype=np.int64)
            index[narrow] = np.arange(narrow.size)
            xs, ys, zs, _ = points
            top, along = kernels.ledge_shape(labels, index, xs, ys, zs, np.array(ground, dtype=np.float64),
                                             p.depth_percentile, TOP_PERCENTILE).T
            out[narrow] = (top < p.ledge_height) & (along > LEDGE_ELONGATION * across[narrow])
        return out

    def _no_object(self, labels, keep, points, ground, flat) -> tuple[np.ndarray, np.ndarray]:
        """Which of the kept components (``keep``, bool (n,)) are no objects: those that
        float (rule 5: ``max_incline``, ``min_contact``) or hide nothing (rule 6:
        ``min_occlusion``; ``flat``, bool (kept,), the components none of whose blocks
        rises, must hide by their depth), bool (kept,); and each one's contact (rule 5's
        share of its columns standing on something, NaN where none has a valid block beneath
        it), float64 (kept,).

        The road plane ``z = a x + b y + c`` seen through the pixel ``(u, v)`` has the inverse
        camera depth ``(r_z - a r_x - b r_y) / (a o_x + b o_y + c - o_z)``, with ``r = M (u,
        v, 1)`` the pixel's ray per metre of camera depth and ``o`` the camera centre: affine
        in the pixel, as v-disparity has it, ``q0 + qu u + qv v`` with ``qv`` the slope down
        the image.
        """
        p = self.params
        a, b, c = ground
        M, o = self._M, self._origin
        qu, qv, q0 = (M[2] - a * M[0] - b * M[1]) / (a * o[0] + b * o[1] + c - o[2])
        out = np.zeros(int(keep.sum()), dtype=bool)
        index = np.full(keep.size, -1, dtype=np.int64)
        index[keep] = np.arange(out.size)
        xs, ys, zs, ds = points
        # the road's slope scales the incline alone, which is not read when it is not > 0
        shape = kernels.surface_shape(labels, index, ds, p.stride, qv if qv > 0 else 1.0, CONTACT_RATIO,
                                      EDGE_BLOCKS)
        incline, contact = shape[:, 0], shape[:, 1]
        if not qv > 0:  # the image's rows do not run down the road: no rule to apply
            return out, contact
        if p.max_incline is not None:
            out |= (incline > p.max_incline) & (contact < p.min_contact)
            out |= np.isnan(contact) & (incline > max(p.max_incline, UNSUPPORTED_INCLINE))
        if p.min_occlusion is not None:
            hides = kernels.occlusion(labels, index, ds, xs, ys, zs, np.array(ground, dtype=np.float64),
                                      np.array([q0, qu, qv]), p.stride, p.min_height, OCCLUSION_RATIO,
                                      EDGE_BLOCKS)
            out |= np.where(flat, hides[:, 1], hides[:, 0]) < p.min_occlusion
        return out, contact

    def _fit_ground(self, x, y, z, d, candidates) -> tuple[tuple[float, float, float], float]:
        """The road plane ``(a, b, c)`` and its support (share of all blocks), or the
        mounting's ``(0, 0, 0)`` and 0 when no plane within the bounds has enough support."""
        p = self.params
        max_slope = math.tan(math.radians(p.max_tilt_deg))
        band0 = p.max_height_offset + p.ground_tolerance
        n = kernels.ground_candidates(x, y, z, d, p.ground_range, band0, max_slope, candidates)
        a, b, c, score = kernels.ransac_plane(x, y, z, candidates, n, self._uniforms,
                                              p.ransac_score_points, p.ground_tolerance,
                                              max_slope, p.max_height_offset)
        if score == 0:
            return (0.0, 0.0, 0.0), 0.0
        for _ in range(2):
            a, b, c, inliers = kernels.refine_plane(x, y, z, candidates, n, a, b, c,
                                                    p.ground_tolerance)
        support = inliers / d.size
        within = a * a + b * b <= max_slope * max_slope and abs(c) <= p.max_height_offset
        if support < p.min_ground_fraction or not within:
            return (0.0, 0.0, 0.0), 0.0
        return (a, b, c), support

    def _check_depth(self, depth: np.ndarray) -> np.ndarray:
        if not isinstance(depth, np.ndarray) or depth.dtype != np.float32 or depth.ndim != 2:
            raise ValueError(
                f"depth: {type(depth).__name__} of shape {getattr(depth, 'shape', None)} and dtype "
                f"{getattr(depth, 'dtype', None)}, expected a float32 (H, W) array in metres")
        expected = (self.camera.height, self.camera.width)
        if depth.shape != expected:
            raise ValueError(f"depth is {depth.shape[1]}x{depth.shape[0]} (W x H), the camera's "
                             f"image is {expected[1]}x{expected[0]}")
        return np.ascontiguousarray(depth)


def warmup() -> None:
    """Compile (or load from Numba's disk cache) every kernel, on a tiny frame."""
    front = Camera.nuscenes_front()
    tiny = Camera(np.diag([0.02, 0.02, 1.0]) @ front.K, 32, 18, front.cam_to_ego)
    retriever = GeometricRetriever(tiny, GeometricParams(stride=1, min_points=1))
    depth = np.minimum(retriever._ground_d.reshape(18, 32), 50.0).astype(np.float32)
    depth[4:12, 12:20] = 8.0  # a wall 8 m ahead above the road: every kernel runs
    retriever.view(depth)
