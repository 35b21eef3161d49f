"""VCB model forms (camopt/cases/vcb/forms.py) and the requirements the dynamics add
(camopt/cases/vcb/requirements.py)."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from camopt.cases.vcb import VcbProblem
from camopt.cases.vcb.dynamics import closing_motion
from camopt.cases.vcb.forms import FORMS, form_of, get_form, link_mass_rows
from camopt.cases.vcb.requirements import requirements
from camopt.errors import ConfigError
from tests.conftest import VELOCITY_PAPER
from tests.helpers import load


@pytest.fixture(scope="module")
def problem():
    return VcbProblem(load(VELOCITY_PAPER, "case.dynamics_steps=100").case)


def _vector(form, c):
    values = {"cam_inertia_kg_m2": c.cam_inertia_kg_m2, "rod_mass_kg": c.rod_mass_kg,
              "contacts_mass_kg": c.contacts_mass_kg, "release_offset_deg": c.release_offset_deg,
              "cam_friction_nm": c.cam_friction_nm, "efficiency": 0.9}
    return np.array([[values[n] for n in form.parameters]])


def test_the_shipped_form_is_the_case_dynamics(problem):
    """efficiency_coulomb under the case's values simulates exactly what the case does
    (the same computation: identical bits)."""
    c = problem.config
    A, kc, link = problem.designs(problem.vendor_x())
    form = get_form("efficiency_coulomb")
    mo = form.closing(problem.model, A, kc, link, problem.rod_offset, problem.load,
                      _vector(form, c), c.follower_inertia_kg_m2, c.dynamics_steps)
    ref = closing_motion(problem.model, A, kc, link, problem.rod_offset, problem.load,
                         problem.dynamics, c.dynamics_steps)
    np.testing.assert_array_equal(mo.time, ref.time)
    np.testing.assert_array_equal(mo.rod, ref.rod)


def test_each_form_charges_its_own_losses(problem):
    """Without the efficiency the springs drive harder (an earlier cam contact); without
    friction in the free rotation the cam meets the roller earlier still and the release
    ratio is infinite; a fitted efficiency is the row's; events() of k rows for n designs
    is set-major, each row as closing() alone."""
    c = problem.config
    A, kc, link = problem.designs(problem.vendor_x())
    args = (problem.model, A, kc, link, problem.rod_offset, problem.load)
    contact = {}
    for form in FORMS:
        mo = form.closing(*args, _vector(form, c), c.follower_inertia_kg_m2, c.dynamics_steps)
        contact[form.name] = mo.cam_contact_time[0]
        if form.friction != "everywhere":
            assert np.isinf(mo.release_torque_ratio[0])
    assert contact["coulomb"] < contact["efficiency_coulomb"]
    assert contact["driven_coulomb"] < contact["coulomb"]
    mp = get_form("fitted_efficiency").motion_parameters(_vector(get_form("fitted_efficiency"),
                                                                 c), 0.0)
    assert mp.efficiency == pytest.approx(0.9) and mp.friction_nm == 0.0
    form = get_form("coulomb")
    X = np.vstack([_vector(form, c), _vector(form, c) * [1, 1, 1, 1.05, 0.95]])
    designs = np.vstack([problem.vendor_x(), problem.vendor_x() * 1.02])
    A2, kc2, link2 = problem.designs(designs)
    ev = form.events(problem.model, A2, kc2, link2, problem.rod_offset, problem.load, X,
                     0.0, c.dynamics_steps)
    for k in range(2):
        for i in range(2):
            one = form.closing(problem.model, A2[i:i + 1], kc2[i:i + 1], link2[i:i + 1],
                               problem.rod_offset, problem.load, X[k:k + 1], 0.0,
                               c.dynamics_steps)
            assert ev.touch_time[2 * k + i] == pytest.approx(one.touch_time[0], rel=1e-12)


def test_an_unknown_form_names_the_known_ones():
    with pytest.raises(ConfigError, match="efficiency_coulomb, coulomb"):
        get_form("viscous")


def test_every_dynamic_requirement_is_judged_with_its_limit(problem):
    """The release margin, the lift-off share, the latch energy's upper limit, the pick-up
    impact's shear stress and the count of band sets that do not close are requirements
    whenever the dynamics report them, with the case's limits."""
    ev = problem.describe(problem.vendor_x()[None, :])
    case = problem.config.model_dump()
    case = {**case, "release_torque_margin_min": 1.3}
    reqs = {r.quantity: r for r in requirements(case, ev.extras.keys())}
    assert reqs["release_torque_margin_low"].lower == 1.3
    assert reqs["lift_off_torque_ratio"].lower == problem.config.lift_off_fraction_min
    assert reqs["latch_kinetic_energy_high_j"].upper == problem.config.latch_energy_max_j
    assert reqs["band_sets_not_latched"].upper == 0
    assert reqs["pickup_tau_mpa"].upper == problem.config.shear_yield_mpa
    # the vendor: it releases under every set, but with less than the margin
    low = ev.extras["release_torque_margin_low"][0]
    assert 1.0 < low < 1.3 and not reqs["release_torque_margin_low"].passes(low)
    assert replace(reqs["band_sets_not_latched"]).passes(ev.extras["band_sets_not_latched"][0])


def test_link_masses_are_each_forms_fit_with_heavier_links(problem):
    """The band's link-mass sets: each kept form's fit (the identified parameters for
    theirs) with the follower's inertia raised by m/2 l2^2 + J_f and the rod's mass by
    m/2 (l4/l5)^2, nothing else changed (to rounding); none without a band or masses;
    heavier links close slower under the same set (the band's slow end)."""
    c = problem.config
    band = np.array(c.dynamics_band, dtype=float)
    rows = link_mass_rows(band, c)
    firsts = [0] + [i + 1 for i in range(len(band))
                    if form_of(band[i]) != form_of(band[0])][:1]
    assert [form_of(r) for r in rows] == ["efficiency_coulomb", "coulomb"] and len(firsts) == 2
    identified = [c.cam_inertia_kg_m2, c.follower_inertia_kg_m2, c.rod_mass_kg,
                  c.contacts_mass_kg, c.release_offset_deg, c.cam_friction_nm,
                  c.cam_friction_nm, c.efficiency]
    fits = np.array([identified, band[firsts[1] - 1]])
    m, jf = c.band_coupler_mass_kg, c.band_follower_inertia_kg_m2
    assert m > 0 and jf > 0
    added = np.zeros(8)
    added[1] = m / 2 * (c.l2_mm * 1e-3) ** 2 + jf
    added[2] = m / 2 * (c.l4_mm / c.l5_mm) ** 2
    np.testing.assert_allclose(rows, fits + added, rtol=1e-12)
    assert len(link_mass_rows(band[:0], c)) == 0
    light = c.model_copy(update={"band_coupler_mass_kg": 0.0,
                                 "band_follower_inertia_kg_m2": 0.0})
    assert len(link_mass_rows(band, light)) == 0
    # under the identified set: the heavier links touch later and slower
    A, kc, link = problem.designs(problem.vendor_x())
    form = get_form("efficiency_coulomb")
    vectors = np.array([[r[0], r[2], r[3], r[4], r[5]] for r in (identified, rows[0])])
    ev = [form.closing(problem.model, A, kc, link, problem.rod_offset, problem.load,
                       v[None, :], jfol, c.dynamics_steps)
          for v, jfol in zip(vectors, (identified[1], rows[0][1]))]
    assert ev[1].touch_velocity[0] < ev[0].touch_velocity[0]
    assert ev[1].touch_time[0] > ev[0].touch_time[0]
