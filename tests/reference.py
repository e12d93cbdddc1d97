"""A slow, obviously-correct NumPy evaluator of MATLAB's fuzzy inference, for the tests.

Written from MATLAB's documented algorithm (trimf.m, trapmf.m, ..., evalfis, defuzz.m)
independently of the Numba kernels: no shared code beyond the FuzzySystem definition.

``exp`` and ``x ** b`` are the C library's (Python's ``math``), one element at a time, not
numpy's: numpy's vectorised versions are chosen by CPU (SIMD) and are off by an ulp for a
few percent of arguments on some CPUs. An ulp in a membership is enough to move an exact
tie of mom/som/lom (with probor, ``1 + g - 1*g`` is 1.0 or not depending on g's last bit),
and then the reference's answer would depend on the machine. The C library's exp and pow
are correctly rounded for almost every argument, as MATLAB's are meant to be; the engine
(Numba, calling the same C library) gives the same bits.
"""
from __future__ import annotations

import math

import numpy as np


def _exp(t):
    """``exp`` of every element with the C library's exp; overflow gives inf (as in C)."""

    def one(v):
        try:
            return math.exp(v)
        except OverflowError:
            return math.inf
    t = np.asarray(t, dtype=float)
    return np.array([one(v) for v in t.ravel().tolist()]).reshape(t.shape)


def _pow(base, b):
    """``base ** b`` of every element (``base >= 0``) with the C library's pow; overflow and
    ``0 ** (b < 0)`` give inf (as in C)."""
    exponent = float(b)

    def one(v):
        try:
            return v ** exponent
        except (OverflowError, ZeroDivisionError):
            return math.inf
    base = np.asarray(base, dtype=float)
    return np.array([one(v) for v in base.ravel().tolist()]).reshape(base.shape)


def _sig(a, c, x):
    with np.errstate(over="ignore", invalid="ignore"):
        return np.where(a == 0, 0.5, 1.0 / (1.0 + _exp(-a * (x - c))))


def _smf(a, b, x):
    if a >= b:
        return (x >= (a + b) / 2).astype(float)
    y = np.zeros_like(x)
    mid = (a + b) / 2
    i2 = (a < x) & (x <= mid)
    y[i2] = 2 * ((x[i2] - a) / (b - a)) ** 2
    i3 = (mid < x) & (x <= b)
    y[i3] = 1 - 2 * ((b - x[i3]) / (b - a)) ** 2
    y[x >= b] = 1
    return y


def _zmf(a, b, x):
    if a >= b:
        return (x <= (a + b) / 2).astype(float)
    y = np.zeros_like(x)
    mid = (a + b) / 2
    y[x <= a] = 1
    i2 = (a < x) & (x <= mid)
    y[i2] = 1 - 2 * ((x[i2] - a) / (b - a)) ** 2
    i3 = (mid < x) & (x <= b)
    y[i3] = 2 * ((b - x[i3]) / (b - a)) ** 2
    y[x >= b] = 0  # last, as zmf.m: when (a + b)/2 rounds to b, x == b is in both ranges above
    return y


def membership(kind: str, p, x) -> np.ndarray:
    """MATLAB's membership functions, transcribed index by index as MATLAB writes them."""
    x = np.atleast_1d(np.asarray(x, dtype=float)).copy()
    y = np.zeros_like(x)
    if kind == "trimf":
        a, b, c = p
        if a != b:
            i = (a < x) & (x < b)
            y[i] = (x[i] - a) / (b - a)
        if b != c:
            i = (b < x) & (x < c)
            y[i] = (c - x[i]) / (c - b)
        y[x == b] = 1
        return y
    if kind == "trapmf":
        a, b, c, d = p
        y1, y2 = np.zeros_like(x), np.zeros_like(x)
        y1[x >= b] = 1
        if a != b:
            i = (a <= x) & (x < b)
            y1[i] = (x[i] - a) / (b - a)
        y2[x <= c] = 1
        if c != d:
            i = (c < x) & (x <= d)
            y2[i] = (d - x[i]) / (d - c)
        return np.minimum(y1, y2)
    if kind == "gaussmf":
        s, c = p
        return _exp(-((x - c) ** 2) / (2 * s * s))
    if kind == "gauss2mf":
        s1, c1, s2, c2 = p
        y1 = np.where(x <= c1, _exp(-((x - c1) ** 2) / (2 * s1 * s1)), 1.0)
        y2 = np.where(x >= c2, _exp(-((x - c2) ** 2) / (2 * s2 * s2)), 1.0)
        return y1 * y2
    if kind == "gbellmf":
        a, b, c = p
        return 1.0 / (1.0 + _pow(((x - c) / a) ** 2, b))
    if kind == "sigmf":
        return _sig(p[0], p[1], x)
    if kind == "dsigmf":
        return np.abs(_sig(p[0], p[1], x) - _sig(p[2], p[3], x))
    if kind == "psigmf":
        return _sig(p[0], p[1], x) * _sig(p[2], p[3], x)
    if kind == "smf":
        return _smf(p[0], p[1], x)
    if kind == "zmf":
        return _zmf(p[0], p[1], x)
    if kind == "pimf":
        return _smf(p[0], p[1], x) * _zmf(p[2], p[3], x)
    with np.errstate(over="ignore", invalid="ignore"):  # np.where computes the unused branch too
        if kind == "linsmf":
            a, b = p
            return np.where(x < a, 0.0, np.where(x >= b, 1.0, (x - a) / (b - a if b != a else 1.0)))
        if kind == "linzmf":
            a, b = p
            return np.where(x <= a, 1.0, np.where(x > b, 0.0, (b - x) / (b - a if b != a else 1.0)))
    raise ValueError(kind)


def _firing(system, x):
    strengths = []
    for rule in system.rules:
        values = []
        for index, var, xi in zip(rule.antecedent, system.inputs, x):
            if index == 0:
                continue
            term = var.terms[abs(index) - 1]
            m = membership(term.kind, term.params, xi)[0]
            values.append(1 - m if index < 0 else m)
        if rule.connective == "and":
            f = 1.0
            for m in values:
                f = min(f, m) if system.and_method == "min" else f * m
        else:
            f = 0.0
            for m in values:
                f = max(f, m) if system.or_method == "max" else f + m - f * m
        strengths.append(f * rule.weight)
    return np.array(strengths)


def _policy(system, var):
    if system.no_rule_fired == "midpoint":
        return (var.range[0] + var.range[1]) / 2
    if system.no_rule_fired == "nan":
        return np.nan
    return system.no_rule_fired


def aggregated_set(system, x, o):
    """The aggregated output set of output ``o`` on MATLAB's grid: (y, mu)."""
    var = system.outputs[o]
    lo, hi, n = var.range[0], var.range[1], system.resolution
    y = lo + (np.arange(n) * (hi - lo)) / (n - 1)  # MATLAB's linspace (numpy's rounds differently)
    y[-1] = hi
    agg = np.zeros_like(y)
    for f, rule in zip(_firing(system, x), system.rules):
        index = rule.consequent[o]
        if index == 0:
            continue
        term = var.terms[abs(index) - 1]
        m = membership(term.kind, term.params, y)
        if index < 0:
            m = 1 - m
        implied = np.minimum(f, m) if system.implication == "min" else f * m
        if system.aggregation == "max":
            agg = np.maximum(agg, implied)
        elif system.aggregation == "sum":
            agg = agg + implied
        else:
            agg = agg + implied - agg * implied
    return y, agg


def defuzzify(method, y, mu):
    """MATLAB's defuzz.m on a grid; None where the set is empty."""
    total = mu.sum()
    if total == 0:
        return None
    if method == "centroid":
        return float((y * mu).sum() / total)
    if method == "bisector":
        running = np.cumsum(mu)  # sequential, as MATLAB's loop
        k = int(np.argmax(running >= running[-1] / 2))
        return float(y[k])
    at_max = y[mu == mu.max()]
    if method == "mom":
        return float(at_max.mean())
    if method == "som":
        return float(at_max[np.argmin(np.abs(at_max))])
    if method == "lom":
        return float(at_max[np.argmax(np.abs(at_max))])
    raise ValueError(method)


def evaluate(system, X) -> np.ndarray:
    """(n, n_in) -> (n, n_out), one sample and one output at a time."""
    X = np.atleast_2d(np.asarray(X, dtype=float))
    out = np.empty((X.shape[0], len(system.outputs)))
    for i, x in enumerate(X):
        for o, var in enumerate(system.outputs):
            if np.isnan(x).any():
                out[i, o] = np.nan
                continue
            if system.type == "sugeno":
                f = _firing(system, x)
                num = den = 0.0
                for w, rule in zip(f, system.rules):
                    index = rule.consequent[o]
                    if index == 0:
                        continue
                    term = var.terms[index - 1]
                    z = term.params[0] if term.kind == "constant" else float(
                        np.dot(term.params[:-1], x) + term.params[-1])
                    num += w * z
                    den += w
                value = None if den == 0 else (num / den if system.defuzzifier == "wtaver" else num)
            else:
                y, mu = aggregated_set(system, x, o)
                value = defuzzify(system.defuzzifier, y, mu)
            out[i, o] = _policy(system, var) if value is None else value
    return out
