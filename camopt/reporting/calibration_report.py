"""The report of a calibration on measured curves (``camopt calibrate``): JSON for scripts
and the text report, from any case's :class:`~camopt.core.calibration.Calibrated` (its
model forms' fits, its verdict and its own words on its curves and predictions); the
case fragment and the fitted curves are the case's, passed through.

The rules the report states are :mod:`camopt.core.fitting`'s: which forms are kept,
which explain the curves, and how the intervals were found.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from camopt.core.calibration import Calibrated, FittedCurve, ModelFit, Verdict
from camopt.core.fitting import EXPLAINS_RULE, IDENTIFIED_WITHIN, INTERVALS, KEEP_RULE, LINEARISED


@dataclass(frozen=True)
class CalibrationReportView:
    """A case's calibration as JSON, text lines, fragment and fitted curves
    (:class:`camopt.core.calibration.CalibrationReport`)."""

    calibrated: Calibrated

    @property
    def verdict(self) -> Verdict:
        """Whether a form explains the curves (the case's verdict)."""
        return self.calibrated.verdict()

    def to_json(self) -> dict[str, object]:
        """Plain data: the verdict, the case's entries, the rules and every form's fit (its
        parameters with intervals, residual test and the case's entries)."""
        unit, size = self.calibrated.unit
        forms = []
        for f in self.calibrated.fits:
            names = [p.name for p in f.parameters]
            t = f.residuals
            forms.append({
                "form": f.form, "description": f.description, f"rms_{unit}": f.rms / size,
                "kept": f.kept, "kept_note": f.kept_note, "explains": f.explains,
                f"noise_{unit}": None if t is None else t.noise / size,
                "rms_ratio": None if t is None else t.rms_ratio,
                "durbin_watson": None if t is None else t.durbin_watson,
                "structure_z": None if t is None else t.structure_z,
                "intervals": INTERVALS if f.intervals == "profile" else LINEARISED,
                "parameters": [{"name": p.name, "unit": p.unit, "value": p.value,
                                "low": p.low, "high": p.high, "identified": p.identified,
                                "at_bound": p.at_bound}
                               for p in f.parameters],
                "correlation": {"names": names, "matrix": np.round(f.correlation, 4).tolist()},
                **self.calibrated.details(f)[0],
            })
        v = self.verdict
        return {"verdict": "explained" if v.explained else "not explained",
                "verdict_line": v.headline, "explained_by": list(v.forms),
                "warnings": list(v.warnings), **self.calibrated.head()[0],
                "keep_rule": KEEP_RULE, "explains_rule": EXPLAINS_RULE,
                "kept_forms": [f.form for f in self.calibrated.fits if f.kept],
                "forms": forms}

    def lines(self) -> list[str]:
        """The text report: the verdict first and last, the forms' table, then each form's
        parameters, strongest correlations and the case's lines."""
        unit, size = self.calibrated.unit
        v = self.verdict
        fits = self.calibrated.fits
        out = [v.headline] + [f"warning: {w}" for w in v.warnings] + [
            "", f"{self.calibrated.head()[1]}; intervals: {INTERVALS}", "",
            f"{'model form':<32}{'RMS ' + unit:>10}{'x noise':>9}{'D-W':>7}  kept  explains",
        ]
        for f in fits:
            t = f.residuals
            ratio = "" if t is None else f"{f.rms / t.noise:>9.2f}{t.durbin_watson:>7.2f}"
            out.append(f"{f.form:<32}{f.rms / size:>10.4f}{ratio}  "
                       f"{'yes ' if f.kept else 'no  '}  {'yes' if f.explains else 'no'}")
        out += [f"({KEEP_RULE}; {EXPLAINS_RULE})"]
        fitted = self.calibrated.curves()
        for f in fits:
            n_curves = sum(c.form == f.form for c in fitted)
            out += ["", f"form {f.form}: {f.description}",
                    f"  RMS misfit {f.rms / size:.4f} {unit} over {n_curves} curve(s); "
                    f"{'kept' if f.kept else (f.kept_note or 'NOT kept')}"
                    + ("" if f.intervals == "profile" else f"; intervals {LINEARISED}"),
                    f"  {'parameter':<22}{'value':>12}{'low':>12}{'high':>12}  identified"]
            for p in f.parameters:
                out.append(f"  {p.name:<22}{p.value:>12.5g}{p.low:>12.5g}{p.high:>12.5g}  "
                           f"{identified_cell(p.identified, f.kept)}"
                           + ("  AT SEARCH BOUND" if p.at_bound else ""))
            out.append("  strongest correlations: " + correlations(f))
            out += self.calibrated.details(f)[1]
        return out + ["", v.headline]

    def fragment(self, extends: str) -> str:
        """The case's TOML fragment with the calibrated values."""
        return self.calibrated.fragment(extends)

    def curves(self) -> tuple[FittedCurve, ...]:
        """Every form's fit of every curve."""
        return self.calibrated.curves()


def correlations(f: ModelFit, count: int = 3) -> str:
    """The ``count`` strongest correlations between a form's parameters, strongest first."""
    names = [p.name for p in f.parameters]
    k = len(names)
    pairs = sorted(((abs(f.correlation[i, j]), names[i], names[j], f.correlation[i, j])
                    for i in range(k) for j in range(i + 1, k)), reverse=True)[:count]
    return "; ".join(f"{a} / {b} {c:+.3f}" for _, a, b, c in pairs)


def identified_cell(identified: bool, kept: bool) -> str:
    """The report's "identified" cell: a form not kept identifies nothing."""
    if not kept:
        return "- (form not kept)"
    return "yes" if identified else f"NO (not to +-{100 * IDENTIFIED_WITHIN:g} %)"
