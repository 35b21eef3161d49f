"""What ``camopt calibrate`` hands a case and gets back: typed, kind-free.

A case that can be calibrated on measured curves names its function in
``CaseSpec.calibration`` (``"module:function"``, imported only when asked); the function
takes the validated ``[case]`` config and a :class:`CalibrationRequest` and returns a
:class:`Calibrated`: its model forms' fits (:class:`ModelFit`, the parameters and tests of
:mod:`camopt.core.fitting`), its verdict and the case's own words about them.
:mod:`camopt.reporting.calibration_report` makes the :class:`CalibrationReport` of it. The
command line knows no case kind (``docs/design.md``)."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Protocol

from camopt.core.fitting import ParameterEstimate, ResidualTest
from camopt.mechanics import Floats


@dataclass(frozen=True)
class CurveRequest:
    """One measured curve file and the ``KEY=VALUE`` settings given after it on the
    command line (its design, its latch delay), in order."""

    path: Path
    settings: tuple[str, ...] = ()


@dataclass(frozen=True)
class CalibrationRequest:
    """The curves, the further designs to predict (each ``KEY=VALUE[,KEY=VALUE]``), the
    contact velocity's two calculation points as travel in mm (None: the case's window)
    and the model forms to fit (empty: every form the case has)."""

    curves: tuple[CurveRequest, ...]
    predict: tuple[str, ...] = ()
    velocity_points_mm: tuple[float, float] | None = None
    forms: tuple[str, ...] = ()


@dataclass(frozen=True)
class FittedCurve:
    """One measured curve and a model form's fit to it, as plain data (what the archive
    stores and the figures draw): the ``form``, the curve file (``source``), its design's
    label, the samples' time from the close command (s) and the measured and fitted
    travel (m), each (m,)."""

    form: str
    source: str
    design: str
    time_s: Floats
    measured_m: Floats
    fitted_m: Floats


class CalibrationReport(Protocol):
    """A finished calibration: JSON-ready data, the lines of its human report, the case
    fragment with the calibrated values (``extends`` the case file) and the fitted
    curves. ``to_json()["forms"]`` lists each form with its ``form`` name and
    ``rms_mm`` (what the figures' titles and ``camopt report`` read)."""

    def to_json(self) -> dict[str, Any]:
        """Plain data (per form ``rms_mm``, parameters with ``value``/``low``/``high``,
        predictions with ``low``/``high``)."""

    def lines(self) -> list[str]:
        """The human report, line by line (plain text)."""

    def fragment(self, extends: str) -> str:
        """TOML text: ``extends = <extends>`` and a ``[case]`` of the calibrated values."""

    def curves(self) -> tuple[FittedCurve, ...]:
        """Every form's fit of every curve (the figures' and the archive's data)."""


@dataclass(frozen=True)
class Verdict:
    """Whether any model form explains the curves (``explained``, those ``forms``), the
    one-line ``headline`` a report leads and ends with, and ``warnings`` (parameters at a
    search bound, explaining forms whose predictions disagree, the curves' own notes)."""

    explained: bool
    forms: tuple[str, ...]
    headline: str
    warnings: tuple[str, ...]


class ModelFit(Protocol):
    """One model form's fit as a report reads it: its name and description, the RMS misfit
    (the data's unit), the parameters with their intervals and correlation matrix, whether
    it is ``kept`` (else ``kept_note`` may say why), how its ``intervals`` were found
    (``profile`` or ``linearised``), its residual test and whether it ``explains`` the
    curves (:mod:`camopt.core.fitting`)."""

    @property
    def form(self) -> str: ...
    @property
    def description(self) -> str: ...
    @property
    def rms(self) -> float: ...
    @property
    def parameters(self) -> tuple[ParameterEstimate, ...]: ...
    @property
    def correlation(self) -> Floats: ...
    @property
    def kept(self) -> bool: ...
    @property
    def kept_note(self) -> str: ...
    @property
    def intervals(self) -> str: ...
    @property
    def residuals(self) -> ResidualTest | None: ...
    @property
    def explains(self) -> bool: ...


class Calibrated(Protocol):
    """A case's finished calibration: the fits of its model forms, the verdict on them,
    and the case's own parts of the report (its words: what it predicts, how its curves
    read), the case fragment and the fitted curves."""

    @property
    def fits(self) -> Sequence[ModelFit]: ...

    @property
    def unit(self) -> tuple[str, float]:
        """The data's unit in reports: its name and its size in SI (``("mm", 1e-3)``)."""
        ...

    def verdict(self) -> Verdict:
        """Whether a form explains the curves, with every warning."""
        ...

    def head(self) -> tuple[dict[str, Any], str]:
        """The case's top-level JSON entries and the report's line on what it reads."""
        ...

    def details(self, fit: ModelFit) -> tuple[dict[str, Any], list[str]]:
        """A form's case-specific JSON entries (its curves, its predictions) and lines."""
        ...

    def fragment(self, extends: str) -> str:
        """TOML text: ``extends = <extends>`` and a ``[case]`` of the calibrated values."""
        ...

    def curves(self) -> tuple[FittedCurve, ...]:
        """Every form's fit of every curve (the figures' and the archive's data)."""
        ...
