"""Figures of runs and sweeps: convergence, plus each case's own figures (its spec's
``figures``). Every function returns ``{name: Figure}`` so tests can read axes and
labels; :func:`save` writes them as PNGs.

The archive readers, pydantic and the driver are imported where a plot is made."""

from __future__ import annotations

import io
import string
from pathlib import Path
from typing import Any

import numpy as np
from matplotlib.figure import Figure

from camopt.cases import get_case
from camopt.core import pareto
from camopt.core.plotting import PAPER_STYLE, close, figure, new_figure, readable, wrapped
from camopt.core.runview import RunView
from camopt.errors import CamoptError, ConfigError
from camopt.mechanics.cam_outline import CamOutline
from camopt.units import MM, TO_DEG


def _band(histories: list[np.ndarray]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Median and inter-quartile band of best-so-far curves (shorter ones hold their end);
    NaN where no curve is finite yet (no feasible design in any repeat so far: numpy would
    warn 'All-NaN slice' for those iterations)."""
    n = max(len(h) for h in histories)
    stack = np.array([np.r_[h, np.full(n - len(h), h[-1])] for h in histories], dtype=float)
    finite = np.isfinite(stack)
    band = np.full((3, n), np.nan)
    some = finite.any(axis=0)
    if some.any():
        band[:, some] = np.nanpercentile(np.where(finite, stack, np.nan)[:, some],
                                         (50, 25, 75), axis=0)
    return band[0], band[1], band[2]


SPREAD = 20.0
"""Positive values spanning more than this factor are drawn on a log axis."""


def _scale(ax: Any, values: np.ndarray) -> None:
    """Fit the y axis to what the data reach: a log axis from the least to the greatest
    positive value when they span more than :data:`SPREAD` (zeros, a violation reaching 0,
    fall below it and are not drawn), else the linear axis matplotlib fits. Never a
    symlog axis, whose linear band near 0 left half the height to decades never reached."""
    finite = values[np.isfinite(values)]
    positive = finite[finite > 0]
    if not positive.size or finite.min() < 0:
        return
    lo, hi = float(positive.min()), float(positive.max())
    if hi > SPREAD * lo:
        ax.set_yscale("log")
        ax.set_ylim(lo / 1.5, hi * 1.5)


def convergence(curves: dict[str, list[np.ndarray]], objective: str,
                target: float | None = None,
                evaluations: dict[str, list[np.ndarray]] | None = None,
                violations: dict[str, list[np.ndarray]] | None = None) -> Figure:
    """Median and inter-quartile band of the best objective, against iterations or, given
    ``evaluations`` (the ``nfev`` histories, one per curve), against function evaluations
    (so grid points of different population sizes compare fairly). ``target`` is drawn
    as a line. When no curve has a finite objective (no feasible design was found) the best
    constraint violation is drawn instead (``violations``), never an empty axes."""
    finite = any(np.isfinite(np.asarray(h, dtype=float)).any()
                 for hist in curves.values() for h in hist)
    if not finite and violations:
        curves, what = violations, "best constraint violation (no feasible design found)"
        ylabel, target = "best constraint violation", None
    else:
        what, ylabel = "best objective", f"best {readable(objective)}"
    xlabel = "function evaluations" if evaluations else "iteration (generation)"
    fig, ax = new_figure(f"Convergence: {what}\n(median and inter-quartile band over runs)",
                         xlabel, ylabel)
    allv = []
    for label, hist in curves.items():
        med, lo, hi = _band(hist)
        x = np.arange(1, med.size + 1, dtype=float)
        if evaluations and evaluations.get(label):
            x = _band([np.asarray(e, dtype=float) for e in evaluations[label]])[0][:med.size]
        # a one-pass solver (enumeration) has one point per run: a marker, not a line
        ax.plot(x, med, marker="o" if med.size <= 2 else None,
                label=f"{label} (n = {len(hist)})")
        ax.fill_between(x, lo, hi, alpha=0.25)
        if med.size == 1:
            ax.set_xlim(x[0] - 0.5, x[0] + 0.5)
            ax.set_xticks([x[0]])
        allv.append(med)
    if target is not None and np.isfinite(target):
        ax.axhline(target, color="black", linestyle=":", linewidth=1.2,
                   label=f"target {target:.6g}")
        allv.append(np.array([float(target)]))
    values = np.concatenate(allv) if allv else np.array([])
    if not np.isfinite(values).any():
        ax.text(0.5, 0.5, "no finite value to draw", transform=ax.transAxes, ha="center")
    _scale(ax, values)
    ax.legend()
    return fig


def run_figures(run: RunView) -> dict[str, Figure]:
    """Convergence and the case's figures for one run archive."""
    figs = {"convergence": convergence(
        {"repeats": run.histories()}, run.objective_name, run.run.get("target"),
        violations={"repeats": run.histories("best_violation")})}
    if len(pareto.objectives(run)[0]) >= 2:
        figs["pareto"] = pareto_front(run)
    spec = get_case(run.kind)
    figs.update(spec.draw(run))
    outline = spec.cam_outline(run) if spec.outline is not None else None
    if outline is not None:
        figs["motion"] = motion_diagram(outline)
    return figs


def motion_diagram(outline: CamOutline) -> Figure:
    """The follower's S-V-A-J diagram over the cam's full turn: displacement (deg),
    velocity, acceleration and jerk (derivatives per cam angle, rad/rad, 1/rad, 1/rad^2)
    against cam angle, the actuated stroke shaded and each segment named. Jerk is the
    acceleration's numerical derivative (the C2 outline's jerk steps at the joints)."""
    theta = outline.theta * TO_DEG
    with np.errstate(all="ignore"):
        jerk = np.gradient(outline.ddphi, outline.theta)
    fig = figure(figsize=(7, 8), layout="constrained")
    axes = fig.subplots(4, 1, sharex=True)
    fig.suptitle(wrapped("Follower motion over the full turn (S-V-A-J): the design's law "
                         "on the actuated stroke (shaded), closed by the outline"))
    rows = ((outline.phi * TO_DEG, "displacement\nphi (deg)"),
            (outline.dphi, "velocity\nd phi / d theta (rad/rad)"),
            (outline.ddphi, "acceleration\nd2 phi / d theta2 (1/rad)"),
            (jerk, "jerk\nd3 phi / d theta3 (1/rad2)"))
    for ax, (values, label) in zip(axes, rows):
        ax.plot(theta, values, color="tab:blue", label="follower")
        ax.set_ylabel(label, fontsize=8)
        ax.grid(alpha=0.3)
        for seg in outline.segments:
            if seg.name == "rise":
                ax.axvspan(seg.start * TO_DEG, seg.end * TO_DEG, color="tab:orange",
                           alpha=0.12, label="actuated stroke")
            else:
                ax.axvline(seg.start * TO_DEG, color="grey", lw=0.5, ls=":")
    for seg in outline.segments:  # names along the top, at each segment's middle
        narrow = (seg.end - seg.start) * TO_DEG < 25  # inside the axes, upright
        axes[0].annotate(seg.name, ((seg.start + seg.end) / 2 * TO_DEG,
                                    0.97 if narrow else 1.0),
                         xycoords=("data", "axes fraction"), ha="center",
                         va="top" if narrow else "bottom", rotation=90 if narrow else 0,
                         fontsize=7)
    axes[-1].set_xlabel("cam angle theta_c (deg; 0: start of the actuated stroke)")
    axes[0].legend(fontsize=7, loc="lower right")
    return fig


def pareto_front(run: RunView) -> Figure:
    """The Pareto set in its first two objectives, infeasible members hollow, with the
    reference design (:func:`camopt.reporting.report.reference`), the front's knee
    (:func:`camopt.core.pareto.summary`) and the headline design (the best by the run's
    scalar objective) marked; one whose value is unknown or unbounded is named in a note
    with the reason instead."""
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
    from camopt.reporting.report import reference

    ref = reference(run)  # one name everywhere: "reference: vendor, Sec 2.3 ..."
    label = ref.label
    notes = []
    marks: list[tuple[str, list[Any], dict[str, Any]]] = [
        (label, [ref.get(n) for n in (a, b)],
         {"marker": "*", "s": 160, "color": PAPER_STYLE["color"]})] if label else []
    doc = pareto.summary(run)
    knee = doc.get("knee") if doc else None
    if knee is None:
        notes.append("knee: none (no feasible design on the front)")
    else:
        marks.append(("knee", [knee.get(n) for n in (a, b)],
                      {"marker": "D", "s": 60, "facecolors": "none", "edgecolors": "black"}))
    marks.append((f"headline (best {run.objective_name})",
                  [run.best.metrics.get(n, run.best.objective if n == run.objective_name
                                        else None) for n in (a, b)],
                  {"marker": "X", "s": 90, "color": "tab:red"}))
    for name, point, style in marks:
        if all(isinstance(v, (int, float)) and np.isfinite(v) for v in point):
            ax.scatter([point[0]], [point[1]], label=name, zorder=3, **style)
        else:  # say why a marker is missing rather than leave the reader to wonder
            values = ", ".join(f"{readable(n)} {_value(v)}" for n, v in zip((a, b), point))
            notes.append(f"{name} not drawn: {values}")
    if notes:
        ax.text(0.01, 0.01, "\n".join(notes), transform=ax.transAxes, fontsize=7,
                va="bottom", ha="left", color="dimgrey")
    ax.legend(fontsize=8)
    return fig


def _value(v: Any) -> str:
    """A marker's coordinate in a note: the number, 'unbounded' or 'unknown'."""
    if isinstance(v, (int, float)):
        return "unbounded" if np.isinf(v) else "undefined (NaN)" if np.isnan(v) else f"{v:.4g}"
    return "unknown"


OUTLINE_CURVES = {"cam-profile": "profile", "cam-pitch-curve": "pitch"}
"""Profile curves drawn from a case's closed outline (its attribute) when it has one."""


def design_letters(labels: list[str]) -> list[str]:
    """``A: <label>``, ``B: <label>``, ...: the legend's names of overlaid designs (the
    titles say ``A vs B``; a run's name, often a timestamp, stays in the legend)."""
    letters = string.ascii_uppercase
    return [f"{letters[i % 26]}{'' if i < 26 else i // 26}: {label}"
            for i, label in enumerate(labels)]


def overlay_figures(runs: list[RunView], labels: list[str]) -> dict[str, Figure]:
    """Several runs of one case kind on the same axes: each cam profile (the case's
    ``profiles``, equal aspect, the cam pivot at the origin; the closed full-turn outline
    where the case has one) and each of the case's
    ``overlays`` (travel and velocity against time), one line per run named A, B, ... in
    the title and ``A: <label>`` in the legend (:func:`design_letters`); a curve some
    run's archive lacks is drawn for the others. Runs of different kinds are bad input
    (ConfigError)."""
    kinds = {r.kind for r in runs}
    if len(kinds) > 1:
        raise ConfigError(runs[1].path, "RUN", f"case '{runs[1].kind}' cannot be overlaid "
                          f"on case '{runs[0].kind}': give runs of one case kind")
    spec = get_case(runs[0].kind)
    labels = design_letters(labels)
    title = " vs ".join(n.split(":", 1)[0] for n in labels)
    figs: dict[str, Figure] = {}

    outlines = [spec.cam_outline(run) for run in runs]
    for curve in spec.profiles:
        which = OUTLINE_CURVES.get(curve.name)
        turn = ", full turn" if which and any(o is not None for o in outlines) else ""
        fig, ax = new_figure(f"{curve.name.replace('-', ' ').capitalize()}{turn}: {title}",
                             "x (mm)", "y (mm)")
        for run, label, outline in zip(runs, labels, outlines):
            a = run.analysis
            if outline is not None and which:  # the full turn the workshop cuts (dxf)
                points = getattr(outline, which)
                closed = np.vstack([points, points[:1]]) / MM
                ax.plot(closed[:, 0], closed[:, 1], label=f"{label} (full turn)")
            elif all(k in a for k in (*curve.x, *curve.y)):
                ax.plot(np.concatenate([a[k] for k in curve.x]),
                        np.concatenate([a[k] for k in curve.y]), label=label)
        ax.plot([0], [0], "k+", markersize=12, label="cam pivot")
        ax.set_aspect("equal", adjustable="datalim")
        ax.legend(fontsize=8, loc="upper center", bbox_to_anchor=(0.5, -0.14), ncol=2)
        figs[curve.name] = fig
    for o in spec.overlays:
        fig, ax = new_figure(f"{o.title}: {title}", o.xlabel, o.ylabel)
        for run, label in zip(runs, labels):
            a = run.analysis
            if o.x in a and o.y in a and np.size(a[o.x]) == np.size(a[o.y]):
                ax.plot(a[o.x], a[o.y], label=label)
        if not ax.lines:
            ax.text(0.5, 0.5, "no run holds this curve", transform=ax.transAxes,
                    ha="center")
        else:
            ax.legend(fontsize=8)
        figs[o.name] = fig
    return figs


def sweep_figures(spec: Any, results: dict) -> dict[str, Figure]:
    """Convergence against function evaluations, one line per grid point (grid points of
    different population sizes spend different evaluations per generation)."""
    curves: dict[str, list[np.ndarray]] = {}
    nfev: dict[str, list[np.ndarray]] = {}
    violations: dict[str, list[np.ndarray]] = {}
    for (point, _), r in sorted(results.items()):
        label = ", ".join(f"{k}={v}" for k, v in spec.points()[point].items()) or "base"
        curves.setdefault(label, []).append(np.asarray(r.history["best_objective"]))
        if "nfev" in r.history:
            nfev.setdefault(label, []).append(np.asarray(r.history["nfev"]))
        if "best_violation" in r.history:
            violations.setdefault(label, []).append(np.asarray(r.history["best_violation"]))
    by_evaluations = nfev if set(nfev) == set(curves) else None
    return {"convergence": convergence(curves, _objective_name(spec),
                                       spec.data["run"].get("target"), by_evaluations,
                                       violations or None)}


def _objective_name(spec: Any) -> str:
    """The objective's name (its unit in the name) of a sweep's case, from its config;
    plain 'objective' when the case cannot be built here (e.g. it names another archive)."""
    from pydantic import ValidationError

    from camopt.engine.setup import prepare, validate

    try:
        return str(prepare(validate(spec.data, spec.source))[0].objective_name)
    except (CamoptError, ValidationError, OSError):
        return "objective"


def save(figures: dict[str, Figure], out_dir: Path, stem: str, force: bool = False,
         inputs: tuple[Path, ...] = (), key: str = "--out") -> list[Path]:
    """Write each figure as ``<stem>-<name>.png`` and close them: rendered in memory, then
    written all or nothing (:func:`camopt.archive.files.write_files`: never over an
    existing file without ``force``, never through a link, never over one of ``inputs``)."""
    from camopt.archive.files import output_folder, write_files

    with output_folder(out_dir, key):  # a folder this made is removed again on failure
        files = {}
        try:
            for name, fig in figures.items():
                png = io.BytesIO()
                fig.savefig(png, dpi=110, format="png")
                files[out_dir / f"{stem}-{name}.png"] = png.getvalue()
        finally:
            for fig in figures.values():
                close(fig)
        return write_files(files, force, inputs)
