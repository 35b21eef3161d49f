"""The multibody model of the VCB closing (camopt.cases.vcb.multibody): its geometry against
camopt's kinematics, its agreement with camopt's lumped closing on the vendor's design, and
its convergence in the step size."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest

from camopt.cases import build_problem
from camopt.cases.vcb import multibody
from camopt.cases.vcb.mechanism import mechanism_of
from camopt.cases.vcb.verify import TIME_LIMIT, VELOCITY_LIMIT, camopt_side
from camopt.engine.setup import load
from tests.conftest import CONFIGS

needs_engine = pytest.mark.skipif(not multibody.available(),
                                  reason="the camopt[multibody] extra is not installed")


@pytest.fixture(scope="module")
def vendor():
    problem = build_problem(load(CONFIGS / "vcb.toml").case)
    x = problem.vendor_x()
    return problem, x, mechanism_of(problem, x)


def test_linkage_is_camopts_own(vendor):
    """The mechanism's own four-bar (circle intersection, its own assembly branch) moves
    the rod as camopt's kinematics (Freudenstein's equation in a mirrored frame) do: two
    independent computations of one geometry, to rounding (rtol 1e-9)."""
    problem, x, mech = vendor
    A, _, link = problem.designs(x)
    theta = np.linspace(0.0, mech.cam_end, 9)
    kin = problem.model.kinematics(A, link, problem.rod_offset, theta)
    ours = [mech.rod_travel(t) for t in theta]
    np.testing.assert_allclose(ours, kin.s1[0], rtol=1e-9, atol=1e-12)


def test_plastic_contact_is_critically_damped():
    """Restitution 0 is critical damping; a coefficient e gives the damping ratio whose
    free linear rebound is e (exp(-zeta pi / sqrt(1 - zeta^2)) = e, to rounding)."""
    assert multibody.damping_ratio(0.0) == 1.0
    for e in (0.1, 0.5, 0.9):
        z = multibody.damping_ratio(e)
        assert math.exp(-z * math.pi / math.sqrt(1 - z * z)) == pytest.approx(e, rel=1e-12)


@needs_engine
def test_vendor_closing_agrees_with_camopts(vendor):
    """The multibody closing of the vendor's design, plastic pick-up, agrees with camopt's
    lumped one within the check's limits (2 % on the release-to-touch time, 3 % on the
    touch and the analyser's velocity); measured: +0.06 %, +0.01 %, -0.04 %."""
    problem, x, mech = vendor
    ours = camopt_side(problem, x)
    ev, trace = multibody.run(mech)
    assert ev.touch_time == pytest.approx(ours["touch_time"], rel=TIME_LIMIT)
    assert ev.touch_velocity == pytest.approx(ours["touch_velocity"], rel=VELOCITY_LIMIT)
    assert ev.contact_velocity_avg == pytest.approx(ours["contact_velocity_avg"],
                                                    rel=VELOCITY_LIMIT)
    assert trace.cam_angle[-1] >= mech.cam_end  # it reached the end of travel


@needs_engine
@pytest.mark.slow
def test_halving_the_step_changes_little(vendor):
    """The engine's result has converged in the step: half the step moves the touch time
    and velocities by less than 0.1 %."""
    _, _, mech = vendor
    full, _ = multibody.run(mech, multibody.STEP)
    half, _ = multibody.run(mech, multibody.STEP / 2)
    for name in ("touch_time", "touch_velocity", "contact_velocity_avg"):
        assert getattr(half, name) == pytest.approx(getattr(full, name), rel=1e-3), name


@needs_engine
@pytest.mark.slow
def test_a_coupler_mass_slows_the_close(vendor):
    """A 0.2 kg coupler (a bar with two revolute joints instead of the massless distance
    constraint) is more inertia to accelerate: the touch comes later and slower (measured
    +1.3 %, -2.1 % at the default step; here at 4e-5 s, which moves each by < 0.1 %), and
    the restitution of the pick-up, which returns at most ~0.3 J of ~15 J, moves neither by
    more than 0.5 %."""
    _, _, mech = vendor
    step = 4e-5
    base, _ = multibody.run(mech, step)
    heavy, _ = multibody.run(replace(mech, coupler_mass=0.2), step)
    assert 0.005 < heavy.touch_time / base.touch_time - 1 < 0.03
    assert -0.04 < heavy.touch_velocity / base.touch_velocity - 1 < -0.01
    elastic, _ = multibody.run(mech, step, restitution=0.6)
    assert elastic.touch_velocity == pytest.approx(base.touch_velocity, rel=5e-3)
