"""Figures of a VCB calibration: per model form, the measured and fitted travel of every
curve against time from the command (top) and the residuals, fitted less measured
(bottom), in mm and ms."""

from __future__ import annotations

from matplotlib.figure import Figure

from camopt.cases.vcb.calibrate import FormFit
from camopt.core.plotting import plt
from camopt.units import MM, MS


def figures(fits: tuple[FormFit, ...]) -> dict[str, Figure]:
    """``fit-<form>``: one figure per form."""
    out = {}
    for f in fits:
        fig, (top, bottom) = plt.subplots(2, 1, figsize=(7, 6), sharex=True,
                                          layout="constrained",
                                          gridspec_kw={"height_ratios": (2, 1)})
        top.set_title(f"{f.form}: RMS misfit {f.rms / MM:.4f} mm")
        for c in f.curves:
            t = c.time / MS
            line, = top.plot(t, c.measured / MM, ".", markersize=2,
                             label=f"measured, {c.design}")
            top.plot(t, c.fitted / MM, "-", color=line.get_color(), linewidth=1.2,
                     label=f"fitted, {c.design}")
            bottom.plot(t, (c.fitted - c.measured) / MM, ".", markersize=2,
                        color=line.get_color(), label=c.design)
        top.set_ylabel("travel (mm)")
        bottom.set_ylabel("fitted - measured (mm)")
        bottom.set_xlabel("time from the close command (ms)")
        for ax in (top, bottom):
            ax.grid(alpha=0.3)
        top.legend(fontsize="small")
        out[f"fit-{f.form}"] = fig
    return out
