"""What runs offline, with ground truth: USC~, the evaluation, the closed-loop simulation.

- :mod:`~monitor.offline.groundtruth`: USC~ and the training target 1 - USC~;
- :mod:`~monitor.offline.evaluation`: the paper's Tables I-III and the quality measures;
- :mod:`~monitor.offline.bootstrap`: how sure those are, by resampling whole scenes;
- :mod:`~monitor.offline.scenarios`, :mod:`~monitor.offline.closed_loop`, :mod:`~monitor.offline.safety_measures`:
  the monitor and shield in a closed loop with traffic, and what it buys and costs;
  :mod:`~monitor.offline.tracking`, the simulated driver's tracker;
  :mod:`~monitor.offline.attribution`, what each object that engaged the shield really lay on;
- :mod:`~monitor.offline.latency`: per-stage latency of the monitor (``fuzzrisk bench --monitor``).
"""
