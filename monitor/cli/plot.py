"""``fuzzrisk plot RULES -o OUT.png [--monotone rdd:+] [--overwrite]``: terms and output surface,
problems marked.

One panel per variable with its terms (the range where no term is positive shaded red),
then the first output over the first two inputs (any others at the middle of their range):
regions where no rule fires hatched red (the exact regions of :func:`fuzzcore.verify`), grid
cells where the output goes against a declared monotonicity outlined in white, and the
worst violation found drawn as an arrow from its higher to its lower point.

The output is checked before any work (a ``.png`` name in an existing folder, not an
existing file unless ``--overwrite``) and written whole or not at all
(:func:`monitor.userfiles.save_figure`).
"""
from __future__ import annotations

import argparse

import numpy as np

import fuzzcore
from fuzzcore.outputs import check_output
from fuzzcore.verification import parse_monotone_specs
from monitor.userfiles import save_figure


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("rules", metavar="RULES", help="rule base (.yaml or .fis)")
    parser.add_argument("-o", "--output", required=True, metavar="OUT.png", help="where to write the figure")
    parser.add_argument("--overwrite", action="store_true", help="replace OUT.png if it exists")
    parser.add_argument("--monotone", nargs="+", default=[], metavar="INPUT:+|-",
                        help="declared monotonicity to check and mark, e.g. rdd:+")
    parser.add_argument("--resolution", type=int, default=121,
                        help="surface grid points per input (default %(default)s)")


def _draw(fis, report, monotone: dict, resolution: int):
    from matplotlib.figure import Figure
    from matplotlib.patches import Rectangle

    variables = list(fis.inputs) + (list(fis.outputs) if fis.type == "mamdani" else [])
    surface = len(fis.inputs) >= 2
    n = len(variables) + (1 if surface else 0)
    fig = Figure(figsize=(4.2 * n, 3.8), layout="constrained")
    axes = fig.subplots(1, n, squeeze=False)[0]
    partitions = {p.variable: p for p in report.partitions}
    for ax, var in zip(axes, variables):
        x = np.linspace(*var.range, 801)
        for term in var.terms:
            ax.plot(x, term.membership(x), label=term.name)
        for lo, hi in partitions[var.name].uncovered:
            ax.axvspan(lo, hi if hi > lo else lo + 1e-3 * (var.range[1] - var.range[0]), color="red", alpha=0.3)
        ax.set_title(f"{'output' if var in fis.outputs else 'input'} {var.name}")
        ax.set_ylim(-0.02, 1.05)
        ax.legend(fontsize=8)
    if surface:
        ax = axes[-1]
        a, b = fis.inputs[0], fis.inputs[1]
        xa, xb = np.linspace(*a.range, resolution), np.linspace(*b.range, resolution)
        A, B = np.meshgrid(xa, xb)
        X = np.tile([0.5 * sum(v.range) for v in fis.inputs], (A.size, 1))
        X[:, 0], X[:, 1] = A.ravel(), B.ravel()
        Z = fis.evaluate(X)[:, 0].reshape(A.shape)
        out = fis.outputs[0]
        mesh = ax.pcolormesh(A, B, Z, shading="auto", vmin=out.range[0], vmax=out.range[1], cmap="viridis")
        fig.colorbar(mesh, ax=ax, label=out.name)
        fixed = {v.name: 0.5 * sum(v.range) for v in fis.inputs[2:]}
        for region in report.coverage.regions:
            if any(not (lo <= fixed[k] <= hi) for k, (lo, hi, *_) in region.bounds.items() if k in fixed):
                continue
            (alo, ahi, *_), (blo, bhi, *_) = region.bounds[a.name], region.bounds[b.name]
            ax.add_patch(Rectangle((alo, blo), max(ahi - alo, 1e-3), max(bhi - blo, 1e-3), fill=False,
                                   hatch="//", edgecolor="red", linewidth=1.5))
        for name, direction in monotone.items():
            if name not in (a.name, b.name):
                continue
            along = 1 if name == a.name else 0  # axis of Z that runs along the input
            step = direction * np.diff(Z, axis=along)
            tol = 1e-6 * (out.range[1] - out.range[0])
            bad = np.zeros(Z.shape, dtype=bool)
            if along == 1:
                bad[:, 1:] |= step < -tol
            else:
                bad[1:, :] |= step < -tol
            if bad.any():
                ax.contour(A, B, bad.astype(float), levels=[0.5], colors="white", linewidths=1.2)
        for m in report.monotonicity:
            if not m.holds and m.output == out.name and m.input in (a.name, b.name):
                ax.annotate("", xy=(m.end[a.name], m.end[b.name]), xytext=(m.start[a.name], m.start[b.name]),
                            arrowprops={"arrowstyle": "->", "color": "white", "linewidth": 2})
        ax.set_xlabel(a.name)
        ax.set_ylabel(b.name)
        ax.set_title(f"{out.name}: red hatch = no rule fires" + (", white = not monotone" if monotone else ""),
                     fontsize=9)
    fig.suptitle(f"{fis.name}: {'PASS' if report.ok else 'FAIL'}")
    return fig


def run(args: argparse.Namespace) -> int:
    output = check_output(args.output, (".png",), [args.rules], args.overwrite, what="figure")
    if args.resolution < 2:
        raise ValueError(f"--resolution {args.resolution}: expected an integer >= 2")
    fis = fuzzcore.load(args.rules)
    monotone = parse_monotone_specs(args.monotone)
    report = fuzzcore.verify(fis, monotone)
    fig = _draw(fis, report, monotone, args.resolution)
    save_figure(fig, output, 110)
    print(f"written to {output} ({'PASS' if report.ok else 'FAIL: ' + '; '.join(report.failures)})")
    return 0
