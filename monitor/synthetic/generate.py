"""Synthetic driving scenes: layout, ray cast, depth estimate and detections per frame.

One scene is a :class:`~monitor.synthetic.scene.Layout` (road, ego speed, actors) seen at
``n_frames`` times ``0, dt, 2 dt, ...`` (nuScenes' key frames come at 2 Hz: ``dt = 0.5 s``).
Per frame: the actors within reach are the ground truth, the ray cast of them and of the
street's static structure gives the true depth and the label map, :func:`~monitor.synthetic.degrade.estimate_depth` the estimated depth
and :func:`~monitor.synthetic.degrade.detect` the detections, all under the condition's
degradations.

Random numbers: the seed's :class:`numpy.random.SeedSequence` is split into one stream for
the layout and one per frame, and each frame's into one for the depth estimate and one for
the detector. So the same seed gives the same traffic in every condition (a condition's
rare-object rate only adds rare actors), and changing the depth errors does not change the
detections, nor the detector errors the depth estimate.
"""
from __future__ import annotations

import math
from typing import Iterator

import numpy as np

from monitor.geometry.camera import Camera
from monitor.datasets.frames import Frame, Scene
from monitor.synthetic.conditions import Condition, get_condition
from monitor.synthetic.degrade import REFERENCE_WIDTH_PX, detect, estimate_depth
from monitor.synthetic.raycast import ground_points, render_depth
from monitor.synthetic.scene import GroundPainter, make_layout

#: nuScenes key frames: 2 Hz
FRAME_INTERVAL_S = 0.5
N_FRAMES = 20


def _check_arguments(seed, n_frames, frame_interval, camera) -> Camera:
    if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or seed < 0:
        raise ValueError(f"seed = {seed!r}, must be an integer >= 0")
    if isinstance(n_frames, bool) or not isinstance(n_frames, (int, np.integer)) or n_frames < 1:
        raise ValueError(f"n_frames = {n_frames!r}, must be an integer >= 1")
    if not (isinstance(frame_interval, (int, float)) and math.isfinite(frame_interval)
            and frame_interval > 0):
        raise ValueError(
            f"frame_interval = {frame_interval!r}, must be a finite number > 0 (seconds)")
    if camera is None:
        return Camera.nuscenes_front()
    if not isinstance(camera, Camera):
        raise ValueError(f"camera is a {type(camera).__name__}, expected a Camera or None")
    return camera


def generate_frames(condition: str | Condition = "nominal", seed: int = 0, *,
                    n_frames: int = N_FRAMES, frame_interval: float = FRAME_INTERVAL_S,
                    camera: Camera | None = None) -> Iterator[Frame]:
    """Generate a synthetic scene frame by frame (one frame in memory at a time).

    Parameters
    ----------
    condition : str or Condition
        A key of :data:`~monitor.synthetic.conditions.CONDITIONS` or a Condition.
    seed : int
        >= 0; the same seed gives identical frames.
    n_frames : int
        >= 1.
    frame_interval : float
        Seconds between frames.
    camera : Camera, optional
        Default :meth:`Camera.nuscenes_front` (1600 x 900). Pixel parameters of the
        condition scale with its width.

    Returns
    -------
    iterator of Frame
        Frames with ``depth_true`` and ``labels`` filled in. The arguments are checked
        at once, the frames made as the iterator is advanced.
    """
    cond = get_condition(condition)
    camera = _check_arguments(seed, n_frames, frame_interval, camera)
    return _frames(cond, int(seed), int(n_frames), float(frame_interval), camera)


def _frames(cond: Condition, seed: int, n_frames: int, frame_interval: float,
            camera: Camera) -> Iterator[Frame]:
    layout_seq, frames_seq = np.random.SeedSequence(seed).spawn(2)
    layout = make_layout(layout_seq, (n_frames - 1) * frame_interval, cond.rare_per_scene)
    painter = GroundPainter(layout.road, *ground_points(camera))
    px_scale = camera.width / REFERENCE_WIDTH_PX
    for index, frame_seq in enumerate(frames_seq.spawn(n_frames)):
        depth_rng, detector_rng = (np.random.default_rng(s) for s in frame_seq.spawn(2))
        t = index * frame_interval
        boxes, classes, ids = layout.frame_boxes(t)
        render = render_depth(camera, boxes, *layout.frame_structure(t))
        depth_est = estimate_depth(render.depth, render.labels, render.background, cond.depth,
                                   depth_rng, px_scale)
        visibility = render.visibility
        detections = detect(camera, boxes, classes, visibility, render.visible_px,
                            cond.detector, detector_rng)
        yield Frame(
            index=index, timestamp=t, ego_speed=float(layout.ego_speed), camera=camera,
            depth_est=depth_est, depth_true=render.depth,
            labels=painter.paint(render.labels, layout.ego_x(t)),
            gt_boxes3d=boxes, gt_classes=classes, gt_ids=ids, gt_visibility=visibility,
            det_boxes3d=detections.boxes3d, det_classes=detections.classes,
            det_scores=detections.scores,
        )


def generate_scene(condition: str | Condition = "nominal", seed: int = 0, *,
                   n_frames: int = N_FRAMES, frame_interval: float = FRAME_INTERVAL_S,
                   camera: Camera | None = None, name: str | None = None) -> Scene:
    """Generate a whole synthetic scene in memory (see :func:`generate_frames`).

    A 1600 x 900 frame holds about 14 MB of maps; stream with :func:`generate_frames`
    when that matters.

    Parameters
    ----------
    name : str, optional
        Default ``"synthetic-{condition}-{seed}"``.

    Returns
    -------
    Scene
        ``synthetic=True``.
    """
    cond = get_condition(condition)
    camera = _check_arguments(seed, n_frames, frame_interval, camera)
    frames = tuple(generate_frames(cond, seed, n_frames=n_frames,
                                   frame_interval=frame_interval, camera=camera))
    return Scene(name=name or f"synthetic-{cond.name}-{seed}", camera=camera,
                 condition=cond.name, seed=int(seed), synthetic=True, frames=frames)


def warm_up() -> None:
    """Compile (or load from Numba's cache) every kernel a scene needs, on a tiny frame."""
    front = Camera.nuscenes_front()
    tiny = Camera(np.diag([0.02, 0.02, 1.0]) @ front.K, 32, 18, front.cam_to_ego)
    for _ in generate_frames("nominal", 0, n_frames=1, camera=tiny):
        pass
