"""Figures of a tolerance analysis: histograms of the requirements' quantities in their
units with the limits marked (the run's normalised constraints when its case declares no
requirement), of the metrics (nominal, 5/95 % and any limit marked), and a tornado chart
of one metric with its limits and each input's tolerance in its label."""

from __future__ import annotations

import math
from collections.abc import Mapping

import numpy as np
from matplotlib.figure import Figure

from camopt.archive.samples import ToleranceSamples
from camopt.core.documents import ToleranceDoc
from camopt.core.plotting import PAPER_STYLE, figure, new_figure, readable
from camopt.core.requirements import Requirement
from camopt.engine.tolerance import Tolerance

LIMIT_STYLE = {"color": "crimson", "linewidth": 1.5}


def _grid(n: int, title: str) -> tuple[Figure, list]:
    """A grid of n small panels, three to a row. Fixed margins, not matplotlib's
    constrained layout: that solves its layout from every tick label's extent, which for
    a VCB's ~45 metric panels took ~4 s a figure (most of a tolerance report's time);
    the panels are alike, so fixed spacing places them as well."""
    cols = min(3, n)
    rows = math.ceil(n / cols)
    height = 2.6 * rows + 0.6  # inches: the panels and the title
    fig = figure(figsize=(3.6 * cols, height))
    axes = fig.subplots(rows, cols, squeeze=False)
    fig.subplots_adjust(left=0.9 / (3.6 * cols), right=1 - 0.3 / (3.6 * cols),
                        bottom=0.55 / height, top=1 - 0.6 / height, wspace=0.35,
                        hspace=0.75)
    fig.suptitle(title)
    flat = list(axes.ravel())
    for ax in flat[n:]:
        ax.set_visible(False)
    return fig, flat[:n]


def samples_of(t: Tolerance | ToleranceSamples) -> ToleranceSamples:
    """What the figures read, from a live analysis or a sample archive alike."""
    if isinstance(t, ToleranceSamples):
        return t
    return ToleranceSamples(t.summary, t.metric_columns(t.samples), t.samples.g,
                            tuple(t.constraint_names), t.samples.feasible, t.run_path)


def limits_of(summary: ToleranceDoc) -> dict[str, Requirement]:
    """The requirements with a numeric limit in an analysis' summary, by the quantity
    they bound (summaries written before the limits were stored give none)."""
    found = {}
    for row in summary.get("requirements", []):
        if row.get("flag") or ("lower" not in row and "upper" not in row):
            continue
        lower, upper = row.get("lower"), row.get("upper")
        found[row["quantity"]] = Requirement(
            row["name"], row["quantity"], row.get("unit", ""),
            -math.inf if lower is None else float(lower),
            math.inf if upper is None else float(upper))
    return found


def _mark_limits(ax: object, req: Requirement | None) -> None:
    """Red lines at a requirement's finite lower and upper limits."""
    if req is None:
        return
    for bound, side in ((req.lower, "lower"), (req.upper, "upper")):
        if math.isfinite(bound):
            ax.axvline(bound, label=f"{side} limit", **LIMIT_STYLE)  # type: ignore[attr-defined]


def constraint_histograms(t: Tolerance | ToleranceSamples) -> Figure:
    """Each requirement's quantity over the samples in its unit with its limits in red
    and its yield in the title; a case without requirements shows the run's normalised
    constraints g (limit g = 0, feasible at or left of it)."""
    s = samples_of(t)
    yield_pct = 100 * float(np.mean(s.feasible))
    title = f"Requirements over {len(s.feasible)} samples (yield {yield_pct:.1f} %)"
    columns = s.columns
    reqs = [r for r in limits_of(s.summary).values() if r.quantity in columns]
    if not reqs:
        fig, axes = _grid(len(s.constraint_names), title.replace("Requirements",
                                                                   "Constraints"))
        for ax, i, name in zip(axes, range(len(s.constraint_names)), s.constraint_names):
            g = s.g[:, i]
            ax.hist(g[np.isfinite(g)], bins=40, color="tab:blue", alpha=0.8)
            ax.axvline(0.0, label="limit", **LIMIT_STYLE)
            ax.set_xlabel(f"{name} (normalised g)")
            ax.set_ylabel("samples")
        return fig
    yields = {row["quantity"]: row["yield"] for row in s.summary.get("requirements", [])}
    fig, axes = _grid(len(reqs), title)
    for ax, req in zip(axes, reqs):
        values = columns[req.quantity]
        ax.hist(values[np.isfinite(values)], bins=40, color="tab:blue", alpha=0.8)
        _mark_limits(ax, req)
        ax.axvline(s.summary["nominal"][req.quantity], color="black", linewidth=1.2,
                   label="nominal")
        share = yields.get(req.quantity)
        ax.set_title(f"{req.name}" + (f": {100 * share:.1f} % pass" if share is not None
                                      else ""), fontsize=8)
        ax.set_xlabel(readable(req.quantity))  # the quantity's name carries its unit
        ax.set_ylabel("samples")
    return fig


def metric_histograms(t: Tolerance | ToleranceSamples) -> Figure:
    """Every metric the varied inputs move: nominal (solid), 5/95 % (dashed) and the
    limits of a requirement on it (red)."""
    s = samples_of(t)
    columns = {k: v for k, v in s.columns.items()
               if np.isfinite(v).any() and np.ptp(v[np.isfinite(v)]) > 0}
    nominal = s.summary["nominal"]
    limits = limits_of(s.summary)
    fig, axes = _grid(max(len(columns), 1), f"Metrics over {len(s.feasible)} samples")
    for ax, (name, values) in zip(axes, columns.items()):
        ax.hist(values[np.isfinite(values)], bins=40, color="tab:blue", alpha=0.8)
        ax.axvline(nominal[name], color="black", linewidth=1.2, label="nominal")
        for q in ("p05", "p95"):
            ax.axvline(s.summary["metrics"][name][q], **PAPER_STYLE)
        _mark_limits(ax, limits.get(name))
        ax.set_xlabel(readable(name))
        ax.set_ylabel("samples")
    return fig


def tornado(t: Tolerance | ToleranceSamples, metric: str) -> Figure:
    """One-at-a-time swings of ``metric``: each input at either end of its tolerance, the
    others nominal; widest swing on top. Each bar runs from the nominal value to the
    metric's value with the input at that end: the orange bar ends where the input at +X
    puts the metric, the blue where -X does (whichever side of nominal that is). Labels
    carry each input's tolerance; a requirement's limits on the metric are red lines."""
    rows = t.summary["one_at_a_time"][metric]
    base = t.summary["nominal"][metric]
    tolerances = {v["input"]: v for v in t.summary.get("vary", [])}
    rows = sorted(rows, key=lambda r: abs(r["high"] - r["low"]))
    fig, ax = new_figure(f"Tornado: {readable(metric)} (nominal {base:.4g})",
                         readable(metric), "input at -X / +X")
    for y, r in enumerate(rows):
        for end, color, sign in (("low", "tab:blue", "-"), ("high", "tab:orange", "+")):
            at = r["low"] if end == "low" else r["high"]
            ax.barh(y, at - base, left=base, color=color, alpha=0.85,
                    label=f"input at {sign}X" if y == 0 else None, gid=f"{end}-{y}")
    ax.set_yticks(range(len(rows)), [_tolerance_label(r["input"], tolerances)
                                     for r in rows])
    ax.axvline(base, color="black", linewidth=1.0)
    _mark_limits(ax, limits_of(t.summary).get(metric))
    ax.legend(fontsize=7)
    return fig


def _tolerance_label(name: str, tolerances: Mapping[str, Mapping[str, object]]) -> str:
    """``kc1_n_per_mm ±5%`` or ``case.l1_mm ±0.05``: the input and the tolerance used."""
    v = tolerances.get(name)
    if v is None:
        return name
    return f"{name} ±{v['tolerance']:g}{'%' if v['unit'] == '%' else ''}"


def figures(t: Tolerance | ToleranceSamples, metric: str | None = None
            ) -> dict[str, Figure]:
    """``constraints``, ``metrics`` and ``tornado`` (of ``metric``, default the quantity
    of the requirement that limits the yield, else the objective: the summary's first
    metric)."""
    default = t.summary.get("limiting") or next(iter(t.summary["metrics"]))
    return {"constraints": constraint_histograms(t), "metrics": metric_histograms(t),
            "tornado": tornado(t, metric or default)}
