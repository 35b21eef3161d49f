"""Figures of runs and sweeps (matplotlib, Agg): convergence and each case's curves.

Every function returns ``{name: Figure}`` so tests can read axes and labels; ``save``
writes them as PNGs. The papers' reported values are marked from ``data/papers.toml``.
"""

from __future__ import annotations

import sys
from collections.abc import Callable
from importlib import resources
from pathlib import Path
from typing import Any

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.figure import Figure  # noqa: E402

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

PAPER_STYLE = {"color": "crimson", "linestyle": "--", "linewidth": 1.2}


def paper_values() -> dict[str, Any]:
    """The papers' reported values (for marking plots only)."""
    return tomllib.loads((resources.files("camopt.data") / "papers.toml").read_text())


def _fig(title: str, xlabel: str, ylabel: str) -> tuple[Figure, Any]:
    fig, ax = plt.subplots(figsize=(7, 4.5), layout="constrained")
    ax.set_title(title)
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    ax.grid(alpha=0.3)
    return fig, ax


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


UNITS = {"j": "J", "ms": "ms", "n": "N", "nm": "N m", "mm": "mm", "rad": "rad", "sq": ""}


def readable(name: str) -> str:
    """'closure_time_ms' -> 'closure time (ms)'."""
    stem, _, unit = name.rpartition("_")
    if stem and unit in UNITS:
        return f"{stem.replace('_', ' ')} ({UNITS[unit]})" if UNITS[unit] else stem
    return name.replace("_", " ")


def convergence(curves: dict[str, list[np.ndarray]], objective: str) -> Figure:
    """Median and inter-quartile band of the best objective over iterations."""
    fig, ax = _fig("Convergence (median and inter-quartile band over repeats)",
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


# ---- case figures ---------------------------------------------------------------------
def _vcb(run: dict[str, Any]) -> dict[str, Figure]:
    a, paper = run["extra"]["analysis"], paper_values()["vcb"]
    figs = {}
    fig, ax = _fig("Cam profile and pitch curve (actuated portion)", "x (mm)", "y (mm)")
    for prefix, label, style in (("", "optimum", "-"), ("initial_", "vendor", ":")):
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
         paper["max_pressure_angle_deg"], "allowable 45 deg (paper)"),
        ("curvature_mm", "Radius of curvature of the cam profile", "radius of curvature (mm)",
         paper["roller_radius_mm"], "roller radius rf (undercut below)"),
        ("tau_max_mpa", "Maximum shear stress beneath the cam surface", "tau_max (MPa)",
         paper["shear_yield_mpa"], "shear yield 1194 MPa (paper)"),
        ("sigma_max_mpa", "Maximum Hertz contact stress", "sigma_max (MPa)", None, ""),
    ):
        fig, ax = _fig(title, "cam angle theta_c (deg)", ylabel)
        ax.plot(a["cam_angle_deg"], a[key], label="optimum")
        ax.plot(a["initial_cam_angle_deg"], a["initial_" + key], ":", label="vendor")
        if mark is not None:
            ax.axhline(mark, label=mark_label, **PAPER_STYLE)
        if key in ("tau_max_mpa", "sigma_max_mpa", "curvature_mm"):
            finite = np.r_[a[key], a["initial_" + key]]
            finite = finite[np.isfinite(finite)]
            if finite.size and finite.max() > 20 * np.median(np.abs(finite)):
                ax.set_yscale("log")
        ax.legend()
        figs[key.rsplit("_", 1)[0]] = fig
    fig, ax = _fig("General output force Fo and resistant force Fr along the stroke",
                   "rod travel s1 (mm)", "force (N)")
    for prefix, label, style in (("", "optimum", "-"), ("initial_", "vendor", ":")):
        ax.plot(a[prefix + "rod_travel_mm"], a[prefix + "fo_n"], style, label=f"Fo, {label}")
        ax.plot(a[prefix + "rod_travel_mm"], a[prefix + "fr_n"], style, label=f"Fr, {label}")
    fo = np.abs(a["fo_n"][np.isfinite(a["fo_n"])])
    if fo.size:
        ax.set_ylim(0, 3 * np.percentile(np.r_[fo, a["fr_n"][np.isfinite(a["fr_n"])]], 95))
    ax.legend()
    figs["forces"] = fig
    return figs


def _emb(run: dict[str, Any]) -> dict[str, Figure]:
    a, paper = run["extra"]["analysis"], paper_values()["emb_cam"]
    figs = {}
    fig, ax = _fig("Drive torque and clamping force against rotation",
                   "cam rotation angle phi (rad)", "drive torque (N m)")
    ax.plot(a["rotation_rad"], a["torque_nm"], label="cam, drive torque")
    ax.plot(a["rotation_rad"], a["screw_torque_nm"], ":", label="ideal ball screw, same travel")
    ax.axhline(paper["peak_torque_nm"], label="paper's peak torque 7.72 N m", **PAPER_STYLE)
    ax.axvline(paper["clearance_angle_rad"], label="paper's clearance angle 1.72 rad",
               color="gray", linestyle="-.")
    ax2 = ax.twinx()
    ax2.plot(a["rotation_rad"], a["clamping_force_kn"], color="tab:green",
             label="clamping force")
    ax2.set_ylabel("clamping force (kN)")
    lines = ax.get_legend_handles_labels()
    lines2 = ax2.get_legend_handles_labels()
    ax.legend(lines[0] + lines2[0], lines[1] + lines2[1], fontsize=8, loc="upper left")
    figs["torque_force"] = fig
    fig, ax = _fig("Cam profile", "x (mm)", "y (mm)")
    ax.plot(a["profile_x_mm"], a["profile_y_mm"], label="working segment")
    ax.plot(a["nonworking_x_mm"], a["nonworking_y_mm"], ":", label="non-working arc")
    ax.plot([0], [0], "k+", markersize=12, label="rotation centre O")
    ax.set_aspect("equal", adjustable="datalim")
    ax.legend()
    figs["profile"] = fig
    fig, ax = _fig("Lift and pressure angle", "cam rotation angle phi (rad)", "lift (mm)")
    ax.plot(a["rotation_rad"], a["lift_mm"], label="lift")
    ax2 = ax.twinx()
    ax2.plot(a["rotation_rad"], a["pressure_angle_deg"], color="tab:orange",
             label="pressure angle")
    ax2.set_ylabel("pressure angle (deg)")
    figs["lift"] = fig
    return figs


def _opening_spring(run: dict[str, Any]) -> dict[str, Figure]:
    a, paper = run["extra"]["analysis"], paper_values()["opening_spring"]
    fig, ax = _fig("Follower motion: desired (Eq 7) against simulated",
                   "follower angle theta (rad)", "angular velocity theta' (rad/s)")
    ax.plot(a["desired_theta_rad"], a["desired_rate_rad_s"], "k-", linewidth=2,
            label="desired (Eq 7)")
    labels = [k.removesuffix("_theta_rad") for k in a
              if k.endswith("_theta_rad") and not k.startswith("desired")]
    for label, style in zip(labels, ("--", ":", "-.", (0, (3, 1, 1, 1)), (0, (5, 2)))):
        name = "this design" if label == "design" else label.replace("_", " ")
        ax.plot(a[f"{label}_theta_rad"], a[f"{label}_rate_rad_s"], linestyle=style, label=name)
    ax.plot([paper["theta_rad"][0]], [paper["thetadot_t0_rad_s"]], "o", color="crimson",
            label="Eq 6: theta(t0), theta'(t0)")
    for i, th in enumerate(paper["theta_rad"][1:]):
        ax.axvline(th, label="Eq 6: theta(tk), theta(ts)" if i == 0 else None, **PAPER_STYLE)
    ax.legend()
    fig2, ax2 = _fig("Follower angle against time", "time (ms)", "follower angle theta (rad)")
    ax2.plot(a["desired_time_ms"], a["desired_theta_rad"], "k-", label="desired (Eq 7)")
    for label in labels:
        name = "this design" if label == "design" else label.replace("_", " ")
        ax2.plot(a[f"{label}_time_ms"], a[f"{label}_theta_rad"], "--", label=name)
    ax2.legend()
    return {"theta_thetadot": fig, "theta_time": fig2}


def _fast_switch(run: dict[str, Any]) -> dict[str, Figure]:
    paper = paper_values()["fast_switch"]
    figs = {}
    rows = run["table"]
    if rows and "coils" in rows[0]:
        fig, ax = _fig("Closure time against coils (the 1-DOF family)", "number of coils",
                       "closure time (ms)")
        coils = np.array([r["coils"] for r in rows])
        tf = np.array([r["closure_time_ms"] for r in rows])
        ok = np.array([r["feasible"] for r in rows])
        ax.plot(coils[ok], tf[ok], "o-", label="camopt, feasible")
        ax.plot(coils[~ok], tf[~ok], "x", color="gray", label="camopt, infeasible (R2)")
        ax.plot(paper["table1_coils"], paper["table1_closure_time_ms"], "s", mfc="none",
                color="crimson", label="paper, Table 1")
        ax.legend()
        figs["closure_time"] = fig
    a = run["extra"]["analysis"]
    if "time_ms" in a:
        fig, ax = _fig("Exact closing motion (Eqs 2-3)", "time (ms)", "crank angle theta2 (deg)")
        ax.plot(a["time_ms"], a["theta2_deg"])
        ax.axhline(90, color="gray", linestyle=":")
        figs["motion"] = fig
    return figs


CASE_FIGURES: dict[str, Callable[[dict[str, Any]], dict[str, Figure]]] = {
    "vcb": _vcb, "emb_cam": _emb, "opening_spring": _opening_spring,
    "fast_switch": _fast_switch,
}


def run_figures(run: dict[str, Any]) -> dict[str, Figure]:
    """Convergence and the case's figures for one run archive (from ``load_run``)."""
    hist = [np.asarray(h["best_objective"]) for h in run["extra"]["histories"]]
    figs = {"convergence": convergence({"repeats": hist}, run["extra"]["objective_name"])}
    kind = run["case"]["kind"]
    if kind in CASE_FIGURES and run["extra"]["analysis"] or kind == "fast_switch":
        figs.update(CASE_FIGURES[kind](run))
    return figs


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
        plt.close(fig)
        paths.append(path)
    return paths
