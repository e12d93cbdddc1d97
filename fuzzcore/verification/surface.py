"""The output surface: monotonicity along declared inputs, the range reached, the largest slope and jump.

The output of a Mamdani system is not piecewise linear (a centroid of clipped sets), so
these are searches, not proofs, built on the cell structure (:mod:`fuzzcore.verification.cells`):

- **Lines.** Along each input, lines through every combination of the other inputs' cell
  representatives (a seeded random subset when there are more than the budget allows),
  sampled at every critical point of the input and at evenly spaced points between them.
- **Monotonicity.** On each line the worst drop ``max_{j<k} y_j - y_k`` (for a declared
  increase; the rise for a decrease) is found exactly by a running maximum. The worst lines
  are then refined locally: a pattern search over the pair's two positions and the other
  inputs, with steps halving from the sample spacing, maximises the drop.
- **Slope and jump.** The steepest sample interval along any input is bisected toward
  its steeper half; an interval that keeps its rise while shrinking below :data:`JUMP_WIDTH`
  of the range is a discontinuity (a jump), else its slope estimates the Lipschitz constant.
- **Range.** The smallest and largest outputs over every point evaluated (an inner
  estimate: the true range can only be wider).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

#: evenly spaced samples per interval between critical points, at most
MAX_PER_INTERVAL = 63
#: interval width (fraction of the input range) below which a rise counts as a jump
JUMP_WIDTH = 1e-9
#: pattern-search iterations of one local refinement
REFINE_ITERATIONS = 60


@dataclass(frozen=True)
class Lines:
    """Samples along one input (see the module docstring).

    Attributes
    ----------
    axis : int
        The input the lines run along.
    X : ndarray (n_lines, n_points, n_inputs)
    Y : ndarray (n_lines, n_points, n_outputs)
    n_possible : int
        Lines through every combination of the other inputs' cell representatives.
    """

    axis: int
    X: np.ndarray
    Y: np.ndarray
    n_possible: int


def sample_lines(fis, axes, axis: int, budget: int, rng: np.random.Generator) -> Lines:
    """Lines along input ``axis`` within ``budget`` evaluations (module docstring)."""
    points = axes[axis].points
    others = [a for a in range(len(axes)) if a != axis]
    shape = tuple(axes[a].n_elements for a in others)
    n_possible = math.prod(shape)
    per_interval = 3
    n_lines = max(1, min(n_possible, budget // (points.shape[0] + (points.shape[0] - 1) * per_interval)))
    if n_lines == n_possible:
        per_line = budget // n_lines
        per_interval = int(np.clip((per_line - points.shape[0]) // max(1, points.shape[0] - 1), 3,
                                   MAX_PER_INTERVAL))
    chosen = np.arange(n_possible) if n_lines == n_possible else np.sort(rng.choice(n_possible, n_lines,
                                                                                      replace=False))
    fractions = np.arange(1, per_interval + 1) / (per_interval + 1)
    t = np.concatenate([points[:-1, None] + np.diff(points)[:, None] * fractions[None, :],
                        points[:-1, None]], axis=1).ravel()
    t = np.sort(np.append(t, points[-1]))
    X = np.empty((n_lines, t.shape[0], len(axes)))
    X[:, :, axis] = t
    if others:
        index = np.unravel_index(chosen, shape)
        for a, idx in zip(others, index):
            X[:, :, a] = axes[a].representatives[idx][:, None]
    Y = fis.evaluate(X.reshape(-1, len(axes))).reshape(n_lines, t.shape[0], -1)
    return Lines(axis, X, Y, n_possible)


@dataclass(frozen=True)
class Monotonicity:
    """The worst violation found of ``output`` changing with ``input`` in ``direction``.

    ``drop`` is how much the output goes against the declared direction between the points
    ``start`` and ``end`` (dicts input -> value; ``end`` is further along the input), and
    ``values`` the outputs there; ``drop <= tol`` means no violation was found.
    """

    input: str
    output: str
    direction: int
    drop: float
    start: dict
    end: dict
    values: tuple[float, float]
    tol: float
    n_lines: int
    n_possible_lines: int
    n_evaluations: int

    @property
    def holds(self) -> bool:
        return bool(not self.drop > self.tol)

    def to_dict(self) -> dict:
        return {"input": self.input, "output": self.output, "direction": self.direction, "holds": self.holds,
                "drop": self.drop, "tol": self.tol, "start": self.start, "end": self.end,
                "values": list(self.values), "lines": self.n_lines, "possible_lines": self.n_possible_lines,
                "evaluations": self.n_evaluations}


def _worst_on_lines(y: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Per line (rows of ``y``), the worst drop ``max_{j<k} y_j - y_k`` and its j, k (NaN skipped)."""
    filled = np.where(np.isnan(y), -np.inf, y)
    running = np.maximum.accumulate(filled, axis=1)
    drops = np.full(y.shape, -np.inf)
    drops[:, 1:] = running[:, :-1] - np.where(np.isnan(y[:, 1:]), np.inf, y[:, 1:])
    k = np.argmax(drops, axis=1)
    rows = np.arange(y.shape[0])
    j = np.argmax(filled[:, :] == running[rows, np.maximum(k - 1, 0)][:, None], axis=1)
    return drops[rows, k], j, k


def _refine_pair(fis, axes, axis: int, o: int, sign: float, x: np.ndarray, ta: float, tb: float,
                 step_t: float) -> tuple:
    """Pattern search maximising ``sign * (y(x with ta) - y(x with tb))``, ta < tb (module docstring).

    Returns ``(drop, point, ta, tb, evaluations, (y at ta, y at tb))``.
    """
    n_in = len(axes)
    lo = np.array([a.lo for a in axes])
    hi = np.array([a.hi for a in axes])
    span = hi - lo
    # variables: ta, tb, then the other inputs
    others = [a for a in range(n_in) if a != axis]
    v = np.concatenate([[ta, tb], x[others]])
    vlo = np.concatenate([[lo[axis]] * 2, lo[others]])
    vhi = np.concatenate([[hi[axis]] * 2, hi[others]])
    steps = np.concatenate([[step_t, step_t], span[others] / 64.0])
    floor = np.concatenate([[span[axis]] * 2, span[others]]) * 1e-9

    def drops(V):
        A = np.empty((V.shape[0], n_in))
        A[:, others] = V[:, 2:]
        B = A.copy()
        A[:, axis], B[:, axis] = V[:, 0], V[:, 1]
        Y = fis.evaluate(np.concatenate([A, B]))[:, o]
        d = sign * (Y[:V.shape[0]] - Y[V.shape[0]:])
        return np.where(np.isnan(d), -np.inf, d), Y[:V.shape[0]], Y[V.shape[0]:]

    best, ya, yb = (float(a[0]) for a in drops(v[None]))
    n_eval = 2
    for _ in range(REFINE_ITERATIONS):
        if (steps <= floor).all():
            break
        polls = np.concatenate([v + np.diag(steps), v - np.diag(steps)])
        polls = np.clip(polls, vlo, vhi)
        polls = polls[polls[:, 0] < polls[:, 1]]
        if polls.shape[0]:
            d, pa, pb = drops(polls)
            n_eval += 2 * polls.shape[0]
            k = int(np.argmax(d))
            if d[k] > best:
                best, ya, yb, v = float(d[k]), float(pa[k]), float(pb[k]), polls[k]
                continue
        steps = steps / 2
    point = np.empty(n_in)
    point[others] = v[2:]
    return best, point, float(v[0]), float(v[1]), n_eval, (ya, yb)


def monotonicity(fis, axes, lines: Lines, direction: int, rel_tol: float, n_refine: int) -> list[Monotonicity]:
    """The worst violation of a monotone output along ``lines.axis`` in ``direction``, per output.

    A drop counts as a violation above ``rel_tol`` times the output's range; the
    ``n_refine`` worst lines are refined locally.
    """
    axis = lines.axis
    out = []
    names = fis.input_names
    for o, var in enumerate(fis.outputs):
        tol = rel_tol * (var.range[1] - var.range[0])
        y = direction * lines.Y[:, :, o]
        drop, j, k = _worst_on_lines(y)
        best = (-np.inf, None)
        n_eval = lines.X.shape[0] * lines.X.shape[1]
        for line in np.argsort(-drop)[:n_refine]:
            if not drop[line] > -np.inf:
                continue
            t = lines.X[line, :, axis]
            step = float(np.min(np.diff(t))) if t.shape[0] > 1 else (axes[axis].hi - axes[axis].lo)
            d, point, ta, tb, used, values = _refine_pair(fis, axes, axis, o, float(direction),
                                                          lines.X[line, 0].copy(), float(t[j[line]]),
                                                          float(t[k[line]]), step)
            n_eval += used
            if d > best[0]:
                best = (d, (point, ta, tb, values))
        if best[1] is None:
            out.append(Monotonicity(names[axis], var.name, direction, -math.inf, {}, {}, (math.nan, math.nan),
                                    tol, lines.X.shape[0], lines.n_possible, n_eval))
            continue
        point, ta, tb, values = best[1]
        start, end = point.copy(), point.copy()
        start[axis], end[axis] = ta, tb
        out.append(Monotonicity(names[axis], var.name, direction, float(max(best[0], 0.0)),
                                dict(zip(names, start.tolist())), dict(zip(names, end.tolist())),
                                values, tol, lines.X.shape[0], lines.n_possible, n_eval))
    return out


@dataclass(frozen=True)
class Steepest:
    """The steepest change of ``output`` found along ``input``.

    ``rise`` is the output change over the final interval ``[start, end]`` (points as
    dicts); ``jump`` says the interval shrank below :data:`JUMP_WIDTH` of the range with the
    output still changing by ``rise``: a discontinuity. ``slope = rise / (end - start)`` along
    the input, in output units per input unit (a Lipschitz estimate when not a jump).
    """

    input: str
    output: str
    rise: float
    slope: float
    start: dict
    end: dict
    jump: bool

    def to_dict(self) -> dict:
        return {"input": self.input, "output": self.output, "rise": self.rise, "slope": self.slope,
                "start": self.start, "end": self.end, "jump": self.jump}


def steepest(fis, axes, lines: Lines, rel_tol: float) -> list[Steepest]:
    """Per output, the steepest sampled interval along ``lines.axis`` refined by bisection.

    A rise above ``rel_tol`` times the output's range over a vanishing interval is a jump.
    """
    axis, names = lines.axis, fis.input_names
    span = axes[axis].hi - axes[axis].lo
    out = []
    for o, var in enumerate(fis.outputs):
        jump_tol = rel_tol * (var.range[1] - var.range[0])
        y = lines.Y[:, :, o]
        t = lines.X[:, :, axis]
        dy = np.abs(np.diff(y, axis=1))
        dt = np.diff(t, axis=1)
        with np.errstate(divide="ignore", invalid="ignore"):
            slope = np.where(np.isnan(dy) | ~(dt > 0), -np.inf, dy / dt)
        if not np.isfinite(slope).any():
            continue
        line, i = np.unravel_index(int(np.argmax(slope)), slope.shape)
        a, b = lines.X[line, i].copy(), lines.X[line, i + 1].copy()
        ya, yb = y[line, i], y[line, i + 1]
        best_slope = float(slope[line, i])
        while b[axis] - a[axis] > JUMP_WIDTH * span:
            m = 0.5 * (a + b)
            ym = float(fis.evaluate(m[None])[0, o])
            if math.isnan(ym):
                break
            if abs(ym - ya) >= abs(yb - ym):
                b, yb = m, ym
            else:
                a, ya = m, ym
            best_slope = max(best_slope, abs(yb - ya) / (b[axis] - a[axis]))
            if abs(yb - ya) <= jump_tol:  # continuous here: the slope estimate is what it is
                break
        rise = abs(yb - ya)
        jump = bool(b[axis] - a[axis] <= JUMP_WIDTH * span and rise > jump_tol)
        out.append(Steepest(names[axis], var.name, float(rise), best_slope, dict(zip(names, a.tolist())),
                            dict(zip(names, b.tolist())), jump))
    return out
