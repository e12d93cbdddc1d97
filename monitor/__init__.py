"""monitor: the perception front-end of fuzzrisk.

Turns a depth map and a 3D detector's output into the IoU~/RDD~ features and a collision
risk per frame (FuzzRisk, Sections III-IV). Depends on :mod:`fuzzcore`, never the reverse.

>>> from monitor import RiskMonitor, Shield, load_config
"""
from monitor.config import MonitorConfig, load_config
from monitor.risk_monitor import RiskMonitor, RiskReport
from monitor.shield import Shield, ShieldDecision

__all__ = ["MonitorConfig", "RiskMonitor", "RiskReport", "Shield", "ShieldDecision", "load_config"]
