"""Synthetic driving scenes: the stand-in for nuScenes, PGD and ZoeDepth.

Real data cannot be downloaded here, so the main command and the evaluation run on
generated scenes (every report on them says so): a pinhole camera with nuScenes CAM_FRONT
geometry over a flat road with cars, trucks, buses, motorcycles, cyclists, pedestrians
and rare objects (animals, wheelchairs, debris) moving as 3D boxes; the true depth by ray
casting; a depth estimate degraded like a monocular network's and detections degraded
like a monocular 3D detector's, under the paper's six conditions.

>>> from monitor.synthetic import generate_scene
>>> scene = generate_scene("night", seed=3, n_frames=20)       # doctest: +SKIP
>>> frame = scene.frames[0]; frame.depth_est, frame.det_boxes3d  # doctest: +SKIP

Modules: :mod:`~monitor.synthetic.scene` (road, actors, motion),
:mod:`~monitor.synthetic.raycast` (true depth), :mod:`~monitor.synthetic.degrade` (error
models), :mod:`~monitor.synthetic.conditions` (the degradation tables),
:mod:`~monitor.synthetic.generate` (frames and scenes), :mod:`~monitor.synthetic.shade`
(a picture to draw boxes on).
"""
from monitor.synthetic.conditions import (
    CONDITIONS, DEPTH_ERROR_PARTS, Condition, DepthErrors, DetectorErrors, get_condition, without_depth_errors,
)
from monitor.synthetic.generate import generate_frames, generate_scene, warm_up
from monitor.synthetic.raycast import DepthRender, render_depth
from monitor.synthetic.shade import shade

__all__ = [
    "CONDITIONS", "DEPTH_ERROR_PARTS", "Condition", "DepthErrors", "DetectorErrors", "get_condition",
    "without_depth_errors",
    "generate_frames", "generate_scene", "warm_up", "DepthRender", "render_depth", "shade",
]
