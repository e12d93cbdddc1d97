"""The path-gated shield written out for the tests, from a report row (``fuzzrisk monitor``, the demo)."""
from __future__ import annotations

#: a configuration section with the gate, no hold, no hysteresis and no confirmation: a
#: shield without memory, deciding on the risk and the unseen objects alone (no walker gate)
GATE_YAML = ("shield: {path_half_width: 1.25, hold_frames: 0, confirm_frames: 1, confirm_window: 1, memory: null, "
             "walker_horizon: null}\n")


def gated_engaged(row: dict, c) -> bool:
    """Whether the shield of ``GATE_YAML`` (settings ``c``, a ShieldConfig) engages on ``row``.

    Engaged on a frame whose risk is above the threshold while an unseen object reaches within
    ``path_half_width`` of the centreline and lies within v^2 / (2 a) + headway v + margin
    of the bumper, v the row's ``ego_speed`` (a frame without a view, ``unseen`` null: by its
    risk alone). Without hold and hysteresis the decision depends on this frame only.
    """
    v = row["ego_speed"]
    reach = v * v / (2.0 * c.deceleration) + c.headway * v + c.margin
    in_path = row["unseen"] is None or any(
        x - c.front <= reach and y_max >= -c.path_half_width and y_min <= c.path_half_width
        for x, y_min, y_max in row["unseen"])
    return row["risk"] > c.threshold and in_path
