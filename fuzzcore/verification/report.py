"""The verification report: what :func:`fuzzcore.verify` found, as text and as a dict for JSON."""
from __future__ import annotations

import math
from dataclasses import dataclass

from .coverage import Coverage
from .partitions import Partition
from .rules import RuleFindings
from .surface import Monotonicity, Steepest


def _point(p: dict) -> str:
    return ", ".join(f"{k} = {v:.6g}" for k, v in p.items())


def _finite(value: float):
    """JSON has no inf/NaN: None stands for them."""
    return value if isinstance(value, float) and math.isfinite(value) else (None if isinstance(value, float)
                                                                             else value)


@dataclass(frozen=True)
class OutputRange:
    """The smallest and largest value of ``output`` over every point evaluated, and where."""

    output: str
    declared: tuple[float, float]
    low: float
    high: float
    low_at: dict
    high_at: dict

    def to_dict(self) -> dict:
        return {"output": self.output, "declared": list(self.declared), "low": _finite(self.low),
                "high": _finite(self.high), "low_at": self.low_at, "high_at": self.high_at}


@dataclass(frozen=True)
class Report:
    """Everything :func:`~fuzzcore.verify` found about one rule base.

    ``ok`` is False when some region of the input box fires no rule (or none reaches the
    threshold) or a declared monotonicity fails; :attr:`failures` says which, in words.
    Rules and partitions are advice: they never make ``ok`` False.
    """

    system: str
    inputs: dict
    outputs: dict
    n_rules: int
    coverage: Coverage
    monotonicity: tuple[Monotonicity, ...]
    output_range: tuple[OutputRange, ...]
    steepest: tuple[Steepest, ...]
    rules: RuleFindings
    partitions: tuple[Partition, ...]
    n_evaluations: int
    seed: int | None

    @property
    def failures(self) -> list[str]:
        out = []
        if not self.coverage.covered:
            what = "no rule fires" if self.coverage.threshold == 0 else \
                f"no rule reaches strength {self.coverage.threshold:g}"
            out.append(f"{what} on {100 * self.coverage.uncovered_share:.4g} % of the input box "
                       f"({self.coverage.n_uncovered_cells} cells)")
        for m in self.monotonicity:
            if not m.holds:
                out.append(f"{m.output} is not {'increasing' if m.direction > 0 else 'decreasing'} in {m.input}: "
                           f"it {'drops' if m.direction > 0 else 'rises'} by {m.drop:.4g}")
        return out

    @property
    def ok(self) -> bool:
        return not self.failures

    def to_dict(self) -> dict:
        jumps = [s.to_dict() for s in self.steepest]
        for j in jumps:
            j["slope"] = _finite(j["slope"])
        mono = [m.to_dict() for m in self.monotonicity]
        for m in mono:
            m["drop"] = _finite(m["drop"])
            m["values"] = [_finite(v) for v in m["values"]]
        return {"system": self.system, "ok": self.ok, "failures": self.failures,
                "inputs": {k: list(v) for k, v in self.inputs.items()},
                "outputs": {k: list(v) for k, v in self.outputs.items()}, "n_rules": self.n_rules,
                "coverage": self.coverage.to_dict(), "monotonicity": mono,
                "output_range": [r.to_dict() for r in self.output_range], "steepest": jumps,
                "rules": self.rules.to_dict(), "partitions": [p.to_dict() for p in self.partitions],
                "evaluations": self.n_evaluations, "seed": self.seed}

    def __str__(self) -> str:
        ranges = ", ".join(f"{k} [{lo:g}, {hi:g}]" for k, (lo, hi) in self.inputs.items())
        outs = ", ".join(f"{k} [{lo:g}, {hi:g}]" for k, (lo, hi) in self.outputs.items())
        lines = [f"{self.system}: inputs {ranges}; outputs {outs}; {self.n_rules} rules"]
        c = self.coverage
        what = "fires no rule" if c.threshold == 0 else f"fires no rule at strength >= {c.threshold:g}"
        if c.covered:
            lines.append("coverage: every point of the input box fires a rule"
                         + ("" if c.threshold == 0 else f" at strength >= {c.threshold:g}")
                         + f" ({c.method}; {c.n_cells} cells)")
        else:
            lines.append(f"coverage: {100 * c.uncovered_share:.4g} % of the input box {what} ({c.method}; "
                         f"{c.n_uncovered_cells} of {c.n_cells} cells)")
            for r in c.regions:
                lines.append(f"  {r.describe()}  ({100 * r.share:.4g} % of the box"
                             + (f", {r.dimension}-dimensional" if r.dimension < len(self.inputs) else "")
                             + f"; e.g. {_point(r.example)})")
            if not c.complete:
                lines.append("  ... and more regions (max_regions reached)")
        for m in self.monotonicity:
            name = f"{m.output} {'increasing' if m.direction > 0 else 'decreasing'} in {m.input}"
            searched = f"{m.n_lines} of {m.n_possible_lines} lines, {m.n_evaluations} evaluations"
            if m.holds:
                lines.append(f"monotonicity: {name}: holds (no violation above {m.tol:.3g} found; {searched})")
            else:
                lines.append(f"monotonicity: {name}: VIOLATED: {m.output} {'drops' if m.direction > 0 else 'rises'} "
                             f"by {m.drop:.4g} from {m.values[0]:.6g} at ({_point(m.start)}) to {m.values[1]:.6g} "
                             f"at ({_point(m.end)}) ({searched})")
        for r in self.output_range:
            lines.append(f"output range reached: {r.output} in [{r.low:.6g}, {r.high:.6g}] of [{r.declared[0]:g}, "
                         f"{r.declared[1]:g}]; lowest at ({_point(r.low_at)}), highest at ({_point(r.high_at)})")
        for s in self.steepest:
            if s.jump:
                lines.append(f"largest jump: {s.output} jumps by {s.rise:.4g} along {s.input} at ({_point(s.start)})")
            else:
                lines.append(f"largest slope: d {s.output} / d {s.input} = {s.slope:.4g} near ({_point(s.start)})")
        f = self.rules
        listed = [("never firing", f.never_firing), ("redundant", [r for r, _ in f.redundant])]
        for label, rules in listed:
            lines.append(f"rules {label}: " + ("none" if not rules else
                                               "; ".join(f"[{r + 1}] {f.texts[r]}" for r in rules)))
        for label, groups in (("conflicting", f.conflicting), ("duplicated", f.duplicates)):
            lines.append(f"rules {label}: " + ("none" if not groups else
                                               "; ".join(" vs ".join(f"[{r + 1}]" for r in g) for g in groups)))
        lines.append("terms no rule uses: " + ("none" if not f.unused_terms else
                                               ", ".join(f"{v}.{t}" for v, t in f.unused_terms)))
        lines.append("partitions:")
        for p in self.partitions:
            parts = ["ordered" if p.ordered else "NOT ordered ("
                     + ", ".join(f"{t} {c:.3g}" for t, c in p.centres.items()) + ")"]
            parts.append("covers the range" if not p.uncovered else
                         "no term on " + ", ".join(f"[{a:.6g}, {b:.6g}]" for a, b in p.uncovered))
            parts.append(f"min max-membership {p.min_cover:.3g} at {p.min_cover_at:.6g}")
            parts.append(f"Ruspini distance {p.ruspini:.3g}")
            if p.similarity:
                a, b, s = max(p.similarity, key=lambda t: t[2])
                parts.append(f"most alike {a}/{b} {s:.2f}" + (" (hard to tell apart)" if p.similar else ""))
            lines.append(f"  {p.role} {p.variable}: " + "; ".join(parts))
        lines.append("result: " + ("PASS" if self.ok else "FAIL: " + "; ".join(self.failures)))
        return "\n".join(lines)
