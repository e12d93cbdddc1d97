"""Tuning data: a table of inputs, a target and an optional group column, and its checks.

The CSV format (shared with ``fuzzrisk features``): a header row naming the columns; one
column per input of the rule base (named after the input), a ``target`` column, and
optionally a group column (``scene``: cross-validation folds never split a group) and
any other columns (kept as text, e.g. ``frame`` or ``condition``)::

    scene,frame,condition,iou,rdd,target
    scene-0001,0,nominal,0.61,0.05,0.12
    scene-0001,1,nominal,,,0.40        <- no features: skipped and counted
    scene-0001,2,nominal,0.58,0.07,    <- no target: skipped and counted

A row whose target is empty or ``nan`` (a frame without ground truth in range) is
skipped, as is a row whose inputs are empty or ``nan`` (a frame without features); both
counts are reported. Anything else that is not a finite number is an error naming the
file, the line and the column.
"""
from __future__ import annotations

import csv
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Sequence

import numpy as np

from ..inputs import real_array

#: spellings of a missing value in a CSV cell (compared lower-case, stripped)
MISSING = frozenset({"", "nan"})


@dataclass(frozen=True)
class FeatureTable:
    """Rows of a feature CSV that can be used for tuning.

    Attributes
    ----------
    X : ndarray of shape (n_rows, n_inputs), float64
        Input columns in the order asked for.
    y : ndarray of shape (n_rows,), float64
        The target column.
    groups : ndarray of shape (n_rows,) of str, or None
        The group column (``None`` when the file has none).
    columns : dict of str -> ndarray of str
        Every other column, as text, for the kept rows.
    lines : ndarray of shape (n_rows,), int64
        The file line of each kept row (the header is line 1).
    n_no_target, n_no_features : int
        Rows skipped for an empty/NaN target, and (target present) for empty/NaN inputs.
    source : str
    input_names : tuple of str
    """

    X: np.ndarray
    y: np.ndarray
    groups: np.ndarray | None
    columns: dict = field(repr=False)
    lines: np.ndarray = field(repr=False)
    n_no_target: int
    n_no_features: int
    source: str
    input_names: tuple[str, ...]

    def __len__(self) -> int:
        return self.y.shape[0]


def _number(text: str, path: Path, line: int, column: str) -> float:
    cell = text.strip()
    if cell.lower() in MISSING:
        return math.nan
    try:
        value = float(cell)
    except ValueError:
        raise ValueError(f"{path}, line {line}, column {column!r}: {text!r} is not a number") from None
    if not math.isfinite(value):
        raise ValueError(f"{path}, line {line}, column {column!r}: {text!r} is not a finite number "
                         "(write an empty cell or 'nan' for a missing value)")
    return value


def read_csv(path: str | Path, inputs: Sequence[str], target: str = "target",
             group: str | None = "scene") -> FeatureTable:
    """Read a feature CSV (format: module docstring).

    Parameters
    ----------
    path : str or Path
    inputs : sequence of str
        Names of the input columns, in the order ``X`` gets them (a rule base's
        ``input_names``).
    target : str
        Name of the target column.
    group : str or None
        Name of the group column, used when present (``None``: never).

    Raises
    ------
    OSError
        The file cannot be read.
    ValueError
        A required column is missing, a row has the wrong number of cells, a cell is not
        a number, or no row is usable; the message names the file, line and column.
    """
    path = Path(path)
    with path.open(newline="", encoding="utf-8") as handle:
        reader = csv.reader(handle)
        header = next(reader, None)
        if header is None:
            raise ValueError(f"{path}: the file is empty; expected a header row with columns "
                             f"{', '.join([*inputs, target])}")
        header = [name.strip() for name in header]
        repeated = sorted({name for name in header if header.count(name) > 1})
        if repeated:
            raise ValueError(f"{path}, line 1: repeated column name(s) {', '.join(repeated)}")
        missing = [name for name in [*inputs, target] if name not in header]
        if missing:
            raise ValueError(f"{path}, line 1: missing column(s) {', '.join(missing)}; the header has "
                             f"{', '.join(header)}")
        position = {name: k for k, name in enumerate(header)}
        numeric = [*inputs, target]
        text_columns = [name for name in header if name not in numeric]
        rows, lines, texts = [], [], []
        n_no_target = n_no_features = 0
        for cells in reader:
            line = reader.line_num
            if not cells:
                continue  # a blank line
            if len(cells) != len(header):
                raise ValueError(f"{path}, line {line}: {len(cells)} cells, expected {len(header)} "
                                 f"(one per header column)")
            values = [_number(cells[position[name]], path, line, name) for name in numeric]
            if math.isnan(values[-1]):
                n_no_target += 1
                continue
            if any(math.isnan(v) for v in values[:-1]):
                n_no_features += 1
                continue
            rows.append(values)
            lines.append(line)
            texts.append([cells[position[name]].strip() for name in text_columns])
    if not rows:
        raise ValueError(f"{path}: no usable row ({n_no_target} without a target, {n_no_features} "
                         "without features)")
    data = np.array(rows, dtype=np.float64)
    text = np.array(texts, dtype=str).reshape(len(rows), len(text_columns))
    columns = {name: text[:, k] for k, name in enumerate(text_columns)}
    groups = None
    if group is not None and group in columns:
        groups = columns.pop(group)
        empty = np.flatnonzero(groups == "")
        if empty.size:
            raise ValueError(f"{path}, line {lines[empty[0]]}, column {group!r}: empty group label "
                             f"({empty.size} rows); every row needs its {group}")
    return FeatureTable(X=data[:, :-1].copy(), y=data[:, -1].copy(), groups=groups, columns=columns,
                        lines=np.array(lines, dtype=np.int64), n_no_target=n_no_target,
                        n_no_features=n_no_features, source=str(path), input_names=tuple(inputs))


def _check_labels(groups: np.ndarray) -> None:
    """Refuse group labels that are missing (NaN, None) or not labels at all (complex, masked)."""
    if isinstance(groups, np.ma.MaskedArray) or groups.dtype.kind in "cmMV":
        raise ValueError(f"groups has dtype {groups.dtype}{' (masked)' if np.ma.isMaskedArray(groups) else ''}; "
                         "expected labels: integers or text")
    if groups.dtype.kind == "f":
        missing = np.flatnonzero(np.isnan(groups))
    elif groups.dtype.kind == "O":
        missing = np.flatnonzero([g is None or (isinstance(g, float) and g != g) for g in groups])
    else:
        return
    if missing.size:
        raise ValueError(f"groups has {missing.size} missing label(s) (NaN or None; first: sample {missing[0]}); "
                         "every sample needs its group (a NaN would make a group of its own)")


def check_data(system, X, y, groups=None) -> tuple[np.ndarray, np.ndarray, np.ndarray | None]:
    """Validate tuning data against ``system``; return ``(X, Y, groups)`` as the tuners use them.

    Parameters
    ----------
    system : FuzzySystem
    X : array_like of shape (n_samples, n_inputs)
        Inputs in the system's declared order; finite.
    y : array_like of shape (n_samples,) or (n_samples, n_outputs)
        Targets, finite and inside each output's range (a Mamdani output can reach no
        value outside it).
    groups : array_like of shape (n_samples,), optional
        Group labels (folds never split a group): numbers or text; NaN and None are refused
        (each NaN would be a group of its own).

    Returns
    -------
    X : ndarray (n_samples, n_inputs), float64, C-contiguous
    Y : ndarray (n_samples, n_outputs), float64, C-contiguous
    groups : ndarray (n_samples,) or None
    """
    X = real_array(X, "X")
    n_in, n_out = len(system.inputs), len(system.outputs)
    if X.ndim != 2 or X.shape[1] != n_in:
        raise ValueError(f"X has shape {X.shape}, expected (n_samples, {n_in}) with columns "
                         f"{', '.join(system.input_names)}")
    if X.shape[0] == 0:
        raise ValueError("X has no rows; tuning needs data")
    Y = real_array(y, "y")
    if Y.ndim == 1 and n_out == 1:
        Y = Y[:, None]
    if Y.ndim != 2 or Y.shape != (X.shape[0], n_out):
        raise ValueError(f"y has shape {np.shape(y)}, expected ({X.shape[0]},)"
                         + (f" or ({X.shape[0]}, {n_out})" if n_out == 1 else f" -> ({X.shape[0]}, {n_out})")
                         + " (one target per sample and output)")
    for name, A in (("X", X), ("y", Y)):
        bad = np.flatnonzero(~np.isfinite(A).all(axis=1))
        if bad.size:
            raise ValueError(f"{name} has {bad.size} row(s) with NaN or infinite values (first: row "
                             f"{bad[0]}, {A[bad[0]].tolist()}); drop them before tuning")
    for o, var in enumerate(system.outputs):
        lo, hi = var.range
        outside = np.flatnonzero((Y[:, o] < lo) | (Y[:, o] > hi))
        if outside.size:
            raise ValueError(f"y has {outside.size} target(s) outside the range [{lo:g}, {hi:g}] of output "
                             f"{var.name!r} (first: row {outside[0]}, {Y[outside[0], o]!r}); the system "
                             "cannot produce them")
    if groups is not None:
        groups = np.asarray(groups)
        if groups.shape != (X.shape[0],):
            raise ValueError(f"groups has shape {groups.shape}, expected ({X.shape[0]},): one label per sample")
        _check_labels(groups)
    return np.ascontiguousarray(X), np.ascontiguousarray(Y), groups
