"""The verdict on a VCB calibration: explained by the forms whose residuals are the
curves' noise (:meth:`camopt.core.fitting.ResidualTest.passes`), else NOT EXPLAINED with
where along the closing the best form misfits and what a rigid model with Coulomb losses
likely lacks there; and the warnings a designer needs beside it."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from camopt.cases.vcb.calibrate import FormFit
from camopt.core.calibration import Verdict
from camopt.units import MM


def missing_physics(fit: FormFit, gap: float) -> str:
    """Where a form's misfit lies along the closing and what typically shows there: the
    residuals' excess over the noise (sum of squares less N sigma^2) before the motion,
    in the stroke to the touch and from the touch on. A reading, not a fit: a smooth
    misfit of the moving part fits several missing effects alike (a distributed mass and
    a dashpot both leave an S-shaped residual across the touch), so it names them all."""
    parts = {"before the motion": 0.0, "in the stroke to the touch": 0.0,
             "from the touch to the latch": 0.0}
    for c in fit.curves:
        r = c.fitted - c.measured
        moving = c.measured > 0.05 * np.max(c.measured)
        first = int(np.argmax(moving)) if moving.any() else len(r)
        touched = c.measured >= gap
        t_touch = int(np.argmax(touched)) if touched.any() else len(r)
        for name, z in zip(parts, (slice(0, first), slice(first, t_touch),
                                   slice(t_touch, len(r)))):
            seg = r[z]
            parts[name] += max(float(np.sum(seg * seg)) - seg.size * c.noise**2, 0.0)
    where = max(parts, key=lambda k: parts[k])
    if where == "before the motion":
        return ("the misfit is largest before the motion: a latch delay that differs "
                "between the curves (give each its measured latch_delay_ms), a release "
                "that is not instantaneous, or a transducer offset")
    return (f"the misfit is largest {where}: likely missing from the rigid model with "
            "Coulomb losses: the closing springs' own mass (inertia along the stroke), "
            "viscous damping (a dashpot or buffer on the rod), the contacts' compliance")


PREDICTION_SPREAD = 0.02
"""Forms that explain the curves but predict a design's closing velocity further apart
than this (relative) are told apart by no curve: a warning says so."""


def verdict(fits: Sequence[FormFit], gap: float) -> Verdict:
    """The verdict on fitted forms (:func:`calibrate`'s) of curves whose contact gap is
    ``gap`` (m): explained by the forms that explain them (:attr:`FormFit.explains`),
    else NOT EXPLAINED with the best form's residual test and where its misfit lies
    (:func:`missing_physics`)."""
    good = [f for f in fits if f.explains]
    warn: list[str] = []
    for f in fits:
        if not f.kept:
            continue
        for p in f.parameters:
            if p.at_bound:
                warn.append(f"form {f.form}: {p.name} = {p.value:.4g} {p.unit} is at its "
                            "search bound: the curves do not measure it (the form may "
                            "stand in for physics it lacks)")
    if good:
        by_design: dict[str, list[float]] = {}
        for f in good:
            for pr in f.predictions:
                by_design.setdefault(pr.design, []).append(pr.closing_velocity)
        for design, v in by_design.items():
            lo, hi = float(np.nanmin(v)), float(np.nanmax(v))
            if len(v) > 1 and hi - lo > PREDICTION_SPREAD * abs(hi):
                warn.append(f"design {design}: the forms that explain the curves predict a "
                            f"closing velocity of {lo:.3f} to {hi:.3f} m/s: the curves do "
                            "not tell them apart (a curve with other springs does)")
        coarse: dict[str, list[float]] = {}
        for f in good:
            for c in f.curves:
                q = c.measured_quantities
                if q.contact_velocity is not None and any("resampled" in n for n in q.notes):
                    coarse.setdefault(c.source, []).append(q.contact_velocity)
        for source, v in coarse.items():
            lo, hi = min(v), max(v)
            warn.append(f"curve {source} is sampled too coarsely for its contact velocity: "
                        "read from the fit"
                        + (f", {lo:.3f} to {hi:.3f} m/s over the forms that explain it"
                           if hi - lo > PREDICTION_SPREAD * hi else ""))
        names = ", ".join(f.form for f in good)
        head = (f"verdict: explained by form{'s' if len(good) > 1 else ''} {names} "
                "(residuals at the curves' noise, without structure)")
        return Verdict(True, tuple(f.form for f in good), head, tuple(warn))
    best = min(fits, key=lambda f: f.rms)
    t = best.residuals
    detail = "" if t is None else (
        f"best form {best.form}: residual RMS {best.rms / t.noise:.2f} x the noise "
        f"({t.noise / MM:.4f} mm), Durbin-Watson {t.durbin_watson:.2f} "
        f"({t.structure_z:.1f} standard errors below 2)")
    head = (f"verdict: NOT EXPLAINED: no model form fits the curves to their noise; {detail}; "
            f"{missing_physics(best, gap)}")
    return Verdict(False, (), head, tuple(warn))
