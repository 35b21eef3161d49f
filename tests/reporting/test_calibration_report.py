"""The calibration report (camopt/reporting/calibration_report.py) of a stand-in case's
calibration: the report knows no case, the case's unit names its columns and keys, its
own entries and lines sit where it puts them, and the verdict leads and ends."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from camopt.core.calibration import FittedCurve, ModelFit, Verdict
from camopt.core.fitting import ParameterEstimate, ResidualTest
from camopt.reporting.calibration_report import CalibrationReportView


@dataclass(frozen=True)
class _Fit:
    form: str = "linear"
    description: str = "a straight line"
    rms: float = 0.002
    parameters: tuple[ParameterEstimate, ...] = (
        ParameterEstimate("slope", "N/m", 2.0, 1.95, 2.05, True),
        ParameterEstimate("offset", "N", 0.5, 0.1, 0.9, False, True))
    correlation: Any = field(default_factory=lambda: np.array([[1.0, -0.8], [-0.8, 1.0]]))
    kept: bool = True
    kept_note: str = ""
    intervals: str = "profile"
    residuals: ResidualTest | None = field(
        default_factory=lambda: ResidualTest(0.002, 1.0, 2.0, 0.0, 10))
    explains: bool = True


class _Spring:
    fits: tuple[ModelFit, ...] = (_Fit(),)
    unit = ("g", 1e-3)

    def verdict(self) -> Verdict:
        return Verdict(True, ("linear",), "verdict: explained by form linear", ())

    def head(self) -> tuple[dict[str, Any], str]:
        return {"load_range_n": [0, 10]}, "loads from 0 to 10 N"

    def details(self, fit: ModelFit) -> tuple[dict[str, Any], list[str]]:
        return {"samples": 10}, ["  ten samples"]

    def fragment(self, extends: str) -> str:
        return f"extends = {extends!r}\n"

    def curves(self) -> tuple[FittedCurve, ...]:
        t = np.linspace(0, 1, 10)
        return (FittedCurve("linear", "a.csv", "ref", t, t, t),)


def test_the_report_of_another_case():
    report = CalibrationReportView(_Spring())
    data = report.to_json()
    assert data["verdict"] == "explained" and data["load_range_n"] == [0, 10]
    (form,) = data["forms"]
    assert form["rms_g"] == 2.0 and form["noise_g"] == 2.0 and form["samples"] == 10
    assert [p["at_bound"] for p in form["parameters"]] == [False, True]
    lines = report.lines()
    assert lines[0] == lines[-1] == "verdict: explained by form linear"
    assert lines[2].startswith("loads from 0 to 10 N; intervals: profile likelihood")
    assert "  RMS misfit 2.0000 g over 1 curve(s); kept" in lines
    assert any("NO (not to +-5 %)" in line and "AT SEARCH BOUND" in line for line in lines)
    assert "  strongest correlations: slope / offset -0.800" in lines
    assert lines[-3] == "  ten samples"
    assert report.fragment("case.toml") == "extends = 'case.toml'\n"
