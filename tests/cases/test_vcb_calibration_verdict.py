"""The verdict on a VCB calibration (camopt/cases/vcb/calibration_verdict.py) on hand-built
fits: which forms it names, NOT EXPLAINED with the best form's test, the at-bound warning
of a kept form only."""

from __future__ import annotations

import numpy as np

from camopt.cases.vcb.calibrate import FormFit
from camopt.cases.vcb.calibration_verdict import verdict
from camopt.core.fitting import ParameterEstimate, ResidualTest
from camopt.units import MM


def _fit(name, explains, kept=True, at_bound=False, rms=0.02 * MM):
    p = ParameterEstimate("rod_mass_kg", "kg", 3.0, 2.9, 3.1, True, at_bound)
    return FormFit(name, name, rms, (p,), np.eye(1), (), (), np.zeros((1, 1)), kept=kept,
                   residuals=ResidualTest(0.02 * MM, rms / (0.02 * MM), 1.9, 1.0, 100),
                   explains=explains)


def test_explained_by_the_forms_that_explain_and_none_other():
    v = verdict([_fit("a", True), _fit("b", False), _fit("c", True)], 8 * MM)
    assert v.explained and v.forms == ("a", "c")
    assert v.headline.startswith("verdict: explained by forms a, c ")


def test_not_explained_names_the_best_forms_test():
    v = verdict([_fit("a", False, rms=0.05 * MM), _fit("b", False, rms=0.03 * MM)],
                8 * MM)
    assert not v.explained and v.forms == ()
    assert "NOT EXPLAINED" in v.headline and "best form b: residual RMS 1.50 x" in v.headline


def test_a_parameter_at_its_bound_is_warned_of_in_kept_forms_only():
    v = verdict([_fit("a", True, at_bound=True), _fit("b", False, kept=False,
                                                     at_bound=True)], 8 * MM)
    assert len(v.warnings) == 1 and v.warnings[0].startswith("form a: rod_mass_kg")
