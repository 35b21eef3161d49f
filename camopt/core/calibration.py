"""What ``camopt calibrate`` hands a case and gets back: typed, kind-free.

A case that can be calibrated on measured curves names its function in
``CaseSpec.calibration`` (``"module:function"``, imported only when asked); the function
takes the validated ``[case]`` config and a :class:`CalibrationRequest` and returns a
:class:`CalibrationReport`. The command line knows no case kind (``docs/design.md``)."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any, Protocol

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
