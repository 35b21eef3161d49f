"""Figures of a tolerance analysis: histograms of the constraints (limit marked) and of
the metrics (nominal and 5/95 % marked), and a tornado chart of one metric."""

from __future__ import annotations

import math

import numpy as np
from matplotlib.figure import Figure

from camopt.core.plotting import PAPER_STYLE, new_figure, plt, readable
from camopt.engine.tolerance import Tolerance

LIMIT_STYLE = {"color": "crimson", "linewidth": 1.5}


def _grid(n: int, title: str) -> tuple[Figure, list]:
    cols = min(3, n)
    rows = math.ceil(n / cols)
    fig, axes = plt.subplots(rows, cols, figsize=(3.6 * cols, 2.6 * rows), layout="constrained",
                             squeeze=False)
    fig.suptitle(title)
    flat = list(axes.ravel())
    for ax in flat[n:]:
        ax.set_visible(False)
    return fig, flat[:n]


def constraint_histograms(t: Tolerance) -> Figure:
    """Each normalised constraint g over the samples; the limit g = 0 in red (feasible
    at or left of it)."""
    yield_pct = 100 * float(np.mean(t.samples.feasible))
    fig, axes = _grid(len(t.constraint_names), f"Constraints over {len(t.inputs)} samples "
                      f"(yield {yield_pct:.1f} %)")
    for ax, i, name in zip(axes, range(len(t.constraint_names)), t.constraint_names):
        g = t.samples.g[:, i]
        ax.hist(g[np.isfinite(g)], bins=40, color="tab:blue", alpha=0.8)
        ax.axvline(0.0, label="limit", **LIMIT_STYLE)
        ax.set_xlabel(f"{name} (normalised g)")
        ax.set_ylabel("samples")
    return fig


def metric_histograms(t: Tolerance) -> Figure:
    """Every metric the varied inputs move: nominal (solid) and 5/95 % (dashed)."""
    columns = {k: v for k, v in t.metric_columns(t.samples).items()
               if np.isfinite(v).any() and np.ptp(v[np.isfinite(v)]) > 0}
    nominal = t.summary["nominal"]
    fig, axes = _grid(max(len(columns), 1), f"Metrics over {len(t.inputs)} samples")
    for ax, (name, values) in zip(axes, columns.items()):
        ax.hist(values[np.isfinite(values)], bins=40, color="tab:blue", alpha=0.8)
        ax.axvline(nominal[name], color="black", linewidth=1.2, label="nominal")
        for q in ("p05", "p95"):
            ax.axvline(t.summary["metrics"][name][q], **PAPER_STYLE)
        ax.set_xlabel(readable(name))
        ax.set_ylabel("samples")
    return fig


def tornado(t: Tolerance, metric: str) -> Figure:
    """One-at-a-time swings of ``metric``: each input at either end of its tolerance, the
    others nominal; widest swing on top."""
    rows = t.summary["one_at_a_time"][metric]
    base = t.summary["nominal"][metric]
    rows = sorted(rows, key=lambda r: abs(r["high"] - r["low"]))
    fig, ax = new_figure(f"Tornado: {readable(metric)} (nominal {base:.4g})",
                         readable(metric), "input at -X / +X")
    for y, r in enumerate(rows):
        for end, color in (("low", "tab:blue"), ("high", "tab:orange")):
            ax.barh(y, r[end] - base, left=base, color=color,
                    label=f"input at {'-' if end == 'low' else '+'}X" if y == 0 else None)
    ax.set_yticks(range(len(rows)), [r["input"] for r in rows])
    ax.axvline(base, color="black", linewidth=1.0)
    ax.legend()
    return fig


def figures(t: Tolerance, metric: str | None = None) -> dict[str, Figure]:
    """``constraints``, ``metrics`` and ``tornado`` (of ``metric``, default the quantity
    of the requirement that limits the yield, else the objective)."""
    return {"constraints": constraint_histograms(t), "metrics": metric_histograms(t),
            "tornado": tornado(t, metric or t.summary.get("limiting") or t.objective_name)}
