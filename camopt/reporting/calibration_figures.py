"""Figures of a calibration on measured curves, live (``camopt calibrate --plot``) or from
its archive (``camopt plot``/``report``): per model form, every curve's measured and
fitted travel against the time from the close command (top) and the residuals, fitted
less measured (bottom), in mm and ms. Kind-free: plain
:class:`~camopt.core.calibration.FittedCurve` records."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

from matplotlib.figure import Figure

from camopt.core.calibration import FittedCurve
from camopt.core.plotting import figure
from camopt.units import MM, MS


def figures(curves: Sequence[FittedCurve], rms_mm: Mapping[str, float]
            ) -> dict[str, Figure]:
    """``fit-<form>``: one figure per form, in the order of ``curves``; ``rms_mm`` each
    form's RMS misfit (mm) for its title."""
    out: dict[str, Figure] = {}
    forms = list(dict.fromkeys(c.form for c in curves))
    for form in forms:
        fig = figure(figsize=(7, 6), layout="constrained")
        top, bottom = fig.subplots(2, 1, sharex=True, gridspec_kw={"height_ratios": (2, 1)})
        rms = rms_mm.get(form)
        top.set_title(form if rms is None else f"{form}: RMS misfit {rms:.4f} mm")
        for c in (c for c in curves if c.form == form):
            t = c.time_s / MS
            line, = top.plot(t, c.measured_m / MM, ".", markersize=2,
                             label=f"measured, {c.design}")
            top.plot(t, c.fitted_m / MM, "-", color=line.get_color(), linewidth=1.2,
                     label=f"fitted, {c.design}")
            bottom.plot(t, (c.fitted_m - c.measured_m) / MM, ".", markersize=2,
                        color=line.get_color(), label=c.design)
        top.set_ylabel("travel (mm)")
        bottom.set_ylabel("fitted - measured (mm)")
        bottom.set_xlabel("time from the close command (ms)")
        for ax in (top, bottom):
            ax.grid(alpha=0.3)
        top.legend(fontsize="small")
        out[f"fit-{form}"] = fig
    return out


def rms_of(summary: Mapping[str, Any]) -> dict[str, float]:
    """Each form's ``rms_mm`` from a calibration's JSON summary."""
    return {str(f["form"]): float(f["rms_mm"]) for f in summary.get("forms", [])}
