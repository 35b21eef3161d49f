"""``camopt calibrate`` for the VCB case: the request read into curves and designs, the
calibration run (:mod:`camopt.cases.vcb.calibrate`) and the case's parts of its report
(:class:`~camopt.core.calibration.Calibrated`: what its curves read and its designs are
predicted to do, and the case fragment ``--out`` writes);
:mod:`camopt.reporting.calibration_report` makes the report of it.

Per-curve settings (``--set KEY=VALUE`` after a ``--curve``) name the curve's design where
it is not the case's reference design: ``kc1_n_per_mm``, ``kc2_n_per_mm`` (the closing
springs), ``a1``, ``a2``, ``a3`` (the follower law's coefficients; a0 stays the case's
Eq 8 value) or ``cam_points`` (a points file of the cam: :mod:`camopt.cases.vcb.cam_points`),
and ``latch_delay_ms`` (measured: the delay is then not fitted for this
curve) and ``label``. A design to predict (``--predict``) takes the same keys, joined by
commas.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any, TypedDict

import numpy as np

from camopt.cases.vcb.calibrate import CurveCase, FormFit, calibrate
from camopt.cases.vcb.calibration_model import Design
from camopt.cases.vcb.calibration_verdict import verdict
from camopt.cases.vcb.cam_points import read_cam_points
from camopt.cases.vcb.config import VcbConfig
from camopt.cases.vcb.curves import (
    MAX_DURATION_S,
    AnalyserQuantities,
    VelocityPoints,
    check_scale,
    read_curve,
)
from camopt.cases.vcb.forms import BAND_COLUMNS, CURVE_FORM_NAMES, CURVE_FORMS, get_form
from camopt.cases.vcb.model import VcbModel
from camopt.config.models import CaseConfig, toml_comment, toml_string
from camopt.core.calibration import CalibrationRequest, FittedCurve, ModelFit, Verdict
from camopt.core.fitting import INTERVALS, KEEP_RULE
from camopt.errors import ConfigError
from camopt.units import DEG, MM, MS, N_PER_MM

DESIGN_KEYS = ("kc1_n_per_mm", "kc2_n_per_mm", "a1", "a2", "a3", "cam_points", "label")
CURVE_KEYS = (*DESIGN_KEYS, "latch_delay_ms")
REFERENCE_LABEL = "reference"


def _settings(items: Sequence[str], keys: Sequence[str], where: str
              ) -> dict[str, str]:
    out: dict[str, str] = {}
    for item in items:
        key, sep, value = item.partition("=")
        key = key.strip()
        if not sep or not value.strip():
            raise ConfigError(where, item, "expected KEY=VALUE")
        if key not in keys:
            raise ConfigError(where, key, f"unknown; expected one of {', '.join(keys)}")
        out[key] = value.strip()
    return out


def _number(value: str, key: str, where: str, positive: bool = True) -> float:
    try:
        v = float(value)
    except ValueError:
        raise ConfigError(where, key, f"not a number: {value!r}") from None
    if not np.isfinite(v) or (positive and v <= 0):
        raise ConfigError(where, key, f"{value}: must be a finite positive number")
    return v


def _delay(value: str, where: str) -> float:
    """A measured latch delay (s) from ``latch_delay_ms``: 0 up to the longest curve
    (MAX_DURATION_S), since the release lies between the close command and the curve's
    end."""
    v = _number(value, "latch_delay_ms", where, positive=False)
    if not 0 <= v <= MAX_DURATION_S / MS:
        raise ConfigError(where, "latch_delay_ms", f"{value}: outside [0, "
                          f"{MAX_DURATION_S / MS:g}] ms (from the close command, within "
                          "the curve)")
    return v * MS


def design_of(config: VcbConfig, model: VcbModel, settings: dict[str, str], where: str
              ) -> Design:
    """The case's reference design with ``settings`` replacing its springs or follower
    law (SI rates)."""
    kc = np.array([config.kc1_n_per_mm, config.kc2_n_per_mm])
    a = model.vendor_a.copy()
    changed = []
    for i, key in enumerate(("kc1_n_per_mm", "kc2_n_per_mm")):
        if key in settings:
            kc[i] = _number(settings[key], key, where)
            changed.append(f"{key.split('_')[0]}={kc[i]:g}")
    if "cam_points" in settings:
        if any(k in settings for k in ("a1", "a2", "a3")):
            raise ConfigError(where, "cam_points", "give the cam as points or as a1..a3, "
                              "not both")
        a = read_cam_points(settings["cam_points"], model.theta_c[-1])
        changed.append(f"cam {Path(settings['cam_points']).name}")
    for i, key in enumerate(("a1", "a2", "a3"), start=1):
        if key in settings:
            a[i] = _number(settings[key], key, where, positive=False)
            changed.append(f"{key}={a[i]:g}")
    label = settings.get("label") or (" ".join(changed) if changed else REFERENCE_LABEL)
    return Design(label, a, kc * N_PER_MM)


def run(config: CaseConfig, request: CalibrationRequest) -> VcbCalibration:
    """Read the curves, calibrate every requested form, predict the designs."""
    assert isinstance(config, VcbConfig)
    if not request.curves:
        raise ConfigError("--curve", "--curve", "give at least one curve file")
    unknown = [f for f in request.forms if f not in CURVE_FORM_NAMES]
    if unknown:
        raise ConfigError("--form", unknown[0], f"unknown model form; known: "
                          f"{', '.join(CURVE_FORM_NAMES)}")
    model = VcbModel(config)
    points = None
    if request.velocity_points_mm is not None:
        low, high = request.velocity_points_mm
        if not 0 < low < high:
            raise ConfigError("--velocity-points", f"{low:g},{high:g}",
                              "need 0 < low < high (travel in mm)")
        points = VelocityPoints(low * MM, high * MM)
    used = points or VelocityPoints.last_third(config.contact_gap_mm * MM)
    curves = []
    for c in request.curves:
        where = str(c.path)
        settings = _settings(c.settings, CURVE_KEYS, where)
        delay = settings.pop("latch_delay_ms", None)
        curve, design = read_curve(c.path), design_of(config, model, settings, where)
        check_scale(curve, stroke(model, design), used)
        curves.append(CurveCase(curve, design, None if delay is None
                                else _delay(delay, where)))
    designs = [design_of(config, model, {}, "case")] + [c.design for c in curves] + [
        design_of(config, model, _settings(p.split(","), DESIGN_KEYS, "--predict"),
                  "--predict") for p in request.predict]
    unique: dict[str, Design] = {}
    for d in designs:
        unique.setdefault(d.label, d)
    forms = [get_form(f) for f in dict.fromkeys(request.forms)] or list(CURVE_FORMS)
    fits = calibrate(config, curves, forms, list(unique.values()), points)
    return VcbCalibration(fits, used, config)


def stroke(model: VcbModel, design: Design) -> float:
    """The rod's stroke (m) of a design: its travel at the cam's last angle, the case's
    linkage."""
    kin = model.kinematics(design.a[None, :], model.vendor_link[None, :],
                           model.c.rod_arm_offset_deg * DEG)
    return float(kin.s1[0, -1])


class QuantitiesDoc(TypedDict):
    """The analyser's quantities of one curve (measured or fitted), engineers' units."""

    closing_time_ms: float | None
    contact_velocity_m_s: float | None
    total_travel_mm: float | None
    contact_wipe_mm: float | None
    over_travel_mm: float | None
    rebound_mm: float | None
    notes: list[str]


def _quantities(q: AnalyserQuantities) -> QuantitiesDoc:
    def mm(v: float | None) -> float | None:
        return None if v is None else v / MM
    return {"closing_time_ms": None if q.closing_time is None else q.closing_time / MS,
            "contact_velocity_m_s": q.contact_velocity, "total_travel_mm": mm(q.total_travel),
            "contact_wipe_mm": mm(q.contact_wipe), "over_travel_mm": mm(q.over_travel),
            "rebound_mm": mm(q.rebound), "notes": list(q.notes)}


@dataclass(frozen=True)
class VcbCalibration:
    """The fits of every form (:class:`~camopt.core.calibration.Calibrated`) and the case
    they calibrate: velocity calculation points, the config and the curves' own notes."""

    fits: tuple[FormFit, ...]
    points: VelocityPoints
    config: VcbConfig
    notes: tuple[str, ...] = ()
    unit: tuple[str, float] = ("mm", MM)

    def verdict(self) -> Verdict:
        """Whether a form explains the curves
        (:func:`~camopt.cases.vcb.calibration_verdict.verdict`), with the curves' own
        warnings (``notes``) among its warnings."""
        v = verdict(self.fits, self.config.contact_gap_mm * MM)
        return Verdict(v.explained, v.forms, v.headline, (*self.notes, *v.warnings))

    def head(self) -> tuple[dict[str, Any], str]:
        """The contact velocity's calculation points (mm of travel)."""
        return ({"velocity_points_mm": [self.points.low / MM, self.points.high / MM]},
                f"contact velocity between {self.points.low / MM:.3g} and "
                f"{self.points.high / MM:.3g} mm of travel")

    def details(self, fit: ModelFit) -> tuple[dict[str, Any], list[str]]:
        """A form's curves (the analyser's quantities measured and fitted) and predictions
        (closing velocity, touch time, closing time from the command)."""
        assert isinstance(fit, FormFit)
        f = fit
        delay = _delay_ms(f)
        data = {
            "curves": [{"file": c.source, "design": c.design,
                        "latch_delay_ms": c.latch_delay / MS, "rms_mm": c.rms / MM,
                        "residual_max_mm": float(np.max(np.abs(c.fitted - c.measured)))
                        / MM, "samples": len(c.time),
                        "measured": _quantities(c.measured_quantities),
                        "fitted": _quantities(c.fitted_quantities)} for c in f.curves],
            "predictions": [{"design": p.design,
                             "closing_velocity_m_s": {"value": p.closing_velocity,
                                                      "low": p.closing_velocity_low,
                                                      "high": p.closing_velocity_high},
                             "touch_time_from_release_ms": {
                                 "value": p.touch_time / MS, "low": p.touch_time_low / MS,
                                 "high": p.touch_time_high / MS},
                             "closing_time_ms": None if delay is None else {
                                 "value": delay + p.touch_time / MS,
                                 "low": delay + p.touch_time_low / MS,
                                 "high": delay + p.touch_time_high / MS}}
                            for p in f.predictions]}
        out = []
        for c in f.curves:
            out.append(f"  curve {c.source} ({c.design}): RMS {c.rms / MM:.4f} mm, largest "
                       f"residual {np.max(np.abs(c.fitted - c.measured)) / MM:.4f} mm, "
                       f"latch delay {c.latch_delay / MS:.3f} ms")
            out += _side_by_side(c.measured_quantities, c.fitted_quantities)
        zero = 0.0 if delay is None else delay
        which = ("touch from the release" if delay is None else
                 f"closing time: command to touch, latch delay {delay:.3f} ms")
        out.append(f"  {'prediction':<22}{'v_close m/s':>12}{'low':>8}{'high':>8}"
                   f"{'closing ms' if delay is not None else 't_touch ms':>12}{'low':>8}"
                   f"{'high':>8}  ({which})")
        for d in f.predictions:
            out.append(f"  {d.design:<22}{d.closing_velocity:>12.4f}"
                       f"{d.closing_velocity_low:>8.4f}{d.closing_velocity_high:>8.4f}"
                       f"{zero + d.touch_time / MS:>12.3f}"
                       f"{zero + d.touch_time_low / MS:>8.3f}"
                       f"{zero + d.touch_time_high / MS:>8.3f}")
        return data, out

    def curves(self) -> tuple[FittedCurve, ...]:
        """Every form's fit of every curve."""
        return tuple(FittedCurve(f.form, c.source, c.design, c.time, c.measured, c.fitted)
                     for f in self.fits for c in f.curves)

    def fragment(self, extends: str) -> str:
        """TOML text extending the case with the kept form of least misfit's values."""
        kept = [f for f in self.fits if f.kept] or list(self.fits)
        best = min(kept, key=lambda f: f.rms)
        form = get_form(best.form)
        v = self.verdict()
        first = ([] if v.explained else [
            "# NOT EXPLAINED: no model form fits these curves to their noise; the values "
            "below are the best form's all the same (written with --allow-unexplained)",
            "# " + toml_comment(v.headline.replace("\n", " "))])
        lines = first + [f"# camopt calibrate: form {best.form} ({best.description}),",
                 f"# RMS misfit {best.rms / MM:.4f} mm on "
                 + ", ".join(toml_comment(c.source) for c in best.curves) + ".",
                 f"# intervals: {INTERVALS}.",
                 f"# kept forms ({KEEP_RULE}): " + ", ".join(f.form for f in kept) + ".",
                 f"extends = {toml_string(extends)}", "", "[case]"]
        for p in best.parameters:
            mark = "" if p.identified else "  NOT identified by the curves"
            if p.name in VcbConfig.model_fields:
                lines.append(f"{p.name} = {p.value:.6g}    # 95 %: {p.low:.4g} .. "
                             f"{p.high:.4g} {p.unit}{mark}")
            else:
                lines.append(f"# {p.name} = {p.value:.6g} (95 %: {p.low:.4g} .. "
                             f"{p.high:.4g} {p.unit}; not a case field){mark}")
        delay = _delay_ms(best)
        if delay is not None and "latch_delay_ms" not in {p.name for p in best.parameters}:
            lines.append(f"latch_delay_ms = {delay:.6g}    # measured (--set latch_delay_ms)")
        # what the form fixes rather than fits, where it differs from the case's
        if form.efficiency == "none":
            lines.append("efficiency = 1.0    # the form has no efficiency (Coulomb alone)")
        if form.friction == "none":
            lines.append("cam_friction_nm = 0.0    # the form has no friction torque")
        if form.friction == "driven":
            lines.append("# the form has no friction in the free rotation from the release: "
                         "only the dynamics_band rows (release_friction_nm = 0) carry that")
        others = [f.form for f in kept if get_form(f.form).extra != form.extra]
        if others:
            lines.append("# not in the band (other physics than the chosen form's; a case "
                         "has one spring mass and damping): " + ", ".join(others))
        if form.extra != "none":
            lines.append(f"# every band row takes the {form.extra.replace('_', ' ')} above "
                         "(its spread is not in the rows)")
        lines.append("# parameter sets inside the intervals (profiles' extremes), every kept "
                     "form, the chosen form's fit first:")
        lines.append("# (" + ", ".join(BAND_COLUMNS) + ")")
        lines.append("dynamics_band = [")
        rows = _band_rows(best, kept, self.config)
        lines += [f"  [{', '.join(f'{v:.6g}' for v in r)}]," for r in rows]
        lines.append("]")
        return "\n".join(lines) + "\n"




def _delay_ms(fit: FormFit) -> float | None:
    """The latch delay (ms) of a fit's predictions: the curves' (fitted, shared, or
    measured), None where measured delays differ between curves."""
    delays = {round(c.latch_delay / MS, 9) for c in fit.curves}
    return delays.pop() if len(delays) == 1 else None


def _band_rows(best: FormFit, kept: Sequence[FormFit], config: VcbConfig
               ) -> list[list[float]]:
    """``dynamics_band`` rows (:data:`~camopt.cases.vcb.forms.BAND_COLUMNS`) of every kept
    form with the chosen form's physics (``best``'s ``extra``: one case carries one spring
    mass and one rod damping for every row): each form's fit and its band's extremes per
    parameter, the chosen form first, at most 64 (the case's limit)."""
    rows: list[list[float]] = []
    extra = get_form(best.form).extra
    for fit in [best] + [f for f in kept if f is not best and get_form(f.form).extra == extra]:
        band = fit.band
        pick = np.unique(np.r_[0, np.argmin(band, axis=0), np.argmax(band, axis=0)])
        rows += get_form(fit.form).band_rows(band[pick], config).tolist()
    return rows[:64]


def _side_by_side(m: AnalyserQuantities, s: AnalyserQuantities) -> list[str]:
    a, b = _quantities(m), _quantities(s)
    out = [f"    {'analyser quantity':<24}{'measured':>12}{'model':>12}"]
    for key in ("closing_time_ms", "contact_velocity_m_s", "total_travel_mm",
                "contact_wipe_mm", "over_travel_mm", "rebound_mm"):
        out.append(f"    {key:<24}{_cell(a[key]):>12}{_cell(b[key]):>12}")
    out += [f"    note (model): {n}" for n in s.notes]
    out += [f"    note (measured): {n}" for n in m.notes]
    return out


def _cell(v: float | None) -> str:
    return "n/a" if v is None else f"{v:.4g}"
