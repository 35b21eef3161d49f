"""The VCB constraint table (camopt/cases/vcb/constraints.py): its rows in the archive's
order, and the signs of the dynamic ones (g <= 0 met)."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

from camopt.cases.vcb import VcbProblem
from camopt.cases.vcb.constraints import CONSTRAINTS
from tests.conftest import CONFIGS
from tests.helpers import load

ROW = {con.name: con for con in CONSTRAINTS}


def test_names_are_listed_once_and_a_config_takes_its_rows_in_order():
    names = [con.name for con in CONSTRAINTS]
    assert len(names) == len(set(names))
    p = VcbProblem(load(CONFIGS / "vcb_velocity.toml").case)
    assert p.constraint_names == tuple(n for n in names
                                       if n not in ("grashof", "preload_setting"))
    robust = VcbProblem(load(CONFIGS / "vcb_velocity_robust.toml",
                             "case.velocity_setting_bounds_m_s=[0.75, 1.05]").case)
    assert robust.constraint_names == tuple(n for n in names if n != "grashof")
    assert VcbProblem(load(CONFIGS / "vcb.toml").case).constraint_names == (
        "phi_max_low", "phi_max_high", "monotonic", "assembly", "rod_travel", "shear_yield")


def test_lift_off_is_met_above_the_share_and_violated_below():
    """The least cam torque as a share of the mean driving torque: 20 % meets a 5 %
    limit (g < 0), 0 % and a pulling cam (-10 %) violate it (g > 0), by the gap."""
    q = SimpleNamespace(config=SimpleNamespace(lift_off_fraction_min=0.05),
                        lift_off_ratio=np.array([0.2, 0.0, -0.1]))
    np.testing.assert_allclose(ROW["lift_off"].g(q), [-0.15, 0.05, 0.15])


def test_the_setting_fails_beyond_the_nuts_reach_and_on_a_missed_velocity():
    """The factory setting (issue #33): the nut travel needed within its reach (10 mm:
    4 mm met, 12 mm and -15 mm violated by the share), and the set velocity within 1 %
    of the setting under every set of the band (1.5 % missed, a stall NaN failed)."""
    q = SimpleNamespace(config=SimpleNamespace(preload_setting_range_mm=10.0),
                        setting=np.array([4e-3, 12e-3, -15e-3, 1e-3, 1e-3]),
                        setting_velocity=np.full(5, 1.0),
                        spread=SimpleNamespace(velocity_low=np.array([1.0, 1.0, 1.0, 1.0, np.nan]),
                                               velocity_high=np.array([1.0, 1.0, 1.0, 1.015,
                                                                       1.0])))
    np.testing.assert_allclose(ROW["preload_setting"].g(q)[:4], [-0.6, 0.2, 0.5, 0.5])
    assert ROW["preload_setting"].g(q)[4] == np.inf


def test_release_torque_is_met_above_the_margin_and_violated_below():
    q = SimpleNamespace(config=SimpleNamespace(release_torque_margin_min=1.2),
                        spread=SimpleNamespace(release_ratio_low=np.array([1.5, 1.2, 1.0])))
    np.testing.assert_allclose(ROW["release_torque"].g(q), [-0.25, 0.0, 1 / 6])


def test_lift_off_share_reads_the_least_cam_torque_over_the_mean_driving_torque():
    """In a real evaluation: the share is cam_torque_min x stroke angle / driving work,
    and the constraint is the limit less it."""
    p = VcbProblem(load(CONFIGS / "vcb_velocity.toml", "case.dynamics_steps=100").case)
    ev = p.evaluate(p.vendor_x()[None, :])
    e = ev.extras
    share = e["cam_torque_min_nm"] * p.model.theta_c[-1] / e["driving_work_j"]
    np.testing.assert_allclose(e["lift_off_torque_ratio"], share, rtol=1e-12)
    g = ev.g[:, p.constraint_names.index("lift_off")]
    np.testing.assert_allclose(g, p.config.lift_off_fraction_min - share, rtol=1e-12)


def test_a_design_that_never_closes_fails_its_velocity_requirements_as_n_a():
    """Issue #34: a breaker whose contacts never meet (friction far above the springs'
    torque) has no closing velocity: its band's ends are NaN, and the requirements on them
    read "n/a" and fail (they read 0 m/s and passed the upper limit before)."""
    from camopt.cases.vcb.requirements import requirements
    from camopt.core.requirements import check

    cfg = load(CONFIGS / "vcb_velocity.toml", "case.cam_friction_nm=60")
    p = VcbProblem(cfg.case)
    ev = p.describe(p.vendor_x()[None, :])
    values = {k: float(v[0]) for k, v in ev.extras.items()}
    assert np.isinf(values["touch_time_high_ms"])
    reqs = requirements(cfg.case.model_dump(), set(values))
    checks = {c.requirement.quantity: c for c in check(reqs, values)
              if c.requirement.quantity.startswith("closing_velocity")}
    assert {"closing_velocity_low_m_s", "closing_velocity_high_m_s"} <= set(checks)
    for c in checks.values():
        assert np.isnan(c.value) and c.passed is False and "n/a" in c.words


def test_pickup_impact_is_met_below_the_shear_yield_and_violated_above():
    q = SimpleNamespace(config=SimpleNamespace(shear_yield_mpa=1000.0),
                        pickup_tau=np.array([500e6, 1000e6, 1500e6]))
    np.testing.assert_allclose(ROW["pickup_impact"].g(q), [-0.5, 0.0, 0.5])


def test_pickup_shear_is_the_hertz_stress_of_the_bands_hardest_blow():
    """The vendor's pick-up (vcb_velocity's case): the reported shear stress is Eq 31 at
    the force that stores the band's greatest impact energy in the line contact of the
    cam profile where it meets the roller (its curvature from the contact's own path,
    ``VcbModel.contact``) and the roller; within the shear yield (about 0.55 of it)."""
    from camopt.mechanics import hertz

    p = VcbProblem(load(CONFIGS / "vcb_velocity.toml").case)
    x = p.vendor_x()[None, :]
    ev = p.describe(x)
    m, c = p.model, p.config
    A, kc, link = p.designs(x)
    kin = m.kinematics(A, link, p.rod_offset)
    rho = m.contact(kin.follower, m.closing_torque(kc)).curvature[0, 0]
    e_eq = hertz.equivalent_modulus(c.cam_modulus_gpa * 1e9, c.poisson,
                                    c.cam_modulus_gpa * 1e9, c.poisson)
    force = hertz.line_impact_force(ev.extras["pickup_impact_energy_high_j"][0], rho, m.rf,
                                    c.contact_length_mm * 1e-3, e_eq)
    tau = hertz.line_contact(force, rho, m.rf, c.contact_length_mm * 1e-3, e_eq)[2] / 1e6
    assert ev.extras["pickup_tau_mpa"][0] == pytest.approx(tau, rel=1e-9)
    assert 0.4 < ev.extras["pickup_tau_mpa"][0] / c.shear_yield_mpa < 0.7
