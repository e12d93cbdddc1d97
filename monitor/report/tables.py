"""Tables for the terminal and for Markdown reports, from rows of dicts."""
from __future__ import annotations

import math
from typing import Sequence

#: a column: (row key, header, format string)
Column = tuple[str, str, str]


def _cell(value, fmt: str) -> str:
    if value is None or (isinstance(value, float) and math.isnan(value)):
        return "-"
    return fmt.format(value)


def format_table(rows: Sequence[dict], columns: Sequence[Column], markdown: bool = False) -> str:
    """Aligned plain text (``markdown=False``) or a Markdown table; NaN and None print as ``-``."""
    head = [h for _, h, _ in columns]
    body = [[_cell(row.get(key), fmt) for key, _, fmt in columns] for row in rows]
    if markdown:
        lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
        return "\n".join(lines + ["| " + " | ".join(r) + " |" for r in body])
    widths = [max(len(x) for x in col) for col in zip(head, *body)]
    return "\n".join("  ".join(x.rjust(w) for x, w in zip(r, widths)) for r in [head] + body)


def interval_cell(value: float, lo: float, hi: float, fmt: str) -> str:
    """``value [lo, hi]`` for a report, ``-`` for an undefined value and ``[-]`` for an
    undefined interval."""
    span = "-" if math.isnan(lo) or math.isnan(hi) else f"{_cell(lo, fmt)}, {_cell(hi, fmt)}"
    return f"{_cell(value, fmt)} [{span}]"
