"""Figures of a VCB run: cam profile, pressure angle, curvature, contact stresses and the
forces along the stroke, each for the optimum beside the vendor's design.

The cam's outline is imported where a figure draws it (matplotlib figures are drawn on
request only)."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import replace

import numpy as np
from matplotlib.figure import Figure

from camopt.cases.vcb.paper import PAPER
from camopt.cases.vcb.requirements import CLOSING_VELOCITY_M_S
from camopt.core.plotting import PAPER_STYLE, log_scale_if_spread, new_figure
from camopt.core.runview import RunView
from camopt.mechanics import Floats
from camopt.mechanics.cam_outline import CamOutline
from camopt.units import DEG, MM, TO_DEG

DESIGNS = (("", "optimum", "-"), ("initial_", "reference: vendor", ":"))


def figures(run: RunView) -> dict[str, Figure]:
    """``cam_profile``, ``pressure_angle``, ``curvature``, ``tau_max``, ``sigma_max`` and
    ``forces`` (needs the analysis curves of a run's best design)."""
    a = run.analysis
    if "profile_x_mm" not in a:
        return {}
    figs = {}
    outlines = {prefix: _outline(run, prefix) for prefix, _, _ in DESIGNS}
    fig, ax = new_figure("Cam profile and pitch curve, full turn (bold: actuated stroke)",
                         "x (mm)", "y (mm)")
    for (prefix, label, style), colour in zip(DESIGNS, ("tab:blue", "dimgrey")):
        whole = outlines[prefix]
        for curve, alpha in (("profile", 1.0), ("pitch", 0.45)):
            name = "profile" if curve == "profile" else "pitch curve"
            if whole is not None:  # the full turn the workshop cuts, closed
                xy = getattr(whole, curve) / MM
                xy = np.vstack([xy, xy[:1]])
                ax.plot(xy[:, 0], xy[:, 1], style, lw=0.9, alpha=alpha, color=colour,
                        label=f"{name}, {label}")
            ax.plot(a[f"{prefix}{curve}_x_mm"], a[f"{prefix}{curve}_y_mm"], style, lw=2.4,
                    alpha=alpha, color=colour, label=f"{name}, {label}, actuated stroke"
                    if whole is None else "_actuated")
    ax.plot([0], [0], "k+", markersize=12, label="cam pivot O")
    ax.set_aspect("equal", adjustable="datalim")
    ax.legend(fontsize=7, loc="upper center", bbox_to_anchor=(0.5, -0.14), ncol=3)
    figs["cam_profile"] = fig
    for key, title, ylabel, mark, mark_label in (
        ("pressure_angle_deg", "Pressure angle over the full turn (actuated stroke bold)",
         "pressure angle (deg)", PAPER["max_pressure_angle_deg"], "allowable 45 deg (paper)"),
        ("curvature_mm", "Radius of curvature of the cam profile over the full turn "
         "(actuated stroke bold)", "radius of curvature (mm)",
         PAPER["roller_radius_mm"], "roller radius rf (undercut below)"),
        ("tau_max_mpa", "Maximum shear stress beneath the cam surface", "tau_max (MPa)",
         PAPER["shear_yield_mpa"], "shear yield 1194 MPa (paper)"),
        ("sigma_max_mpa", "Maximum Hertz contact stress", "sigma_max (MPa)", None, ""),
    ):
        fig, ax = new_figure(title, "cam angle theta_c (deg)", ylabel)
        geometric = key in ("pressure_angle_deg", "curvature_mm")
        ax.plot(a["cam_angle_deg"], a[key], lw=2.2 if geometric else None, label="optimum")
        ax.plot(a["initial_cam_angle_deg"], a["initial_" + key], ":",
                lw=2.2 if geometric else None, label="reference: vendor")
        everything = [a[key], a["initial_" + key]]
        for (prefix, label, style), colour in zip(DESIGNS if geometric else (),
                                                  ("tab:blue", "tab:orange")):
            whole = outlines[prefix]
            if whole is None:
                continue
            closure = whole.closure()
            values = (whole.pressure_angle * TO_DEG if key == "pressure_angle_deg"
                      else whole.curvature / MM)
            # the closure only: the bold actuated stroke is the archived curve
            ax.plot(whole.theta * TO_DEG, np.where(closure, values, np.nan), style,
                    lw=0.9, color=colour, label=f"{label}, closing the turn")
            everything.append(values)
        if mark is not None:
            ax.axhline(mark, label=mark_label, **PAPER_STYLE)
        if key in ("tau_max_mpa", "sigma_max_mpa", "curvature_mm"):
            log_scale_if_spread(ax, np.concatenate(everything))
        ax.legend(fontsize=8)
        figs[key.rsplit("_", 1)[0]] = fig
    figs["cam_torque"] = _cam_torque(a)
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
        figs.update(_dynamics(a, run))
    return figs


def _outline(run: RunView, prefix: str) -> CamOutline | None:
    """The closed full-turn outline of the optimum (``prefix`` '') or of the vendor's
    design (``initial_``: its law's coefficients ``initial_a0..``); None without a law."""
    from camopt.cases.vcb.outline import outline

    metrics = run.best.metrics
    law = {f"a{k}": metrics.get(f"{prefix}a{k}") for k in range(6)}
    best = replace(run.best, metrics={k: v for k, v in law.items() if v is not None})
    try:
        return outline(replace(run, best=best))
    except ValueError:  # a law whose closure needs more than a turn: the stroke only
        return None


def _cam_torque(a: Mapping[str, Floats]) -> Figure:
    """Torque on the cam against cam angle: the closing springs' drive and the load's
    resistance along the stroke (quasi-static, the slopes of the archived works, N m per
    rad), and the torque the cam passes to the roller during the closing (dynamics)."""
    fig, ax = new_figure("Cam torque against cam angle", "cam angle theta_c (deg)",
                         "torque (N m)")
    for prefix, label, style in DESIGNS:
        theta = a[prefix + "cam_angle_deg"] * DEG
        for key, what in (("driving_work_j", "spring drive"),
                          ("resistant_work_j", "load resistance")):
            work = a.get(prefix + key)
            if work is not None and np.size(work) == theta.size and theta.size > 2:
                with np.errstate(all="ignore"):
                    torque = np.gradient(work, theta)
                ax.plot(theta * TO_DEG, torque, style, label=f"{what} (quasi-static), "
                        f"{label}", color="tab:blue" if what == "spring drive" else "tab:red")
        t_angle, torque = a.get(prefix + "dyn_cam_angle_deg"), a.get(prefix + "dyn_cam_torque_nm")
        if t_angle is not None and torque is not None and np.size(torque):
            ax.plot(t_angle, torque, style, color="tab:green",
                    label=f"to the roller while closing (dynamics), {label}")
    if not any(np.size(a.get(p + "dyn_cam_torque_nm", [])) for p, _, _ in DESIGNS[:1]):
        ax.text(0.01, 0.01, "optimum: no closing dynamics (the design does not close)",
                transform=ax.transAxes, fontsize=7, color="dimgrey")
    ax.axhline(0.0, color="k", lw=0.6)
    ax.legend(fontsize=7)
    return fig


def _window(a: Mapping[str, Floats], prefix: str, gap: float) -> tuple[float, float] | None:
    """Times (ms) at which the movable contact has covered 2/3 of its gap and all of it:
    the window the average closing velocity is taken over (the last third of the contact
    stroke, Sec 2.1), read off the archived rod travel, which the contacts follow until
    they touch (their curve is min(rod, gap): from the first node after the touch it stays
    at the gap, so reading the gap off it ends the window at that node, up to one step
    late); None if it never gets there."""
    t, s = a[prefix + "time_ms"], a[prefix + "dyn_rod_travel_mm"]
    if not t.size or np.nanmax(s) < gap:
        return None
    first = [int(np.argmax(s >= level)) for level in (2 * gap / 3, gap)]
    return tuple(float(np.interp(level, s[max(i - 1, 0):i + 1], t[max(i - 1, 0):i + 1]))
                 for i, level in zip(first, (2 * gap / 3, gap)))  # type: ignore[return-value]


def _finite(metrics: Mapping[str, object], names: list[str]) -> list[float] | None:
    """The metrics ``names`` as floats, or None unless all are finite numbers."""
    values = [metrics.get(n) for n in names]
    if all(isinstance(v, (int, float)) and np.isfinite(v) for v in values):
        return [float(v) for v in values]  # type: ignore[arg-type]
    return None


def _dynamics(a: Mapping[str, Floats], run: RunView) -> dict[str, Figure]:
    """Closing against time: displacements and velocities of rod and movable contact, with
    what a breaker engineer reads on them: the contact gap, the window of the average
    closing velocity (shaded), the requirement band (green), the optimum's average over
    the window with its band over the parameter sets equally consistent with the ADAMS
    data (error bar), and the touch instant with that band (dashed line, grey span)."""
    figs = {}
    m = run.best.metrics
    gap = run.case.get("contact_gap_mm")
    band = run.case.get("closing_velocity_m_s") or CLOSING_VELOCITY_M_S
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
        # the curves set the time axis; a parameter set that closes far later is a span
        # running off it, not a reason to squeeze the curves
        times = np.concatenate([a[p + "time_ms"] for p, _, _ in DESIGNS])
        if times.size:
            ax.set_xlim(float(times.min()), float(times.max()))
        limits = ax.get_xlim()
        window = _window(a, "", float(gap)) if gap is not None else None
        if window is not None:
            ax.axvspan(*window, color="tab:blue", alpha=0.12,
                       label="closing-velocity window (last third of the gap)")
        touch = _finite(m, [f"touch_time{s}_ms" for s in ("", "_low", "_high")])
        if touch is not None:
            ax.axvline(touch[0], color="k", lw=0.9, ls="--", label="contacts touch")
            if touch[2] > touch[1]:
                ax.axvspan(touch[1], touch[2], color="grey", alpha=0.2,
                           label="touch over the parameter sets")
        if key == "travel_mm" and gap is not None:
            ax.axhline(gap, color="k", lw=0.6, ls=":", label=f"contact gap {gap:g} mm")
        if key == "velocity_m_s":
            ax.axhspan(float(band[0]), float(band[1]), color="tab:green", alpha=0.12,
                       label=f"required {band[0]:g}-{band[1]:g} m/s")
            v = _finite(m, [f"closing_velocity{s}_m_s" for s in ("_avg", "_low", "_high")])
            if window is not None and v is not None:
                mid = sum(window) / 2
                ax.errorbar([mid], [v[0]], yerr=[[v[0] - v[1]], [v[2] - v[0]]], fmt="o",
                            color="tab:red", capsize=4,
                            label=f"average {v[0]:.3g} m/s ({v[1]:.3g}-{v[2]:.3g} over sets)")
        ax.set_xlim(*limits)
        ax.legend(fontsize=7)
        figs["closing_" + key.split("_")[0]] = fig
    return figs
