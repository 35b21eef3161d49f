"""Figures of a VCB run: cam profile, pressure angle, curvature, contact stresses and the
forces along the stroke, each for the optimum beside the vendor's design."""

from __future__ import annotations

import numpy as np
from matplotlib.figure import Figure

from camopt.cases.vcb.paper import PAPER
from camopt.core.plotting import PAPER_STYLE, log_scale_if_spread, new_figure
from camopt.core.runview import RunView

DESIGNS = (("", "optimum", "-"), ("initial_", "reference: vendor", ":"))


def figures(run: RunView) -> dict[str, Figure]:
    """``cam_profile``, ``pressure_angle``, ``curvature``, ``tau_max``, ``sigma_max`` and
    ``forces`` (needs the analysis curves of a run's best design)."""
    a = run.analysis
    if "profile_x_mm" not in a:
        return {}
    figs = {}
    fig, ax = new_figure("Cam profile and pitch curve (actuated portion)", "x (mm)", "y (mm)")
    for prefix, label, style in DESIGNS:
        ax.plot(a[prefix + "profile_x_mm"], a[prefix + "profile_y_mm"], style,
                label=f"profile, {label}")
        ax.plot(a[prefix + "pitch_x_mm"], a[prefix + "pitch_y_mm"], style, alpha=0.6,
                label=f"pitch curve, {label}")
    ax.plot([0], [0], "k+", markersize=12, label="cam pivot O")
    ax.set_aspect("equal", adjustable="datalim")
    ax.legend(fontsize=8)
    figs["cam_profile"] = fig
    for key, title, ylabel, mark, mark_label in (
        ("pressure_angle_deg", "Pressure angle", "pressure angle (deg)",
         PAPER["max_pressure_angle_deg"], "allowable 45 deg (paper)"),
        ("curvature_mm", "Radius of curvature of the cam profile", "radius of curvature (mm)",
         PAPER["roller_radius_mm"], "roller radius rf (undercut below)"),
        ("tau_max_mpa", "Maximum shear stress beneath the cam surface", "tau_max (MPa)",
         PAPER["shear_yield_mpa"], "shear yield 1194 MPa (paper)"),
        ("sigma_max_mpa", "Maximum Hertz contact stress", "sigma_max (MPa)", None, ""),
    ):
        fig, ax = new_figure(title, "cam angle theta_c (deg)", ylabel)
        ax.plot(a["cam_angle_deg"], a[key], label="optimum")
        ax.plot(a["initial_cam_angle_deg"], a["initial_" + key], ":", label="reference: vendor")
        if mark is not None:
            ax.axhline(mark, label=mark_label, **PAPER_STYLE)
        if key in ("tau_max_mpa", "sigma_max_mpa", "curvature_mm"):
            log_scale_if_spread(ax, np.r_[a[key], a["initial_" + key]])
        ax.legend()
        figs[key.rsplit("_", 1)[0]] = fig
    fig, ax = new_figure("General output force Fo and resistant force Fr along the stroke",
                         "rod travel s1 (mm)", "force (N)")
    for prefix, label, style in DESIGNS:
        ax.plot(a[prefix + "rod_travel_mm"], a[prefix + "fo_n"], style, label=f"Fo, {label}")
        ax.plot(a[prefix + "rod_travel_mm"], a[prefix + "fr_n"], style, label=f"Fr, {label}")
    fo = np.abs(a["fo_n"][np.isfinite(a["fo_n"])])
    if fo.size:
        ax.set_ylim(0, 3 * np.percentile(np.r_[fo, a["fr_n"][np.isfinite(a["fr_n"])]], 95))
    if "contact_gap_mm" in run.case:
        ax.axvline(run.case["contact_gap_mm"], color="k", lw=0.8, ls="--",
                   label="contacts touch")
    ax.legend()
    figs["forces"] = fig
    if "time_ms" in a:
        figs.update(_dynamics(a))
    return figs


def _dynamics(a: dict) -> dict[str, Figure]:
    """Closing against time: displacements and velocities of rod and movable contact."""
    figs = {}
    for key, title, ylabel in (
        ("travel_mm", "Closing: rod and movable contact against time", "displacement (mm)"),
        ("velocity_m_s", "Closing: rod and movable contact velocity", "velocity (m/s)"),
    ):
        fig, ax = new_figure(title, "time from the springs' release (ms)", ylabel)
        for prefix, label, style in DESIGNS:
            t = a[prefix + "time_ms"]
            ax.plot(t, a[prefix + "dyn_rod_" + key], style, label=f"rod, {label}")
            ax.plot(t, a[prefix + "dyn_contact_" + key], style, lw=2.5, alpha=0.5,
                    label=f"movable contact, {label}")
        ax.legend(fontsize=8)
        figs["closing_" + key.split("_")[0]] = fig
    return figs
