"""VCB opening and closing dynamics (camopt/cases/vcb/dynamics.py): the work-energy method
against independent ODE integrations of Lagrange's equation at non-degenerate points (a
follower inertia, friction and a release off the opened-state crank), convergence, energy
bookkeeping, and the identification on the vendor's ADAMS data (Kang 2023 Sec 3.2)."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from camopt.cases.vcb import VcbProblem, dynamics
from camopt.cases.vcb.dynamics import (
    MotionParameters,
    closing_events,
    closing_motion,
    first_zero,
)
from camopt.cases.vcb.forms import link_mass_rows
from camopt.cases.vcb.identify import (
    DATA,
    PARAMETERS,
    VcbDynamicsIdentification,
    data_tolerance,
)
from camopt.engine.driver import execute
from camopt.units import DEG, MS, N_PER_MM
from tests.cases import vcb_ode
from tests.conftest import CONFIGS, VELOCITY_PAPER
from tests.helpers import load

TABLE6 = np.array([0.238432, 0.000226, -0.011492, 9315.336, 7788.183])  # Table 6 DE-gr
# a non-degenerate point of the model: every term of J(theta) and every load in play
RICH = ("case.follower_inertia_kg_m2=2.0e-3", "case.cam_friction_nm=6.0",
        "case.release_offset_deg=8.0", "case.dynamics_band=[]")


@pytest.fixture(scope="module")
def problem():
    return VcbProblem(load(CONFIGS / "vcb.toml", "case.dynamics_steps=4000", *RICH).case)


def _closing_ode(problem, x):
    """Right-hand side of J(theta) theta'' + J'(theta) theta'^2 / 2 = eps T - T_f - Fr ds1,
    J = J_cam + J_f phi'^2 + (m_rod + m_c) ds1^2, for one design before the touch, and the
    conserved energy KE + eps E_cs + V_r + T_f theta, from the model's kinematics at
    single angles (nothing shared with the energy method but the model)."""
    m, c, loads = problem.model, problem.config, problem.load
    A, kc, link = problem.designs(x)
    mass = c.rod_mass_kg + c.contacts_mass_kg

    def state(theta):
        kin = m.kinematics(A, link, problem.rod_offset, np.array([0.0, theta]))
        return kin.s1[0, 1], kin.ds1[0, 1], kin.dphi[0, 1]

    def inertia(theta):
        _, ds1, dphi = state(theta)
        return c.cam_inertia_kg_m2 + c.follower_inertia_kg_m2 * dphi**2 + mass * ds1**2

    def rhs(_t, y):
        theta, omega = y
        s1, ds1, _ = state(theta)
        ext, rate = m.closing_spring_geometry(np.array([theta]))
        torque = m.closing_torque(kc, (ext, rate))[0, 0]
        h = 1e-6
        dj = (inertia(theta + h) - inertia(theta - h)) / (2 * h)
        force = loads.resistant_force(np.array([s1]))[0]
        return [omega, (c.efficiency * torque - c.cam_friction_nm - force * ds1
                        - 0.5 * dj * omega**2) / inertia(theta)]

    def energy(theta, omega):
        s1, _, _ = state(theta)
        ext, _ = m.closing_spring_geometry(np.array([theta]))
        stored = m.closing_energy(kc, ext)[0, 0]
        return (0.5 * inertia(theta) * omega**2 + c.efficiency * stored
                + loads.resistant_energy(np.array([s1]))[0] + c.cam_friction_nm * theta)

    def touch(_t, y):
        return state(y[0])[0] - loads.gap

    touch.terminal = True
    return rhs, energy, touch


@pytest.mark.parametrize("which", ["vendor", "table6"])
def test_closing_matches_an_ode_integration(problem, which):
    """From the cam meeting the roller to the contacts' touch, the energy method's touch
    time and cam speed equal solve_ivp's (DOP853, rtol 1e-11) to 1e-4, and the ODE keeps
    KE + eps E_closing + V_resist + T_f theta constant to 1e-6 of the driving work."""
    x = problem.vendor_x() if which == "vendor" else TABLE6
    mo = problem.motion(x)
    rhs, energy, touch = _closing_ode(problem, x[None, :])
    sol = solve_ivp(rhs, (0.0, 0.1), [0.0, mo.omega[0, 0]], method="DOP853", rtol=1e-11,
                    atol=1e-12, events=touch, dense_output=True)
    assert sol.status == 1  # stopped at the touch
    t_event, (theta_t, omega_t) = sol.t_events[0][0], sol.y_events[0][0]
    assert mo.touch_time[0] - mo.cam_contact_time[0] == pytest.approx(t_event, rel=1e-4)
    i = np.searchsorted(mo.theta_c, theta_t) - 1
    w = (theta_t - mo.theta_c[i]) / (mo.theta_c[i + 1] - mo.theta_c[i])
    omega_energy = (1 - w) * mo.omega[0, i] + w * mo.omega[0, i + 1]
    assert omega_energy == pytest.approx(omega_t, rel=1e-4)
    samples = np.linspace(0, t_event, 25)
    e = np.array([energy(*sol.sol(t)) for t in samples])
    driving = problem.evaluate(x[None, :]).extras["driving_work_j"][0]
    assert np.ptp(e) / driving < 1e-6


def test_free_rotation_matches_an_ode_integration(problem):
    """The freely turning cam, J_cam theta'' = eps T(theta) - T_f from rest at the release
    crank angle, reaches the roller (theta_c = 0) at the energy method's time and speed
    within 1e-4 (solve_ivp, DOP853)."""
    m, c = problem.model, problem.config
    x = problem.vendor_x()
    _, kc, _ = problem.designs(x)
    mo = problem.motion(x)
    start = m.dead_centre + c.release_offset_deg * np.pi / 180 - m.contact_crank_angle

    def rhs(_t, y):
        torque = m.closing_torque(kc, m.closing_spring_geometry(np.array([y[0]])))[0, 0]
        return [y[1], (c.efficiency * torque - c.cam_friction_nm) / c.cam_inertia_kg_m2]

    def contact(_t, y):
        return y[0]

    contact.terminal = True
    sol = solve_ivp(rhs, (0.0, 0.2), [start, 0.0], method="DOP853", rtol=1e-11, atol=1e-13,
                    events=contact)
    assert sol.status == 1
    assert mo.cam_contact_time[0] == pytest.approx(sol.t_events[0][0], rel=1e-4)
    omega_free = sol.y_events[0][0][1]
    # after the plastic impact on the roller: J_cam omega- = J(0) omega+
    j0 = (c.cam_inertia_kg_m2 + c.follower_inertia_kg_m2 * (problem.model.vendor_a[1]) ** 2
          + (c.rod_mass_kg + c.contacts_mass_kg) * (mo.rod_velocity[0, 0] / mo.omega[0, 0]) ** 2)
    assert mo.omega[0, 0] == pytest.approx(c.cam_inertia_kg_m2 * omega_free / j0, rel=1e-4)
    # and the impact takes the relative motion's energy, 1/2 J* omega^2 (Carnot)
    j_star = c.cam_inertia_kg_m2 * (j0 - c.cam_inertia_kg_m2) / j0
    assert mo.pickup_loss[0] == pytest.approx(0.5 * j_star * omega_free**2, rel=2e-4)


def test_opening_matches_an_ode_integration():
    """The opening from the closed state at rest, J(phi) phi'' + J'(phi) phi'^2 / 2 =
    -eps Fr(s1) ds1/dphi with J = J_f + m_rod (ds1/dphi)^2, gives the energy method's
    contact separation time within 1e-3 (solve_ivp, DOP853; the rest start is graded
    in the energy method)."""
    from camopt.cases.vcb.dynamics import opening_motion

    p = VcbProblem(load(CONFIGS / "vcb.toml", *RICH).case)
    m, c, loads = p.model, p.config, p.load
    A, _, link = p.designs(p.vendor_x())
    end = m.theta_c[-1]
    phi_closed = float(A[0] @ [1.0, end, end**2, end**3])
    phi_open = float(A[0, 0])

    def rod(phi):
        lin = np.array([[phi_open, 1.0, 0.0, 0.0]])
        kin = m.kinematics(lin, link, p.rod_offset, np.array([0.0, phi - phi_open]))
        return kin.s1[0, 1], kin.ds1[0, 1]

    def inertia(phi):
        return c.follower_inertia_kg_m2 + c.rod_mass_kg * rod(phi)[1] ** 2

    def rhs(_t, y):
        phi, rate = y
        s1, ds = rod(phi)
        h = 1e-7
        dj = (inertia(phi + h) - inertia(phi - h)) / (2 * h)
        force = loads.resistant_force(np.array([s1]))[0]
        return [rate, (-c.efficiency * force * ds - 0.5 * dj * rate**2) / inertia(phi)]

    def separation(_t, y):
        return rod(y[0])[0] - loads.gap

    separation.terminal = True
    sol = solve_ivp(rhs, (0.0, 0.05), [phi_closed, 0.0], method="DOP853", rtol=1e-10,
                    atol=1e-12, events=separation)
    assert sol.status == 1
    op = opening_motion(m, A, link, p.rod_offset, loads, p.dynamics, steps=4000)
    assert op.departure_time[0] == pytest.approx(sol.t_events[0][0], rel=1e-3)


def test_motion_converges_with_the_integration_grid():
    """The metrics at the configs' 400 graded steps equal those at 4,000 within 1e-4."""
    x = np.vstack([TABLE6, [0.343973, -0.179031, 0.0431478, 4032.8, 4779.95]])
    out = []
    for steps in (400, 4000):
        p = VcbProblem(load(CONFIGS / "vcb.toml", f"case.dynamics_steps={steps}", *RICH).case)
        mo = p.motion(x)
        out.append(np.r_[mo.closing_velocity_avg, mo.touch_time, mo.cam_contact_time,
                         mo.touch_velocity])
    np.testing.assert_allclose(out[0], out[1], rtol=1e-4)


def test_energy_left_at_the_latch_is_eps_surplus_less_losses(problem):
    """Bookkeeping: kinetic energy at the latch = eps x surplus (Eq 26) + the cam's kinetic
    energy after meeting the roller - the contacts' kinetic energy lost at the touch - the
    friction torque's work over the 140 deg stroke."""
    X = np.vstack([problem.vendor_x(), TABLE6])
    mo = problem.motion(X)
    ev = problem.evaluate(X)
    c = problem.config
    A, _, _ = problem.designs(X)
    dphi0 = A[:, 1]  # phi'(0) = a1
    ds1 = mo.rod_velocity[:, 0] / mo.omega[:, 0]
    start = 0.5 * mo.omega[:, 0] ** 2 * (
        c.cam_inertia_kg_m2 + c.follower_inertia_kg_m2 * dphi0**2
        + (c.rod_mass_kg + c.contacts_mass_kg) * ds1**2)
    expected = (c.efficiency * ev.extras["surplus_work_j"] + start - mo.touch_loss
                - c.cam_friction_nm * mo.theta_c[-1])
    np.testing.assert_allclose(mo.final_kinetic, expected, rtol=1e-9)
    assert np.all(mo.latched)


def test_zero_surplus_stalls_before_the_latch():
    """A zero-surplus design (the paper's objective, Eq 26) has nothing left to pay the
    contacts' impact loss and the friction: the cam stops short of 140 deg."""
    p = VcbProblem(load(CONFIGS / "vcb.toml").case)
    x = np.array([0.0728521, 0.101742, -0.0259065, 4050.72, 4814.89])
    ev = p.describe(x[None, :])
    assert abs(ev.extras["surplus_work_j"][0]) < 0.05
    assert ev.extras["latched"][0] == 0 and np.isinf(ev.extras["release_to_latch_ms"][0])


@pytest.fixture(scope="module")
def identification():
    return VcbDynamicsIdentification(load(CONFIGS / "vcb_identify_dynamics.toml").case)


def test_identification_meets_every_adams_datum(identification, reported):
    """The parameters in configs/vcb.toml meet each of the vendor's seven ADAMS data (Sec
    3.2, Table 4) within 10 % (closed by the run's end at 45 ms: a bound), with five
    parameters, at least two fewer than the data; the targets are the paper's."""
    adams = reported["vcb"]["adams_vendor"]
    c = load(CONFIGS / "vcb.toml").case
    x = np.array([[getattr(c, name) for name in PARAMETERS]])
    ev = identification.evaluate(x)
    assert len(DATA) >= 6 and len(PARAMETERS) <= len(DATA) - 2
    for d in DATA:
        target = adams["closed_by_ms" if d.upper_bound_only else d.name]
        value = ev.extras[d.name][0]
        if d.upper_bound_only:
            assert value <= target, d.name
        else:
            assert value == pytest.approx(target, rel=0.10), d.name
    assert ev.extras["max_residual_pct"][0] <= 10.0


@pytest.mark.slow
def test_identification_run_reproduces_the_config_values():
    """configs/vcb_identify_dynamics.toml (DE-gr, its 3 repeats, 80 generations) reports
    n_data, n_parameters, the largest residual and each datum's residual, and fits the
    ADAMS data as well as the parameters copied into configs/vcb.toml: misfit within 2 %
    of theirs (the misfit is flat along J_cam: fits land anywhere in the band, 5.0e-4 -
    6.8e-4 kg m^2; test_band_members_are_as_consistent_as_the_fit), every datum within
    10 %. The misfit has other basins (0.016 - 0.09: J_cam 1e-3 - 2e-3 with less friction)
    where a repeat ends for about 1 seed in 3 (8 of 21 repeats of seeds 0-6): such a
    repeat misses run.target (0.016), so it is no success, and its fit is worse than the
    config's. Checked for seeds 0-6: the best of 3 was within 1.5 % of the config's
    misfit for each (about 5 % of seeds would have all three repeats in another basin)."""
    rec = execute(load(CONFIGS / "vcb_identify_dynamics.toml", "solver.generations=80"))
    m = rec.metrics
    assert m["n_data"] == 7 and m["n_parameters"] == 5
    assert m["max_residual_pct"] <= 10.0
    assert all(f"residual_{d.key}_pct" in m for d in DATA)
    case = load(CONFIGS / "vcb.toml").case
    config_x = rec.problem.from_display({k: getattr(case, k) for k in PARAMETERS})
    config_f = rec.problem.evaluate(config_x[None, :]).f[0]
    assert rec.best.success and len(rec.repeats) == 3
    assert rec.best.fun <= 1.02 * config_f
    for r in rec.repeats:
        assert r.success or r.fun > config_f  # another basin: a worse fit, said so
    # every model form fitted on the same data, kept by the stated criterion
    forms = {f["name"]: f for f in rec.findings["model_forms"]}
    assert len(forms) >= 4
    best = min(f["max_residual_pct"] for f in forms.values())
    for f in forms.values():
        assert {"misfit", "max_residual_pct", "kept", "parameters"} <= f.keys()
        assert f["kept"] == (f["max_residual_pct"] <= max(1.5 * best, 10.0))
    assert forms["coulomb"]["kept"] and forms["efficiency_coulomb"]["kept"]
    assert forms["coulomb"]["misfit"] < forms["efficiency_coulomb"]["misfit"]
    # identifiability: the release offset and the friction move together (issue #31)
    ident = rec.findings["identifiability"]
    s = ident["singular_values"]
    assert s == sorted(s, reverse=True) and ident["condition"] > 50
    assert ident["correlations"]["release_offset_deg"]["cam_friction_nm"] > 0.99
    # the band over the kept forms reaches every datum's reading interval, or misses it by
    # less than the widening it carries
    band = rec.findings["band"]
    assert set(band["sets_per_form"]) == {n for n, f in forms.items() if f["kept"]}
    for d in band["data"]:
        assert d["misses_reading_interval_by"] <= d["tolerance"], d["datum"]
    velocity = next(d for d in band["data"] if d["datum"] == "closing_velocity_avg_m_s")
    assert velocity["misses_reading_interval_by"] == 0


def test_band_members_are_consistent_with_the_data_in_their_form(identification):
    """Every parameter set of configs/vcb.toml's dynamics_band, simulated in its own model
    form (efficiency 0.85: the shipped form; 1: Coulomb friction alone), predicts each
    ADAMS datum (Sec 3.2, Table 4) within its reading error (2 % velocities, 0.5 ms times)
    widened to the largest residual of the forms' fits (the first set of each form), and
    the closing by 45 ms plus that; both forms are in the band."""
    c = identification.config
    band = np.array(load(CONFIGS / "vcb.toml").case.dynamics_band)
    forms = {0.85: "efficiency_coulomb", 1.0: "coulomb"}
    assert set(band[:, 7]) == set(forms) and np.all(band[:, 6] == band[:, 5])
    y = np.empty((len(band), len(DATA)))
    for eps, name in forms.items():
        rows = band[:, 7] == eps
        p = VcbDynamicsIdentification(c.model_copy(update={"model_form": name}))
        y[rows] = p.predict(band[rows][:, [0, 2, 3, 4, 5]])
    fits = [np.flatnonzero(band[:, 7] == eps)[0] for eps in forms]
    widened = np.max(np.abs(identification.residuals(y[fits])))
    tolerance = data_tolerance(c, widened)
    assert 0.05 < widened < 0.10
    event = ~identification.one_sided
    assert np.all(np.abs(y - identification.targets)[:, event] <= tolerance[event] + 1e-9)
    assert np.all(y[:, ~event] <= identification.targets[~event] + tolerance[~event])


def test_table6_against_the_vendor_in_every_reading():
    """configs/reference/vcb_table6.toml: the vendor row is within 10 % of ADAMS's 1.71 m/s;
    Table 6's optimum is not predicted 32 % slower (paper: 1.17 m/s): its velocity is at
    least 0.96 of the vendor's with Table 2 as printed and with the two closing springs'
    pre-compressions swapped (docs/assumptions.md)."""
    for swap in ((), ("case.kc1_precompression_mm=100", "case.kc2_precompression_mm=140")):
        p = VcbProblem(load(CONFIGS / "vcb.toml", *swap).case)
        v = p.describe(np.vstack([p.vendor_x(), TABLE6])).extras["closing_velocity_avg_m_s"]
        assert v[0] == pytest.approx(1.71, rel=0.10)
        assert v[1] / v[0] >= 0.96
        assert v[1] / v[0] > 1.17 / 1.71 + 0.2


@pytest.mark.slow
def test_velocity_design_passes_every_requirement_in_every_set():
    """configs/vcb_velocity.toml (reduced: 1 repeat, 15,000 evaluations) under the band over
    both kept model forms, in its design space (30 mm base circle, quintic law, the latch's
    seat a variable: docs/assumptions.md, "VCB: the velocity design's space"): the best
    found keeps its whole closing-velocity band in 0.9 +- 0.2 m/s (Sec 2.1), releases with
    the 1.2 torque margin and latches under every parameter set with at least 1 J and at
    most 5 J left, tau_max < 1194 MPa, phi_max in [23, 26] deg, rod travel 18.0 +- 0.2 mm:
    the run is feasible (in the paper's space it was not)."""
    rec = execute(load(CONFIGS / "vcb_velocity.toml", "run.repeats=1",
                       "solver.evaluations=15000"))
    m = rec.metrics
    assert rec.best.feasible
    assert 0.7 - 1e-6 <= m["closing_velocity_low_m_s"] <= m["closing_velocity_avg_m_s"]
    assert m["closing_velocity_avg_m_s"] <= m["closing_velocity_high_m_s"] <= 1.1 + 1e-6
    assert m["tau_max_mpa"] < 1194 and 23 <= m["phi_max_deg"] <= 26
    assert abs(m["rod_travel_mm"] - 18.0) <= 0.2 + 1e-6
    # the identified set, 9 of dynamics_band, each form's link-mass set
    assert m["latched"] == 1 and m["band_sets_not_latched"] == 0 and m["band_sets"] == 12
    low, high = m["latch_kinetic_energy_low_j"], m["latch_kinetic_energy_high_j"]
    assert 1.0 - 1e-6 <= low <= high <= 5.0 + 1e-6  # at the limits within 1e-6 J
    assert m["release_torque_margin_low"] >= 1.2 - 1e-6
    assert m["lift_off_torque_ratio"] >= 0.05 - 1e-6


def test_band_is_the_extremes_over_the_parameter_sets():
    """closing_velocity_low/high_m_s and latched of a design are the min, max and all over
    the identified set, every set of dynamics_band and each form's link-mass set, each
    simulated on its own (the band
    reuses one kinematics per design for all sets; a set's efficiency is the case's in a
    run of its own, its free rotation's friction the same as the driven closing's);
    where the contacts never meet in some set the band's velocities are undefined (NaN:
    "n/a, fails" in the verdict, issue #34)."""
    assert all(row[6] == row[5] for row in load(CONFIGS / "vcb.toml").case.dynamics_band)
    p = VcbProblem(load(VELOCITY_PAPER).case)
    rng = np.random.default_rng(5)
    X = np.vstack([p.vendor_x(), p.lower + rng.random((6, p.n_var)) * (p.upper - p.lower)])
    ev = p.describe(X)
    v, latched, closed, touched = [], [], [], []
    links = link_mass_rows(np.array(p.config.dynamics_band), p.config)
    assert len(links) == 2  # each form's fit with the links' own masses
    for row in [None, *p.config.dynamics_band, *links]:
        sets = () if row is None else (
            "case.dynamics_band=[]", f"case.cam_inertia_kg_m2={row[0]}",
            f"case.follower_inertia_kg_m2={row[1]}", f"case.rod_mass_kg={row[2]}",
            f"case.contacts_mass_kg={row[3]}", f"case.release_offset_deg={row[4]}",
            f"case.cam_friction_nm={row[5]}", f"case.efficiency={row[7]}")
        one = VcbProblem(load(VELOCITY_PAPER, *sets).case).motion(X)
        v.append(one.closing_velocity_avg)
        latched.append(one.latched)
        closed.append(one.closing_time)
        touched.append(one.touch_time)
    # two computations (one kinematics shared by the band vs one per set): to rounding
    every = np.isfinite(touched).all(axis=0)
    assert every.any() and not every.all()  # both kinds of design are exercised
    with np.errstate(invalid="ignore"):
        low, high = np.min(v, axis=0), np.max(v, axis=0)
    np.testing.assert_allclose(ev.extras["closing_velocity_low_m_s"],
                               np.where(every, low, np.nan), rtol=1e-12, atol=1e-15)
    np.testing.assert_allclose(ev.extras["closing_velocity_high_m_s"],
                               np.where(every, high, np.nan), rtol=1e-12, atol=1e-15)
    np.testing.assert_array_equal(ev.extras["latched"], np.all(latched, axis=0))
    np.testing.assert_array_equal(ev.extras["band_sets_not_latched"],
                                  np.sum(~np.array(latched), axis=0))
    assert np.all(ev.extras["band_sets"] == len(latched))
    # the members' times come from the events-only path, the nominal's from the curves
    for name, values in (("release_to_latch", closed), ("touch_time", touched)):
        np.testing.assert_allclose(ev.extras[f"{name}_low_ms"], np.min(values, axis=0) / MS,
                                   rtol=1e-12, atol=1e-12)
        np.testing.assert_allclose(ev.extras[f"{name}_high_ms"], np.max(values, axis=0) / MS,
                                   rtol=1e-12, atol=1e-12)
    assert np.isfinite(closed).any()  # some designs close: the times are exercised
    assert np.ptp(np.array(v)[:, 0]) > 0  # the vendor's band has a width


def test_a_cam_the_springs_cannot_release_never_closes():
    """Friction above the closing springs' torque at the release crank angle: the cam never
    leaves it, so nothing of the closing happens (no contact, no latch), whatever the
    springs could do further on."""
    p = VcbProblem(load(CONFIGS / "vcb.toml", "case.dynamics_band=[]",
                        "case.release_offset_deg=1.0", "case.cam_friction_nm=30").case)
    mo = p.motion(p.vendor_x())
    assert np.isinf(mo.cam_contact_time[0]) and not mo.latched[0]
    # its reach is below 0 by the torque ratio's shortfall (rotation.start_shortfall)
    ratio = mo.release_torque_ratio[0]
    assert 0 < ratio < 1 and mo.reach[0] == pytest.approx(ratio - 1, rel=1e-12)
    assert np.isinf(mo.closing_time[0])
    free = VcbProblem(load(CONFIGS / "vcb.toml", "case.dynamics_band=[]",
                           "case.release_offset_deg=1.0", "case.cam_friction_nm=0").case)
    assert free.motion(free.vendor_x()).latched[0]  # the same springs close without it


def test_a_latch_seat_past_the_roller_contact_is_graded_by_how_far():
    """A latch seat that holds the crank past the roller contact (release angle >= 0):
    no free rotation, and the reach is minus that angle as a share of the cam's stroke,
    so the latch constraint grows with it instead of sitting on one value for every
    such seat (what stranded the robust VCB's searches); the compiled events and the
    numpy reference agree."""
    problems = [VcbProblem(load(CONFIGS / "vcb.toml", "case.dynamics_band=[]",
                                f"case.release_offset_deg={deg}").case) for deg in (24, 26, 28)]
    m = problems[0].model
    past = [m.dead_centre + d * np.pi / 180 - m.contact_crank_angle for d in (24, 26, 28)]
    assert min(past) > 0  # every seat lies past the contact
    reach = []
    for p, angle in zip(problems, past):
        mo = p.motion(p.vendor_x())
        assert np.isinf(mo.cam_contact_time[0]) and not mo.latched[0]
        reach.append(mo.reach[0])
        assert mo.reach[0] == pytest.approx(-angle / m.theta_c[-1], rel=1e-9)
        A, kc, link = p.designs(p.vendor_x())
        state = dynamics.closing_state(m, A, kc, link, p.rod_offset, p.load, p.dynamics,
                                       p.config.dynamics_steps)
        assert dynamics.events_of(state).reach[0] == pytest.approx(mo.reach[0], rel=1e-12)
    assert reach[0] > reach[1] > reach[2]


@pytest.mark.parametrize("ratio", [0.999, 1.001])
def test_release_decision_matches_an_ode_at_torque_ratios_either_side_of_one(ratio):
    """Friction set so that eps T_s / T_f at the vendor's release crank angle is 0.999 or
    1.001: the test's own ODE of the free rotation (J_cam theta'' = eps T(theta) - T_f while
    turning; Coulomb friction holds the cam at rest while eps T <= T_f; DOP853, rtol 1e-11)
    decides as camopt does: at 0.999 the cam never leaves the release (no contact, no
    latch), at 1.001 it meets the roller at the ODE's time within 1e-6 (the free
    rotation's sinh grid gives 1.5e-7 here: the slow start is resolved)."""
    p = vcb_ode.problem_at_release_ratio(ratio)
    m, c, friction = p.model, p.config, p.config.cam_friction_nm
    _, kc, _ = p.designs(p.vendor_x())
    start = m.dead_centre + c.release_offset_deg * np.pi / 180 - m.contact_crank_angle
    mo = p.motion(p.vendor_x())

    def rhs(_t, y):
        torque = m.closing_torque(kc, m.closing_spring_geometry(np.array([y[0]])))[0, 0]
        net = c.efficiency * torque - friction
        turning = y[1] > 0 or net > 0  # static friction holds a cam at rest up to T_f
        return [y[1], net / c.cam_inertia_kg_m2 if turning else 0.0]

    def contact(_t, y):
        return y[0]

    contact.terminal = True
    sol = solve_ivp(rhs, (0.0, 0.5), [start, 0.0], method="DOP853", rtol=1e-11, atol=1e-13,
                    events=contact)
    assert mo.release_torque_ratio[0] == pytest.approx(ratio, rel=1e-12)
    if ratio < 1:
        assert sol.status == 0 and np.all(sol.y[0] == start)  # the ODE's cam never moves
        assert np.isinf(mo.cam_contact_time[0]) and not mo.latched[0]
        assert mo.reach[0] == pytest.approx(ratio - 1, rel=1e-9)  # minus its shortfall
    else:
        assert sol.status == 1
        assert mo.cam_contact_time[0] == pytest.approx(sol.t_events[0][0], rel=1e-6)


@pytest.mark.parametrize("ratio", [1.00001, 1.001])
def test_closing_time_near_balance_matches_an_ode(ratio):
    """The latch moved so that eps T_s / T_f at the release is 1.00001 or 1.001 (the
    identified friction throughout: the driven closing latches): the closing time from
    the release to the latch, of the curves (numpy) and of the events (what a band
    member gives, compiled where numba is), equals the test's own ODE of every phase
    (tests/cases/vcb_ode.py: DOP853, rtol 1e-11, each phase ended by an event) within
    2e-4 (the issue asks 0.5 %; at 400 steps it is 3.8e-5 and 5.0e-5, the driven
    closing's trapezoid times), the cam contact within 2e-6 (measured 6e-7 and 2e-7), and
    doubling ``dynamics_steps`` moves the closing time by less than 1e-4 (measured 3.3e-5,
    4.3e-5). Before the free rotation's sinh grid the cam contact at 1.00001 came 12 %
    early on the fixed 64-interval grid."""
    p = vcb_ode.problem_released_at_ratio(ratio)
    _, kc, _ = p.designs(p.vendor_x())
    ode = vcb_ode.simulate(p, tuple(kc[0] / N_PER_MM), vcb_ode.truth_of(p), rtol=1e-11)
    times = {}
    for steps in (400, 800):
        q = VcbProblem(p.config.model_copy(update={"dynamics_steps": steps}))
        A, kc, link = q.designs(q.vendor_x()[None, :])
        mo = q.motion(q.vendor_x()[None, :])
        events = closing_events(q.model, A, kc, link, q.rod_offset, q.load, q.dynamics,
                                steps)
        assert mo.release_torque_ratio[0] == pytest.approx(ratio, rel=1e-9)
        assert mo.latched[0] and events.latched[0]
        assert mo.cam_contact_time[0] == pytest.approx(ode.cam_contact_time, rel=2e-6)
        assert mo.closing_time[0] == pytest.approx(ode.closing_time, rel=2e-4)
        assert events.closing_time[0] == pytest.approx(mo.closing_time[0], rel=1e-12)
        times[steps] = mo.closing_time[0]
    assert times[800] == pytest.approx(times[400], rel=1e-4)


@pytest.mark.parametrize("numba", ["1", "0"], ids=["compiled", "numpy"])
def test_first_zero_finds_a_zero_between_positive_nodes(monkeypatch, numba):
    """An energy positive at every node that dips below zero between two (the phantom
    creep of issue #31): the first zero is found inside the interval, exactly for a
    quadratic (the Hermite interpolant reproduces it), whatever the node spacing; an
    energy that stays positive has none; a start at rest with a positive slope is not
    one. Both paths: the compiled kernel and the numpy reference (CAMOPT_NUMBA=0)."""
    monkeypatch.setenv("CAMOPT_NUMBA", numba)
    def e(x):
        return (x - 0.5) ** 2 - 0.001

    def de(x):
        return 2 * (x - 0.5)

    root = 0.5 - np.sqrt(0.001)
    for x in (np.array([0.0, 1.0, 2.0]), np.linspace(0.0, 2.0, 7)):
        assert e(x).min() > 0  # no node sees it
        assert first_zero(x, e(x)[None], de(x)[None])[0] == pytest.approx(root, abs=1e-9)
    x = np.linspace(0.0, 1.0, 5)
    assert np.isnan(first_zero(x, (e(x) + 0.01)[None], de(x)[None])[0])
    assert np.isnan(first_zero(x, (x * (2 - x))[None], (2 - 2 * x)[None])[0])


@pytest.mark.parametrize("ode, terms", [
    ({"spring_kg": 1.2}, {"spring_kg": 0.8}),  # two 1.2 kg springs: a third of each moves
    ({"dashpot_n_s_per_m": 250.0}, {"rod_damping_n_s_per_m": 250.0}),
])
def test_spring_mass_and_rod_dashpot_match_the_independent_ode(ode, terms):
    """The closing springs' own mass and a rod dashpot against tests/cases/vcb_ode.py
    (solve_ivp on Lagrange's equation with the same terms): rod travel within 1 um
    (0.5 um measured on the case's 400 steps), touch time within 1e-6 s and the closing
    velocity within 1e-4 relative; each term moves the velocity by over 7 %, so the test
    sees them."""
    from camopt.cases.vcb.calibration_model import _loads
    from camopt.units import N_PER_MM

    p = VcbProblem(load(CONFIGS / "vcb.toml").case)
    m, c, t = p.model, p.config, vcb_ode.TRUTH
    kc = np.array([vcb_ode.SPRING_SETS["vendor"]]) * N_PER_MM
    rod, t_touch, v = vcb_ode.closing(p, vcb_ode.SPRING_SETS["vendor"], **ode)
    _, _, v_rigid = vcb_ode.closing(p, vcb_ode.SPRING_SETS["vendor"])
    params = MotionParameters(t.cam_kg_m2, 0.0, t.rod_kg, t.contacts_kg,
                              t.release_offset_deg * DEG, t.friction_nm, **terms)
    mo = closing_motion(m, m.vendor_a[None], kc, m.vendor_link[None],
                        c.rod_arm_offset_deg * DEG, _loads(m), params, c.dynamics_steps)
    ev = closing_events(m, m.vendor_a[None], kc, m.vendor_link[None],
                        c.rod_arm_offset_deg * DEG, _loads(m), params, c.dynamics_steps)
    assert abs(v - v_rigid) > 0.07 * v_rigid
    assert mo.touch_time[0] == pytest.approx(t_touch, abs=1e-6)
    assert mo.closing_velocity_avg[0] == pytest.approx(v, rel=1e-4)
    assert ev.closing_velocity_avg[0] == pytest.approx(v, rel=1e-4)  # the events' path
    times = np.linspace(0.012, 0.04, 200)
    ok = np.isfinite(mo.time[0])
    np.testing.assert_allclose(np.interp(times, mo.time[0][ok], mo.rod[0][ok]), rod(times),
                               atol=1e-6)


def test_a_case_with_spring_mass_and_damping_simulates_them_in_every_band_set():
    """case.spring_mass_kg and case.rod_damping_n_s_per_m reach the design run: the
    vendor's closing velocity and the band's ends are each slower than the rigid case's
    (every set carries the terms), by more than 5 % at these values."""
    rigid = VcbProblem(load(CONFIGS / "vcb.toml").case)
    x = rigid.vendor_x()[None, :]
    a = rigid.describe(x).extras
    for setting in ("case.spring_mass_kg=0.8", "case.rod_damping_n_s_per_m=250"):
        b = VcbProblem(load(CONFIGS / "vcb.toml", setting).case).describe(x).extras
        for key in ("closing_velocity_avg_m_s", "closing_velocity_low_m_s",
                    "closing_velocity_high_m_s"):
            assert b[key][0] < 0.95 * a[key][0], (setting, key)
