"""monitor: the perception front-end of fuzzrisk.

Turns a depth map and a 3D detector's output into the IoU~/RDD~ features and a collision
risk per frame (FuzzRisk, Sections III-IV). Depends on :mod:`fuzzcore`, never the reverse.
"""
