"""The VCB ``[case]`` models (camopt/cases/vcb/config.py), split by step (issue #37): the
mechanism every kind describes, step 1's search (the cam), step 2's (the four-bar), and
the identifications on the same flat table."""

from __future__ import annotations

import pydantic
import pytest

from camopt.cases.vcb.config import VcbCamStep, VcbConfig, VcbMechanism
from camopt.cases.vcb.identify_config import VcbDynamicsIdentifyConfig, VcbIdentifyConfig


def test_the_steps_are_layers_of_one_flat_table():
    """VcbConfig's keys are the mechanism's, then step 1's, then step 2's, in that order
    (the TOML and ``camopt init`` keep their order); the identifications take them all."""
    mechanism, cam = list(VcbMechanism.model_fields), list(VcbCamStep.model_fields)
    full = list(VcbConfig.model_fields)
    assert full[:len(mechanism)] == mechanism and full[:len(cam)] == cam
    assert {"a1_bounds", "kc2_bounds_n_per_mm"} <= set(cam) - set(mechanism)
    assert {"l1_bounds_mm", "cam_design", "cam_archive"} <= set(full) - set(cam)
    for identify in (VcbIdentifyConfig, VcbDynamicsIdentifyConfig):
        assert set(full) <= set(identify.model_fields)


@pytest.mark.parametrize("model, fields, match", [
    (VcbMechanism, {"node_cam_deg": [0.0, 70.0, 60.0, 140.0]}, "node_cam_deg"),
    (VcbMechanism, {"phi_max_deg": (26.0, 23.0)}, "phi_max_deg"),
    (VcbMechanism, {"closing_velocity_m_s": (1.1, 0.7)}, "closing_velocity_m_s"),
    (VcbCamStep, {"a5_bounds": {"lower": -0.01, "upper": 0.01}}, "a5_bounds needs a4"),
    (VcbCamStep, {"release_offset_bounds_deg": {"lower": 0.0, "upper": 10.0}},
     "release_offset_bounds_deg"),
    (VcbConfig, {"step": "fourbar"}, "needs the step-1 design"),
    (VcbConfig, {"step": "fourbar", "cam_archive": "a.h5",
                 "a4_bounds": {"lower": -0.01, "upper": 0.01}}, "a4_bounds: a step-1"),
])
def test_each_step_checks_its_own_fields(model, fields, match):
    with pytest.raises(pydantic.ValidationError, match=match):
        model.model_validate(fields)


def test_an_identification_takes_no_step_two_design():
    """The four-bar step's needs are step 2's: an identification is not held to them."""
    assert VcbIdentifyConfig.model_validate({"step": "fourbar"}).cam_design is None
