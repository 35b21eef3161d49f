"""The compiled closing (camopt/cases/vcb/kernel.py) against the numpy reference
(closing_state then events_of, CAMOPT_NUMBA=0): the events to 1e-12 relative on random
designs under the band's parameter sets and at the near-balance release, the node geometry
within rounding, the least cam torque to 1e-9 of the driving torque; the fallback when
numba is absent."""

from __future__ import annotations

import subprocess
import sys
from dataclasses import fields

import numpy as np
import pytest

from camopt.cases.vcb import VcbProblem
from camopt.cases.vcb import dynamics as dyn
from tests.cases import vcb_ode
from tests.conftest import CONFIGS, ROOT
from tests.helpers import load

kernel = pytest.importorskip("camopt.cases.vcb.kernel", reason="numba not installed")


ENERGIES = {"final_kinetic", "touch_loss", "pickup_loss"}
"""Events that are differences of energies of some J: a latch energy of 1e-4 J is such a
residue, so they are held to 1e-12 J besides 1e-12 relative (the kernel's free rotation
takes its angles by the addition theorems, numpy by sin and cos: last-bit differences)."""


def _same(ref: dyn.ClosingEvents, new: dyn.ClosingEvents) -> None:
    """Every field equal to 1e-12 relative (energies also to 1e-12 J), with the same NaN
    and inf."""
    for f in fields(ref):
        a = np.asarray(getattr(ref, f.name), dtype=float)
        b = np.asarray(getattr(new, f.name), dtype=float)
        np.testing.assert_allclose(b, a, rtol=1e-12, atol=1e-12 if f.name in ENERGIES else 0,
                                   err_msg=f.name)


def _band_args(problem: VcbProblem, X: np.ndarray) -> tuple:
    A, kc, link = problem.designs(X, None)
    assert problem.band is not None
    sets = problem.band.repeat(len(A))
    return (problem.model, A, kc, link, problem.rod_offset, problem.load, sets,
            problem.config.dynamics_steps)


def _reference(monkeypatch, *args, **kwargs) -> dyn.ClosingEvents:
    """The numpy path's events (closing_state then events_of, with the free rotation and
    the first zero in numpy too: ``CAMOPT_NUMBA=0``)."""
    with monkeypatch.context() as m:
        m.setenv("CAMOPT_NUMBA", "0")
        return dyn.events_of(dyn.closing_state(*args, **kwargs))


def test_kernel_matches_numpy_on_random_designs_under_the_band(monkeypatch):
    p = VcbProblem(load(CONFIGS / "vcb_velocity.toml").case)
    rng = np.random.default_rng(36)
    # random designs (most stall), and the vendor's neighbourhood (most close and latch)
    X = np.vstack([p.lower + rng.random((60, p.n_var)) * (p.upper - p.lower),
                   p.vendor_x() * (1 + 0.02 * rng.standard_normal((40, p.n_var)))])
    X = np.clip(X, p.lower, p.upper)
    args = _band_args(p, X)
    sets = len(np.ravel(p.band.cam_kg_m2))
    ref = _reference(monkeypatch, *args, sets=sets)
    new = dyn.compiled_events(kernel, *args, sets=sets)
    assert ref.latched.any() and not ref.latched.all()  # both branches covered
    assert np.isfinite(ref.touch_time).any() and np.isinf(ref.touch_time).any()
    _same(ref, new)


@pytest.mark.parametrize("ratio", [0.999, 1.001])
def test_kernel_matches_numpy_at_the_near_balance_release(ratio, monkeypatch):
    """Friction set so that eps T_s / T_f at the release is 0.999 (the cam never starts)
    or 1.001 (it starts slowly), as in test_vcb_dynamics."""
    p = vcb_ode.problem_at_release_ratio(ratio)
    X = p.vendor_x()[None, :]
    A, kc, link = p.designs(X, None)
    args = (p.model, A, kc, link, p.rod_offset, p.load, p.dynamics, p.config.dynamics_steps)
    ref = _reference(monkeypatch, *args)
    new = dyn.compiled_events(kernel, *args)
    assert ref.release_torque_ratio[0] == pytest.approx(ratio, rel=1e-12)
    assert np.isinf(ref.cam_contact_time[0]) == (ratio < 1)
    _same(ref, new)


def test_closing_events_take_the_kernel_and_the_numpy_path_alike(monkeypatch):
    """``closing_events`` (what the band evaluates through) gives the same with the kernel
    and with ``CAMOPT_NUMBA=0`` (the numpy path)."""
    p = VcbProblem(load(CONFIGS / "vcb_velocity.toml").case)
    X = p.vendor_x()[None, :] * np.array([[1.0], [1.01], [0.99]])
    args = _band_args(p, np.clip(X, p.lower, p.upper))
    sets = len(np.ravel(p.band.cam_kg_m2))
    compiled = dyn.closing_events(*args, sets=sets)
    monkeypatch.setenv("CAMOPT_NUMBA", "0")
    _same(dyn.closing_events(*args, sets=sets), compiled)


def test_validate_does_not_import_numba():
    """No compile or import cost on a command that evaluates no VCB."""
    code = ("import sys; from typer.testing import CliRunner; from camopt.cli import app; "
            f"r = CliRunner().invoke(app, ['validate', {str(CONFIGS / 'vcb_velocity.toml')!r}]);"
            " assert r.exit_code == 0, r.output; print('numba' in sys.modules)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         cwd=ROOT, check=True)
    assert out.stdout.strip().splitlines()[-1] == "False"


def test_kernel_matches_numpy_with_parts_per_design(monkeypatch):
    """A drawn breaker's own parts (closing-spring compressions, opening and contact spring
    rates per design: what tolerance and robust runs evaluate) through the kernel and the
    numpy path alike, the pick-up impact included."""
    from dataclasses import replace

    p = VcbProblem(load(CONFIGS / "vcb_velocity.toml").case)
    rng = np.random.default_rng(33)
    n = 12
    X = p.vendor_x() * (1 + 0.02 * rng.standard_normal((n, p.n_var)))
    X = np.clip(X, p.lower, p.upper)
    model, A, kc, link, rod_offset, loads, sets, steps = _band_args(p, X)
    c = p.config
    pre = np.array([c.kc1_precompression_mm, c.kc2_precompression_mm]) * 1e-3 * (
        1 + 0.02 * rng.standard_normal((n, 2)))
    loads = replace(loads, opening_k=loads.opening_k * (1 + 0.1 * rng.standard_normal((n, 1))),
                    wipe_k=loads.wipe_k * (1 + 0.1 * rng.standard_normal((n, 1))))
    k = len(np.ravel(p.band.cam_kg_m2))
    args = (model, A, kc, link, rod_offset, loads, sets, steps)
    ref = _reference(monkeypatch, *args, sets=k, pre=pre)
    new = dyn.compiled_events(kernel, *args, sets=k, pre=pre)
    assert np.isfinite(ref.pickup_loss).all() and (ref.pickup_loss > 0).any()
    _same(ref, new)


def _random_designs(p: VcbProblem, seed: int) -> np.ndarray:
    """Random designs (most stall) and the vendor's neighbourhood (most close and latch)."""
    rng = np.random.default_rng(seed)
    X = np.vstack([p.lower + rng.random((40, p.n_var)) * (p.upper - p.lower),
                   p.vendor_x() * (1 + 0.02 * rng.standard_normal((40, p.n_var)))])
    return np.clip(X, p.lower, p.upper)


def test_compiled_geometry_matches_numpy_within_rounding():
    """The kernel's node geometry (Horner's rule, the table sincos) against
    ``closing_inputs`` (numpy's matrix product and the same sincos): every quantity
    within 1e-13 of its row's largest magnitude (rounding: measured 3e-14 at most; a
    relative test would fail where s1 or phi' pass through zero)."""
    p = VcbProblem(load(CONFIGS / "vcb_velocity.toml").case)
    A, kc, link = p.designs(_random_designs(p, 7), None)
    steps = p.config.dynamics_steps
    theta, _ = dyn.graded_grid(p.model.theta_c[-1], steps)
    ref = dyn.closing_inputs(p.model, A, kc, link, p.rod_offset, p.load, theta)
    pre = np.tile([p.config.kc1_precompression_mm * 1e-3,
                   p.config.kc2_precompression_mm * 1e-3], (len(A), 1))
    loads = np.array([np.full(len(A), float(v)) for v in (
        p.load.opening_k, p.load.opening_arm, p.load.opening_stretch_open, p.load.wipe_k,
        p.load.wipe_preload, p.load.free_contact)])
    new = np.empty((7, len(A), theta.size))
    _, extension, rate = p.model.graded_springs(steps)
    kernel.closing_geometry(theta, A, link, np.full(len(A), float(p.rod_offset)), kc, pre,
                            extension, rate, loads, p.load.gap, p.model.xi, p.model.l2,
                            p.model.theta_bo, new)
    for name, a, b in zip(("dphi", "s1", "ds1", "spring", "torque", "resisting",
                           "resisting_torque"), ref, new):
        assert np.array_equal(np.isnan(a), np.isnan(b)), name
        scale = np.nanmax(np.abs(a), axis=1, keepdims=True)
        assert np.nanmax(np.abs(a - b) / scale) < 1e-13, name


@pytest.mark.parametrize("shared", [True, False], ids=["shared-link", "drawn-links"])
def test_compiled_statics_match_numpy_within_rounding(shared):
    """The statics on the case's nodes compiled (``VcbModel.kinematics`` and
    ``contact.contact_ratio`` with the kernel, the robust draws' path) against their numpy
    path: the same operations in the same order, so equal on this machine (measured);
    held within 1e-14 of each row's largest magnitude, as another CPU's compiler may
    round differently. Links shared by every design (a nominal population) and drawn per
    row (tolerance draws, with a rod offset per row)."""
    from camopt.cases.vcb import contact

    p = VcbProblem(load(CONFIGS / "vcb_velocity_robust.toml").case)
    m = p.model
    A, kc, link = p.designs(_random_designs(p, 17), None)
    offset: float | np.ndarray = p.rod_offset
    if not shared:
        rng = np.random.default_rng(5)
        link = link * (1 + 2e-3 * rng.standard_normal(link.shape))
        offset = p.rod_offset + 1e-3 * rng.standard_normal((len(A), 1))
    new = m.kinematics(A, link, offset, kernel=kernel)
    ref = m._numpy_kinematics(A, link, offset, m.theta_c)
    pairs = [(name, getattr(ref, name), getattr(new, name))
             for name in ("cos4", "sin4", "s1", "ds1")]
    pairs += [(name, getattr(ref.follower, name), getattr(new.follower, name))
              for name in ("cos_a", "sin_a", "angle", "dphi", "ddphi")]
    torque = m.closing_torque(kc)
    with np.errstate(all="ignore"):
        pairs.append(("contact ratio",
                      contact._numpy_contact_ratio(ref.follower, torque, m.l2, m.l6, m.rf),
                      contact.contact_ratio(new.follower, torque, m.l2, m.l6, m.rf, kernel)))
    for name, a, b in pairs:
        assert np.array_equal(np.isnan(a), np.isnan(b)), name
        assert np.isfinite(a).any(), name  # designs that assemble are compared
        scale = np.nanmax(np.abs(a), axis=1, keepdims=True)
        assert np.nanmax(np.abs(a - b) / np.where(scale > 0, scale, 1)) <= 1e-14, name
    with np.errstate(all="ignore"):  # and the peak stress the verdict reads
        np.testing.assert_allclose(
            m.peak_stress(A, new.follower, torque, kernel=kernel),
            m.peak_stress(A, ref.follower, torque), rtol=1e-12)


def test_compiled_sincos_is_the_numpy_one():
    """The geometry's compiled sincos is camopt.mechanics.trig's (the same operations in
    the same order; compared within 1e-16 absolute, half an ulp near 1, since a compiler
    may round differently on another CPU), within the table and beyond it, NaN and inf
    included; and within 2 ulp of libm (an independent reference)."""
    from camopt.cases.vcb.kernel_geometry import sincos
    from camopt.mechanics import trig

    x = np.r_[np.random.default_rng(11).uniform(-40.0, 40.0, 4000), 0.0, -0.0, 1e-300,
              trig._LIMIT, -trig._LIMIT * (1 - 1e-16), np.nan, np.inf, -np.inf]
    with np.errstate(invalid="ignore"):
        new = np.array([sincos(v) for v in x]).T
        ref = np.array(trig.sincos(x))
        lib = np.array([np.cos(x), np.sin(x)])
    np.testing.assert_allclose(new, ref, rtol=0, atol=1e-16)
    np.testing.assert_allclose(new[:, :-3], lib[:, :-3], rtol=0, atol=4.5e-16)


def test_compiled_closing_motion_matches_numpy(monkeypatch):
    """``closing_motion`` through the kernel (events and the least cam torque, the curves
    on first use) against the numpy path (``CAMOPT_NUMBA=0``): the events to 1e-12 as
    above, the least cam torque within 1e-9 of the row's mean driving torque (it is
    eps T_s - T_f less J_cam omega domega/dtheta, a difference of larger terms:
    measured 2e-10: omega^2 differenced on the fine nodes near the start), the curves those
    of closing_state."""
    p = VcbProblem(load(CONFIGS / "vcb_velocity.toml").case)
    X = _random_designs(p, 11)
    A, kc, link = p.designs(X, None)
    args = (p.model, A, kc, link, p.rod_offset, p.load, p.dynamics, p.config.dynamics_steps)
    new = dyn.closing_motion(*args)
    with monkeypatch.context() as m:
        m.setenv("CAMOPT_NUMBA", "0")
        ref = dyn.closing_motion(*args)
    events = [f.name for f in fields(dyn.ClosingEvents)]
    _same(dyn.ClosingEvents(**{f: getattr(ref, f) for f in events}),
          dyn.ClosingEvents(**{f: getattr(new, f) for f in events}))
    low_ref, low_new = ref.cam_torque_min, new.cam_torque_min
    assert np.isfinite(low_ref).any() and np.isinf(low_ref).any()  # reached and never
    assert np.array_equal(np.isinf(low_ref), np.isinf(low_new))
    mean_drive = p.model.driving_work(kc) / p.model.theta_c[-1]
    finite = np.isfinite(low_ref)
    assert np.all(np.abs(low_new[finite] - low_ref[finite]) <= 1e-9 * mean_drive[finite])
    # the curves from closing_state either way (here with the compiled free rotation)
    np.testing.assert_allclose(new.time, ref.time, rtol=1e-12)
    np.testing.assert_allclose(new.cam_torque, ref.cam_torque, rtol=1e-9,
                               atol=1e-9 * mean_drive.max())
