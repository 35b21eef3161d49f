"""Figures of a fast-switch run: closure time over the coil family, the exact motion."""

from __future__ import annotations

import numpy as np
from matplotlib.figure import Figure

from camopt.cases.fast_switch.paper import PAPER
from camopt.core.plotting import PAPER_STYLE, new_figure
from camopt.core.runview import RunView


def figures(run: RunView) -> dict[str, Figure]:
    """``closure_time`` (Table 1 beside camopt's family, when the run tabulates coil counts)
    and ``motion`` (theta2(t) of the exact dynamics of the best design)."""
    figs = {}
    rows = run.table
    if rows and "coils" in rows[0]:
        fig, ax = new_figure("Closure time against coils (the 1-DOF family)",
                             "number of coils", "closure time (ms)")
        coils = np.array([r["coils"] for r in rows])
        tf = np.array([r["closure_time_ms"] for r in rows])
        ok = np.array([r["feasible"] for r in rows])
        ax.plot(coils[ok], tf[ok], "o-", label="camopt, feasible")
        ax.plot(coils[~ok], tf[~ok], "x", color="gray", label="camopt, infeasible (R2)")
        ax.plot(PAPER["table1_coils"], PAPER["table1_closure_time_ms"], "s", mfc="none",
                color=PAPER_STYLE["color"], label="paper, Table 1")
        ax.legend()
        figs["closure_time"] = fig
    a = run.analysis
    if "time_ms" in a:
        fig, ax = new_figure("Exact closing motion (Eqs 2-3)", "time (ms)",
                             "crank angle theta2 (deg)")
        ax.plot(a["time_ms"], a["theta2_deg"], label="theta2(t), best design")
        ax.axhline(90, color="gray", linestyle=":", label="closed (theta2 = 90 deg)")
        ax.legend()
        figs["motion"] = fig
    return figs
