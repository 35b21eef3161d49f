"""Figures of runs and sweeps: convergence, plus each case's own figures (its spec's
``figures``). Every function returns ``{name: Figure}`` so tests can read axes and
labels; :func:`save` writes them as PNGs."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
from matplotlib.figure import Figure

from camopt import pareto
from camopt.cases import get_case
from camopt.plotting import PAPER_STYLE, close, new_figure, readable
from camopt.runview import RunView


def _band(histories: list[np.ndarray]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Median and inter-quartile band of best-so-far curves (shorter ones hold their end)."""
    n = max(len(h) for h in histories)
    stack = np.array([np.r_[h, np.full(n - len(h), h[-1])] for h in histories], dtype=float)
    stack = np.where(np.isfinite(stack), stack, np.nan)
    with np.errstate(all="ignore"):
        return tuple(np.nanpercentile(stack, q, axis=0) for q in (50, 25, 75))  # type: ignore


def _scale(ax: Any, values: np.ndarray) -> None:
    finite = values[np.isfinite(values)]
    if finite.size and finite.min() >= 0 and finite.max() > 0:
        positive = finite[finite > 0]
        floor = positive.min() if positive.size else 1.0
        ax.set_yscale("symlog", linthresh=max(floor, finite.max() * 1e-12))


def convergence(curves: dict[str, list[np.ndarray]], objective: str) -> Figure:
    """Median and inter-quartile band of the best objective over iterations."""
    fig, ax = new_figure("Convergence (median and inter-quartile band over repeats)",
                         "iteration (generation)", f"best {readable(objective)}")
    allv = []
    for label, hist in curves.items():
        med, lo, hi = _band(hist)
        x = np.arange(1, med.size + 1)
        ax.plot(x, med, label=f"{label} (n = {len(hist)})")
        ax.fill_between(x, lo, hi, alpha=0.25)
        allv.append(med)
    _scale(ax, np.concatenate(allv))
    ax.legend()
    return fig


def run_figures(run: RunView) -> dict[str, Figure]:
    """Convergence and the case's figures for one run archive."""
    figs = {"convergence": convergence({"repeats": run.histories()}, run.objective_name)}
    if len(pareto.objectives(run)[0]) >= 2:
        figs["pareto"] = pareto_front(run)
    figs.update(get_case(run.kind).draw(run))
    return figs


def pareto_front(run: RunView) -> Figure:
    """The Pareto set in its first two objectives, infeasible members hollow, and the
    paper's design (the case's ``paper`` values of those metrics) and the case's initial
    design (metrics ``initial_<name>``) marked when known."""
    names, _ = pareto.objectives(run)
    a, b = names[:2]
    fig, ax = new_figure(f"Pareto front ({len(run.table)} designs)", readable(a), readable(b))
    rows = pareto.rows(run) or []
    for feasible, style in ((True, {"color": "tab:blue"}),
                            (False, {"facecolors": "none", "edgecolors": "grey"})):
        pts = np.array([[r[a], r[b]] for r in rows if r["feasible"] is feasible], dtype=float)
        if len(pts):
            ax.scatter(pts[:, 0], pts[:, 1], s=18, label="feasible" if feasible
                       else "infeasible", **style)
    paper = get_case(run.kind).paper
    if a in paper and b in paper:
        ax.scatter([paper[a]], [paper[b]], marker="*", s=160, color=PAPER_STYLE["color"],
                   label="paper's design", zorder=3)
    m = run.best.metrics  # a case's initial design, reported with the prefix initial_
    initial = [m.get(f"initial_{n}") for n in (a, b)]
    if all(isinstance(v, float) and np.isfinite(v) for v in initial):
        ax.scatter([initial[0]], [initial[1]], marker="D", s=60,
                   color="black", label="initial design", zorder=3)
    ax.legend()
    return fig


def sweep_figures(spec: Any, results: dict) -> dict[str, Figure]:
    """Convergence with one line per grid point."""
    curves: dict[str, list[np.ndarray]] = {}
    for (point, _), r in sorted(results.items()):
        label = ", ".join(f"{k}={v}" for k, v in spec.points()[point].items()) or "base"
        curves.setdefault(label, []).append(np.asarray(r.history["best_objective"]))
    return {"convergence": convergence(curves, "objective")}


def save(figures: dict[str, Figure], out_dir: Path, stem: str) -> list[Path]:
    """Write each figure as ``<stem>-<name>.png``; close them."""
    out_dir.mkdir(parents=True, exist_ok=True)
    paths = []
    for name, fig in figures.items():
        path = out_dir / f"{stem}-{name}.png"
        fig.savefig(path, dpi=110)
        close(fig)
        paths.append(path)
    return paths
