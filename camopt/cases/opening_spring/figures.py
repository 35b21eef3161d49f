"""Figures of an opening-spring run: the simulated motion against the desired one (Eq 7)."""

from __future__ import annotations

from matplotlib.figure import Figure

from camopt.cases.opening_spring.paper import THETA_RAD, THETADOT_T0_RAD_S
from camopt.core.plotting import PAPER_STYLE, new_figure
from camopt.core.runview import RunView

STYLES = ("--", ":", "-.", (0, (3, 1, 1, 1)), (0, (5, 2)))


def _name(label: str) -> str:
    return "this design" if label == "design" else label.replace("_", " ")


def figures(run: RunView) -> dict[str, Figure]:
    """``theta_thetadot`` (velocity against angle, Fig 6/7 of the paper) and
    ``theta_time`` for the design and every design simulated beside it."""
    a = run.analysis
    if "desired_theta_rad" not in a:
        return {}
    fig, ax = new_figure("Follower motion: desired (Eq 7) against simulated",
                         "follower angle theta (rad)", "angular velocity theta' (rad/s)")
    ax.plot(a["desired_theta_rad"], a["desired_rate_rad_s"], "k-", linewidth=2,
            label="desired (Eq 7)")
    labels = [k.removesuffix("_theta_rad") for k in a
              if k.endswith("_theta_rad") and not k.startswith("desired")]
    for label, style in zip(labels, STYLES):
        ax.plot(a[f"{label}_theta_rad"], a[f"{label}_rate_rad_s"], linestyle=style,
                label=_name(label))
    ax.plot([THETA_RAD[0]], [THETADOT_T0_RAD_S], "o",
            color=PAPER_STYLE["color"], label="Eq 6: theta(t0), theta'(t0)")
    for i, th in enumerate(THETA_RAD[1:]):
        ax.axvline(th, label="Eq 6: theta(tk), theta(ts)" if i == 0 else None, **PAPER_STYLE)
    ax.legend()
    fig2, ax2 = new_figure("Follower angle against time", "time (ms)",
                           "follower angle theta (rad)")
    ax2.plot(a["desired_time_ms"], a["desired_theta_rad"], "k-", label="desired (Eq 7)")
    for label in labels:
        ax2.plot(a[f"{label}_time_ms"], a[f"{label}_theta_rad"], "--", label=_name(label))
    ax2.legend()
    return {"theta_thetadot": fig, "theta_time": fig2}
