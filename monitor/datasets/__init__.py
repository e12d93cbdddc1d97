"""Recorded and generated drives as frames: in memory, scene folders, nuScenes.

- :mod:`~monitor.datasets.frames`: :class:`Frame` and :class:`Scene` in memory;
- :mod:`~monitor.datasets.scene_folder`: the on-disk scene-folder format;
- :mod:`~monitor.datasets.nuscenes`: nuScenes tables and detection results;
- :mod:`~monitor.datasets.fields`: typed JSON access whose errors name file and field;
- :mod:`~monitor.datasets.calibration`: camera calibration files (YAML).
"""
