"""The kinetic energy a VCB breaker of the ``coulomb`` model form needs at the contacts'
touch, as built, to pass the release and the latch at the end of its life: the
inequality of docs/tolerance.md ("Adjustments at assembly and the end of life", "Where it
stands"), and where it stops short of a bound.

One parameter set of the ``coulomb`` form (eps = 1, friction torque T from the release
on), friction scale s as built, the end of life at 1 + rise (friction) and 1 - relax
(the closing springs' compressions, the nut held). The closing springs are linear: with
P = k1 p1 + k2 p2 (p_i the compressions with the nut) and K = k1 + k2, their force at
extension e (from the opened state, :meth:`VcbModel.closing_spring_geometry`) is
P - K e, their work from e1 to e2 is P (e2 - e1) - K (e2^2 - e1^2) / 2, and relaxing the
compressions by relax takes relax P per metre of extension. Every step is an inequality
of the model's equations (:mod:`camopt.cases.vcb.closing`, :mod:`~camopt.cases.vcb.rotation`,
:mod:`~camopt.cases.vcb.life`):

1. The release at the end of life (ratio >= 1.2, :func:`release_torque_ratio`):
   ((1 - relax) P - K e_r) rate_r >= 1.2 (1 + rise) s T, e_r and rate_r the springs'
   extension and rate at the release. The cam turns free only from a release before the
   roller (theta_r < 0, else it never starts), where the rate rises to rate(0), so
   P >= (1.2 (1 + rise) s T / rate(0) + K e_min) / (1 - relax), e_min the extension at
   the earliest release the latch's space allows.
2. Energy to the touch (theta_t, where the rod reaches the contact gap g), as built:
   KE_t = KE_0 + W(e_0, e_t) - V_r(g) - s T theta_t, KE_0 >= 0 what the cam keeps of the
   free rotation after the pick-up's impact, so W(e_0, e_t) <= KE_t + V_r(g) + s T theta_t
   (V_r(g) at its largest: the opening spring's rate +10 %).
3. At the end of life every term before the touch is no larger: the free rotation's
   energy and the pick-up's share of it (the same inertias) fall, and
   KE'_t <= KE_t - relax P (e_t - e_0) - rise s T theta_t.
4. The energy left at the latch at the end of life (theta_end = 140 deg) is at most
   KE'_t + W(e_t, e_end) - relax P (e_end - e_t) - dV_a - (1 + rise) s T (theta_end -
   theta_t) (the contacts' impact dropped, >= 0), dV_a = V_r(17.8 mm) - V_r(g) at its
   least (the contact and opening springs' rates -10 %, the rod travel at its 17.8 mm
   limit: the resistant force is positive after the touch).
5. The compressions lie within the free lengths' tolerance and the nut's reach:
   P <= p_max K, p_max = the longer spring's compression + 1.5 + the reach (171.5 mm in
   the serviced space): soft springs cannot carry the release's force.

Steps 1-5 leave a linear programme in (P, K), whose optimum ``latch_bound`` writes in
closed form: with P at the least of p_max K and step 2's limit (E + K q_b) / d_b, the
bound rises with K up to where they meet and falls after it, so K* is the largest of
that meeting point, the release's least K and ``k_min``. The bound rises with KE_t
(it relaxes step 2), and ``least_touch_energy`` inverts it: a breaker that passes at
the end of life (latch >= ``latch_energy_min_j``) had KE_t >= that value at the touch
as built. No inertia or mass of the set enters, only its friction torque; no design
variable but the touch angle (the law, the links and the cam profile set it).
tests/cases/test_vcb_life.py checks steps 2-4 as the model's energy equations, steps
1 and 5 on its releases, the closed form against scipy's linprog, and the composed
inequality, on random designs.

It is not a bound on the yield: that needs KE_t (as built, the analyser's velocity set
by the nut) below the need at every touch angle a passing breaker can have. The need
falls by about 0.5 J per degree of earlier touch (at s = 1.2 under the serviced case's
fit, 7.1 J at 28 deg, 5.5 J at 25, 3.0 J at 20), under what the designs found carry
(5.7-6.3 J), and the velocity band (an average over the last third of the contact
stroke) caps neither the touch velocity nor the cam's own share, J_cam (v_t /
s1'(theta_t))^2 / 2. What holds designs away from an early touch is outside steps 1-5:
the law's coefficient bounds, and the energy staying positive through the contact
springs' wipe after the touch (a stall there, not at the latch). The script prints the
need per friction scale and touch angle; with ``--earliest`` the earliest touch a law of
the space reaches (pressure angle, rod travel, a rod that never turns back; a local
search from the archive's law or the vendor's, where a search stops, not a bound); for
archives, each design's touch angle, energy there and end-of-life latch under the set,
against the need.

    python scripts/vcb_life_touch_energy.py [--config CONFIG] [--set-index I]
        [--k-min N_PER_MM] [--rise 0.25] [--earliest] [ARCHIVE ...]
"""

from __future__ import annotations

import argparse
from dataclasses import dataclass
from pathlib import Path
from typing import cast

import numpy as np
from numpy.typing import NDArray

from camopt.cases.vcb.config import VcbConfig
from camopt.cases.vcb.problem import VcbProblem
from camopt.engine.driver import load
from camopt.units import DEG, MM

ROOT = Path(__file__).resolve().parents[1]
CONFIG = ROOT / "configs" / "vcb_velocity_serviced.toml"
RELEASE_RATIO = 1.2
"""The release margin (``release_torque_ratio`` >= 1.2)."""


@dataclass(frozen=True)
class Space:
    """What the inequality takes from the case and its space, the least or the most over
    it where the safe side needs one (SI): the springs' extension e_0 at the pick-up
    (theta_c = 0) and e_end at the latch, the rate at the pick-up (the most before it),
    the extension at the earliest release, the resistant potential at the gap (its
    most) and from the gap to the least rod travel (its least), the stroke, the
    end of life's rise and relaxation, the latch's least energy, the least total rate
    ``k_min`` (N/m) and the longest compression ``p_max``."""

    e_0: float
    e_end: float
    rate_max: float
    e_min: float
    v_gap: float
    dv_after: float
    theta_end: float
    rise: float
    relax: float
    latch_min: float
    k_min: float
    p_max: float


def space_of(problem: VcbProblem, earliest_release_deg: float, rise: float = 0.25,
             relax: float = 0.03, k_min: float = 0.0, rate_pct: float = 10.0,
             free_length_mm: float = 1.5) -> Space:
    """The :class:`Space` of ``problem``'s case: ``earliest_release_deg`` the earliest
    release past the springs' dead centre any set can have (the latch's lower bound less
    its tolerance, plus the set's offset from the fit); the resisting springs' rates
    within ``rate_pct`` % (class ``standard``: 10); ``k_min`` N/m the least total rate;
    the closing springs' free lengths within ``free_length_mm`` (class ``standard``)."""
    m, c = problem.model, problem.config
    cap = m.contact_crank_angle - m.dead_centre
    theta_end = float(m.theta_c[-1])
    before = np.linspace(earliest_release_deg * DEG - cap, 0.0, 2001)
    ext_before, rate_before = m.closing_spring_geometry(before)
    # the rate rises from the earliest release to the pick-up: its most is at theta_c = 0
    assert np.all(np.diff(rate_before) > 0) and np.all(np.diff(ext_before) > 0)
    (e_0, e_end), _ = m.closing_spring_geometry(np.array([0.0, theta_end]))
    travel = (c.rod_travel_mm - c.rod_travel_tolerance_mm) * MM
    gap = c.contact_gap_mm * MM
    v_gap, v_end = problem.load.resistant_energy(np.array([gap, travel]))
    low, high = 1 - rate_pct / 100, 1 + rate_pct / 100
    # V_r is linear in the opening and contact springs' rates (no free-contact force here)
    assert problem.load.free_contact == 0.0
    return Space(e_0=float(e_0), e_end=float(e_end), rate_max=float(rate_before[-1]),
                 e_min=float(ext_before[0]), v_gap=high * float(v_gap),
                 dv_after=low * float(v_end - v_gap), theta_end=theta_end, rise=rise,
                 relax=relax, latch_min=c.latch_energy_min_j, k_min=k_min,
                 p_max=(max(c.kc1_precompression_mm, c.kc2_precompression_mm) + free_length_mm
                        + c.preload_setting_range_mm) * MM)


def latch_bound(sp: Space, torque: float | NDArray, s: NDArray, theta_t: NDArray,
                e_t: NDArray, ke_t: NDArray) -> NDArray:
    """Steps 1-4: the most energy left at the latch at the end of life for a breaker of
    friction torque ``torque`` x ``s`` as built whose contacts touch at ``theta_t`` (rad,
    springs' extension ``e_t``) with kinetic energy ``ke_t`` (J) as built, (n,)."""
    friction = torque * s
    d_b, d_a = e_t - sp.e_0, sp.e_end - e_t
    q_b, q_a = (e_t**2 - sp.e_0**2) / 2, (sp.e_end**2 - e_t**2) / 2
    keep = 1 - sp.relax
    # 1. P >= a + beta K
    a = RELEASE_RATIO * (1 + sp.rise) * friction / sp.rate_max / keep
    beta = sp.e_min / keep
    # 2. P d_b - K q_b <= E
    work = ke_t + sp.v_gap + friction * theta_t
    # P <= p_max K; the bound's largest at the least K where P = min(p_max K,
    # (E + K q_b) / d_b) meets the release
    k = np.maximum.reduce([np.full(np.shape(work), sp.k_min),
                           (a * d_b - work) / (q_b - beta * d_b),
                           work / (sp.p_max * d_b - q_b)])
    p = np.minimum(sp.p_max * k, (work + k * q_b) / d_b)
    # 3-4.
    return (ke_t + p * d_a - k * q_a - sp.relax * p * (sp.e_end - sp.e_0)
            - sp.rise * friction * theta_t
            - (1 + sp.rise) * friction * (sp.theta_end - theta_t) - sp.dv_after)


def least_touch_energy(sp: Space, torque: float, s: NDArray, theta_t: NDArray,
                       e_t: NDArray) -> NDArray:
    """The least kinetic energy at the touch, as built (J), with which a breaker of
    friction ``torque`` x ``s`` touching at ``theta_t`` (springs' extension ``e_t``) can
    leave ``latch_energy_min_j`` at the latch at the end of life and release there:
    :func:`latch_bound` is increasing in the energy (piecewise linear), inverted by
    bisection on +-1 kJ to 1e-12 J."""
    lo, hi = np.full(np.shape(s), -1e3), np.full(np.shape(s), 1e3)
    f_lo = latch_bound(sp, torque, s, theta_t, e_t, lo)
    f_hi = latch_bound(sp, torque, s, theta_t, e_t, hi)
    for _ in range(60):  # 2 kJ / 2^60
        mid = 0.5 * (lo + hi)
        f = latch_bound(sp, torque, s, theta_t, e_t, mid)
        up = f >= sp.latch_min
        hi, lo = np.where(up, mid, hi), np.where(up, lo, mid)
    assert np.all(f_lo < sp.latch_min) and np.all(f_hi > sp.latch_min)
    return 0.5 * (lo + hi)


def coulomb_sets(problem: VcbProblem) -> tuple[int, NDArray, NDArray]:
    """The ``coulomb`` form's index in ``problem.forms``, and its sets' friction torques
    (N m) and latch offsets from the identified one (rad), the fit first, (k,) each."""
    form = next(i for i, f in enumerate(problem.forms) if f.name == "coulomb")
    every = problem.forms[form]
    sets = [every.nominal] + ([] if every.members is None else [every.members])

    def column(name: str) -> NDArray:
        return np.concatenate([np.ravel(np.asarray(getattr(s, name), dtype=float))
                               for s in sets])
    return (form, column("friction_nm"),
            column("release_offset_rad") - problem.config.release_offset_deg * DEG)


def set_space(problem: VcbProblem, index: int, k_min: float = 0.0) -> tuple[Space, float]:
    """The :class:`Space` and friction torque of the coulomb form's set ``index`` (0 its
    fit): its earliest release is the latch's lower bound less the ±0.25 deg of its seat
    (class ``standard``) plus the set's offset from the fit."""
    c = problem.config
    _, torque, offset = coulomb_sets(problem)
    lower = c.release_offset_bounds_deg.lower if c.release_offset_bounds_deg else 0.0
    earliest = max(lower - 0.25 + float(offset[index]) / DEG, 0.0)
    return space_of(problem, earliest, c.life_friction_rise or 0.25,
                    c.life_spring_relaxation or 0.03, k_min), float(torque[index])


def touch_state(problem: VcbProblem, X: NDArray, index: int, pre: NDArray | None = None,
                scale: NDArray | float = 1.0) -> dict[str, NDArray]:
    """The closing of designs ``X`` (n, n_var) under the coulomb form's set ``index`` (a
    set without follower inertia), its friction times ``scale`` (n,) as built, as built
    and at the end of life (the numpy path, :func:`closing_state`): the closing springs'
    compressions ``pre`` (n, 2) m, or where None each design set at the factory under
    that set (:meth:`VcbProblem.as_set`). Returns the touch angle ``theta_t`` and the
    springs' extension there ``e_t``, the kinetic energy before the touch's impact
    ``ke_t`` and the cam's share ``ke_cam``, the velocities ``v_avg`` and ``v_t``, the
    rod travel and the cam's energy after the pick-up ``ke_0``; at the end of life the
    release ratio, the latch energy (``release_end``, ``latch_end``; 0 where it
    stalls), ``ke_0_end`` and the contacts' impact ``loss_end``, (n,) each."""
    from dataclasses import replace

    from camopt.cases.vcb.closing import closing_state, events_of
    from camopt.cases.vcb.locate import _at, _crossing

    c, m = problem.config, problem.model
    form, _, _ = coulomb_sets(problem)
    n = len(X)
    if pre is None:
        parts, setting = problem.as_set(X, None, form)
        assert parts is not None and parts.pre is not None and setting is not None
        pre = parts.pre if index == 0 or setting.member_pre is None else \
            setting.member_pre[(index - 1) * n:index * n]
    every = problem.forms[form]
    sets = [every.nominal] + ([] if every.members is None else [every.members])
    pick = {name: float(np.concatenate([np.ravel(np.asarray(getattr(s, name), dtype=float))
                                        for s in sets])[index])
            for name in ("cam_kg_m2", "follower_kg_m2", "rod_kg", "contacts_kg",
                         "release_offset_rad", "friction_nm")}
    assert pick["follower_kg_m2"] == 0.0, "a set without the follower's inertia"
    moved = np.asarray(problem.release_offset(X)) - c.release_offset_deg * DEG
    A, kc, link = problem.designs(X)
    A = problem.profiled(A, None)
    out: dict[str, NDArray] = {}
    ends = ((1.0, 1.0, "new"), (1 + c.life_friction_rise, 1 - c.life_spring_relaxation, "end"))
    for rise, keep, tag in ends:
        friction = pick["friction_nm"] * rise * np.broadcast_to(scale, (n,))
        params = replace(every.nominal, cam_kg_m2=pick["cam_kg_m2"], follower_kg_m2=0.0,
                         rod_kg=pick["rod_kg"], contacts_kg=pick["contacts_kg"],
                         release_offset_rad=pick["release_offset_rad"] + moved,
                         friction_nm=friction, release_friction_nm=friction, efficiency=1.0)
        st = closing_state(m, A, kc, link, problem.rod_offset, problem.load, params,
                           c.dynamics_steps, pre=keep * pre)
        ev = events_of(st)
        if tag == "new":
            k, w = _crossing(st.s1, st.gap)
            out["theta_t"] = _at(st.theta[None, :], k, w)
            ds1 = _at(st.ds1, k, w)
            with np.errstate(divide="ignore", invalid="ignore"):
                omega = st.v_touch / ds1
            out["ke_cam"] = 0.5 * pick["cam_kg_m2"] * omega**2
            out["ke_t"] = out["ke_cam"] + 0.5 * (pick["rod_kg"] + pick["contacts_kg"]) \
                * st.v_touch**2
            out["v_avg"], out["v_t"] = ev.closing_velocity_avg, st.v_touch
            out["travel"] = st.s1[:, -1]
            out["touched"] = st.touched
            out["ke_0"] = st.kinetic[:, 0]
        else:
            out["latch_end"] = ev.final_kinetic
            out["release_end"] = ev.release_torque_ratio
            out["ke_0_end"], out["loss_end"] = st.kinetic[:, 0], st.loss
    out["e_t"] = m.closing_spring_geometry(out["theta_t"])[0]
    return out


def earliest_touch(problem: VcbProblem, start: NDArray) -> tuple[NDArray, dict[str, float]]:
    """The earliest touch angle a follower law of ``problem``'s space reaches from the
    law ``start`` (a1..a5): Nelder-Mead on the touch angle with penalties for a pressure
    angle over the case's limit, a rod travel outside its tolerance and a rod that turns
    back (ds1/dtheta < 0), the vendor's links, kinematics only (no springs, no
    dynamics). A local search: where it stops, not a bound. Returns the law and its
    touch angle, pressure angle and rod travel (deg, deg, mm)."""
    from scipy.optimize import minimize

    from camopt.mechanics import cam

    m, c = problem.model, problem.config
    names = ("a1", "a2", "a3", "a4", "a5")
    variables = {v.name: v for v in problem.variables}
    lo = np.array([variables[k].lower for k in names])
    hi = np.array([variables[k].upper for k in names])
    grid = np.linspace(0.0, float(m.theta_c[-1]), 1121)
    gap = c.contact_gap_mm * MM
    limit = c.pressure_angle_max_deg or 90.0

    def kinematics(y: NDArray) -> tuple[float, float, float, float]:
        A = np.r_[m.phi0(), y][None, :]
        k = m.kinematics(A, m.vendor_link[None, :], problem.rod_offset, grid)
        psi = float(np.max(np.abs(cam.pressure_angle(m.l2, m.l6, k.follower)))) / DEG
        s1 = k.s1[0]
        i = int(np.argmax(s1 >= gap))
        if i == 0:
            return np.inf, psi, float(s1[-1]) / MM, float(k.ds1[0].min())
        touch = grid[i - 1] + (gap - s1[i - 1]) / (s1[i] - s1[i - 1]) * (grid[i] - grid[i - 1])
        return float(touch) / DEG, psi, float(s1[-1]) / MM, float(k.ds1[0].min())

    def penalised(y: NDArray) -> float:
        if np.any(y < lo) or np.any(y > hi):
            return 1e3
        touch, psi, travel, slope = kinematics(y)
        off = abs(travel - c.rod_travel_mm) - c.rod_travel_tolerance_mm
        return min(touch, 1e3) + 50 * (max(psi - limit, 0) + max(off, 0)) + 1e4 * max(-slope, 0)

    law = np.asarray(minimize(penalised, start, method="Nelder-Mead",
                              options={"maxiter": 8000, "xatol": 1e-9, "fatol": 1e-7}).x)
    touch, psi, travel, _ = kinematics(law)
    return law, {"touch_deg": touch, "pressure_angle_deg": psi, "rod_travel_mm": travel}


def main() -> None:
    ap = argparse.ArgumentParser(description=(__doc__ or "").split("\n\n")[0])
    ap.add_argument("--config", type=Path, default=CONFIG)
    ap.add_argument("--set-index", type=int, default=0,
                    help="the coulomb form's set: 0 its fit, 1.. the band's others")
    ap.add_argument("--k-min", type=float, default=0.0, help="least K = k1 + k2, N/mm")
    ap.add_argument("--rise", type=float, default=0.25,
                    help="the friction's rise over the life (the config's is replaced)")
    ap.add_argument("--earliest", action="store_true",
                    help="search the earliest touch from each archive's law (or the "
                    "config's vendor law without archives)")
    ap.add_argument("archives", nargs="*", type=Path)
    args = ap.parse_args()
    config = cast(VcbConfig, load(args.config).case)
    problem = VcbProblem(config.model_copy(update={"life_friction_rise": args.rise}))
    sp, torque = set_space(problem, args.set_index, args.k_min * 1e3)
    print(f"{args.config.name}, end of life +{sp.rise:.1%} friction, -{sp.relax:.0%} "
          f"springs; coulomb set {args.set_index}: T = {torque:.4f} N m; "
          f"springs' extension {sp.e_0 / MM:.3f} mm at the pick-up, {sp.e_end / MM:.3f} mm "
          f"at the latch; rate at the pick-up {sp.rate_max / MM:.3f} mm/rad; extension at "
          f"the earliest release {sp.e_min / MM:.3f} mm; V_r(gap) <= {sp.v_gap:.3f} J, "
          f"V_r(17.8 mm) - V_r(gap) >= {sp.dv_after:.3f} J; K >= {args.k_min:g} N/mm")
    angles = np.arange(10.0, 131.0, 10.0)
    e_t = problem.model.closing_spring_geometry(angles * DEG)[0]
    print("least kinetic energy at the touch as built (J) by friction scale s (rows) and "
          "touch angle (deg):")
    print("   s   " + "".join(f"{a:7.0f}" for a in angles))
    for s in (0.75, 0.9, 1.0, 1.1, 1.2, 1.25):
        need = least_touch_energy(sp, torque, np.full(angles.size, s), angles * DEG, e_t)
        print(f"  {s:4.2f} " + "".join(f"{v:7.2f}" for v in need))
    for path in args.archives:
        import h5py

        with h5py.File(path, "r") as f:
            x = np.asarray(f["best/x"][()], dtype=float)
        X = (x / np.array([v.scale for v in problem.variables]))[None, :]
        st = touch_state(problem, X, args.set_index)
        one = np.ones(1)
        bound = latch_bound(sp, torque, one, st["theta_t"], st["e_t"], st["ke_t"])
        need = least_touch_energy(sp, torque, one, st["theta_t"], st["e_t"])
        print(f"{path.name}: touch at {st['theta_t'][0] / DEG:.2f} deg, kinetic energy "
              f"{st['ke_t'][0]:.3f} J (the cam's {st['ke_cam'][0]:.3f} J), velocity "
              f"{st['v_avg'][0]:.4f} m/s (touch {st['v_t'][0]:.4f} m/s); at the end of "
              f"life release {st['release_end'][0]:.4f}, latch {st['latch_end'][0]:.3f} J "
              f"<= bound {bound[0]:.3f} J; need {need[0]:.3f} J at this touch")
        if args.earliest:
            report_earliest(problem, sp, torque, X[0, [0, 1, 2, 5, 6]])
    if args.earliest and not args.archives:
        report_earliest(problem, sp, torque, problem.vendor_x()[[0, 1, 2, 5, 6]])


def report_earliest(problem: VcbProblem, sp: Space, torque: float, start: NDArray) -> None:
    """Print :func:`earliest_touch` from ``start`` and the need there."""
    law, found = earliest_touch(problem, start)
    theta = np.array([found["touch_deg"] * DEG])
    e_t = problem.model.closing_spring_geometry(theta)[0]
    need = [float(least_touch_energy(sp, torque, np.array([s]), theta, e_t)[0])
            for s in (1.0, 1.2, 1.25)]
    print(f"  earliest touch from a1..a5 = {np.round(start, 5).tolist()}: "
          f"{found['touch_deg']:.2f} deg at a1..a5 = {np.round(law, 5).tolist()} (pressure "
          f"angle {found['pressure_angle_deg']:.2f} deg, rod travel "
          f"{found['rod_travel_mm']:.3f} mm); need there {need[0]:.2f}, {need[1]:.2f}, "
          f"{need[2]:.2f} J at s = 1.0, 1.2, 1.25")


if __name__ == "__main__":
    main()
