"""Figures of an EMB cam run: torque and clamping force, the profile, lift and pressure
angle against the cam rotation."""

from __future__ import annotations

from matplotlib.figure import Figure

from camopt.cases.emb_cam.paper import PAPER
from camopt.core.plotting import PAPER_STYLE, new_figure
from camopt.core.runview import RunView


def figures(run: RunView) -> dict[str, Figure]:
    """``torque_force``, ``profile`` and ``lift`` of the best design."""
    a = run.analysis
    if "rotation_rad" not in a:
        return {}
    figs = {}
    fig, ax = new_figure("Drive torque and clamping force against rotation",
                         "cam rotation angle phi (rad)", "drive torque (N m)")
    ax.plot(a["rotation_rad"], a["torque_nm"], label="cam, drive torque")
    ax.plot(a["rotation_rad"], a["screw_torque_nm"], ":", label="ideal ball screw, same travel")
    ax.axhline(PAPER["peak_torque_nm"], label="paper's peak torque 7.72 N m", **PAPER_STYLE)
    ax.axvline(PAPER["clearance_angle_rad"], label="paper's clearance angle 1.72 rad",
               color="gray", linestyle="-.")
    ax2 = ax.twinx()
    ax2.plot(a["rotation_rad"], a["clamping_force_kn"], color="tab:green",
             label="clamping force")
    ax2.set_ylabel("clamping force (kN)")
    lines, lines2 = ax.get_legend_handles_labels(), ax2.get_legend_handles_labels()
    ax.legend(lines[0] + lines2[0], lines[1] + lines2[1], fontsize=8, loc="upper left")
    figs["torque_force"] = fig
    fig, ax = new_figure("Cam profile", "x (mm)", "y (mm)")
    ax.plot(a["profile_x_mm"], a["profile_y_mm"], label="working segment")
    ax.plot(a["nonworking_x_mm"], a["nonworking_y_mm"], ":", label="non-working arc")
    ax.plot([0], [0], "k+", markersize=12, label="rotation centre O")
    ax.set_aspect("equal", adjustable="datalim")
    ax.legend()
    figs["profile"] = fig
    fig, ax = new_figure("Lift and pressure angle", "cam rotation angle phi (rad)", "lift (mm)")
    ax.plot(a["rotation_rad"], a["lift_mm"], label="lift")
    ax2 = ax.twinx()
    ax2.plot(a["rotation_rad"], a["pressure_angle_deg"], color="tab:orange",
             label="pressure angle")
    ax2.set_ylabel("pressure angle (deg)")
    lines, lines2 = ax.get_legend_handles_labels(), ax2.get_legend_handles_labels()
    ax.legend(lines[0] + lines2[0], lines[1] + lines2[1], fontsize=8, loc="upper left")
    figs["lift"] = fig
    return figs
