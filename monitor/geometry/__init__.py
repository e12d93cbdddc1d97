"""Geometry of the detector view: 2D boxes and their measures, poses, 3D boxes, the camera.

- :mod:`~monitor.geometry.boxes`: 2D box arrays ``(n, 5)`` ``cx, cy, w, h, d``, IoU, IoG, RDD,
  the range limit;
- :mod:`~monitor.geometry.poses`: quaternions, rigid transforms;
- :mod:`~monitor.geometry.boxes3d`: 3D box arrays ``(n, 7)``, frame changes, corners;
- :mod:`~monitor.geometry.camera`: the pinhole camera and :func:`project_boxes`;
- :mod:`~monitor.geometry.corridor`: the driving corridor along the ego's path.
"""
