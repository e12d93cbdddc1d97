"""monitor: the perception front-end of fuzzrisk.

Turns a depth map and a 3D detector's output into the IoU~/RDD~ features and a collision
risk per frame (FuzzRisk, Sections III-IV). Depends on :mod:`fuzzcore`, never the reverse.

>>> from monitor import Camera, RiskMonitor, Shield, load_config, load_prior

The names below are imported when first used (PEP 562), so that importing a light part of
the package (``monitor.cli`` for ``fuzzrisk infer``, say) does not load OpenCV.
"""
from __future__ import annotations

import importlib

#: public name -> module defining it
_EXPORTS = {
    "Camera": "monitor.geometry.camera",
    "MonitorConfig": "monitor.config",
    "RiskMonitor": "monitor.risk_monitor",
    "RiskReport": "monitor.risk_monitor",
    "Shield": "monitor.shield",
    "ShieldDecision": "monitor.shield",
    "load_config": "monitor.config",
    "load_prior": "monitor.depth.prior",
}

__all__ = sorted(_EXPORTS)


def __getattr__(name: str):
    if name not in _EXPORTS:
        raise AttributeError(f"module 'monitor' has no attribute {name!r}")
    value = getattr(importlib.import_module(_EXPORTS[name]), name)
    globals()[name] = value  # later look-ups skip this function
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(__all__))
