"""The metrics a VCB judgement reports beside its objective and constraints (display
units: mm, deg, MPa, ms): the factory setting's nut travel, the closing's values under
the identified parameters with their band over every parameter set, and, for tables and
reports, the cam's shape (pressure angle, curvature, normal force, output range); one
design's metrics as the archive stores them, and its analysis curves along the stroke
and against time."""

from __future__ import annotations

import numpy as np

from camopt.cases.vcb.band import BANDED, band_ends
from camopt.cases.vcb.constraints import Terms
from camopt.cases.vcb.dynamics import ClosingMotion
from camopt.cases.vcb.model import Loads, VcbModel, follower_dwell, row_max
from camopt.cases.vcb.setting import Setting
from camopt.core.problem import Evaluation
from camopt.mechanics import Floats, cam
from camopt.units import DEG, MM, MPA, TO_MS


def setting_metrics(setting: Setting) -> dict[str, Floats]:
    """The nut travel the factory setting needs (mm; +inf: none reaches the velocity):
    the set needing the most, and the form's fit."""
    return {"preload_setting_mm": setting.longest / MM,
            "preload_setting_fit_mm": setting.needed[0] / MM}


def motion_metrics(motion: ClosingMotion, q: Terms, latch_delay_ms: float | None
                   ) -> dict[str, Floats]:
    """The closing under the identified parameters (``motion``) and the band over the sets
    equally consistent with the ADAMS data (``dynamics_band``, ``q.spread``): every
    velocity and time, the latch's energy and margins. The analyser's closing time,
    command to touch, is ``latch_delay_ms`` + the touch time (where the case gives it)."""
    spread = q.spread
    closes = np.isfinite(spread.high["touch_time"])  # every set touches
    extras: dict[str, Floats] = {
        "closing_velocity_avg_m_s": motion.closing_velocity_avg,
        # undefined (NaN: "n/a, fails") where a set never brings the contacts together;
        # the constraints keep the band's finite stand-in (0 m/s) so a search among
        # stalling designs still sees how far it is
        "closing_velocity_low_m_s": np.where(closes, spread.velocity_low, np.nan),
        "closing_velocity_high_m_s": np.where(closes, spread.velocity_high, np.nan),
    }
    for name, (field, _, scale) in BANDED.items():
        extras[name] = getattr(motion, field) / scale
        low, high = band_ends(name)
        extras[low], extras[high] = spread.low[field] / scale, spread.high[field] / scale
    if latch_delay_ms is not None:
        for end in ("", "_low", "_high"):
            extras[f"closing_time{end}_ms"] = latch_delay_ms + extras[f"touch_time{end}_ms"]
    extras.update({
        "latch_kinetic_energy_j": motion.final_kinetic,
        "latch_kinetic_energy_low_j": spread.kinetic_low,
        "latch_kinetic_energy_high_j": spread.kinetic_high,
        "band_sets": np.full(len(spread.latched), spread.sets, dtype=float),
        "band_sets_not_latched": spread.not_latched.astype(float),
        "cam_torque_min_nm": q.cam_torque_min,
        "lift_off_torque_ratio": q.lift_off_ratio,
        "release_torque_margin": motion.release_torque_ratio,
        "release_torque_margin_low": spread.release_ratio_low,
        # the cam's blow on the resting roller, the band's worst (Hertz estimate)
        "pickup_tau_mpa": q.pickup_tau / MPA,
        "latched": spread.latched.astype(float),  # at every end of the band
    })
    return extras


def shape_metrics(q: Terms, A: Floats, torque: Floats, zeros: Floats
                  ) -> dict[str, Floats]:
    """The cam's shape for tables and reports: the law's coefficients, the largest
    pressure angle, the least convex radius, the largest normal force, the follower's
    dwell, Eq 39's sum and mean and the output's range. ``torque`` the closing springs'
    torque, ``zeros`` where phi' = 0 (:func:`~camopt.cases.vcb.model.rate_zeros`)."""
    m, c = q.model, q.config
    con = m.contact(q.kin.follower, torque)
    ends = m.output_angle(q.kin.ends()) / DEG
    dwell = follower_dwell(A, m.theta_c[-1], zeros) / DEG
    eq39 = m.abs_sum(q.bal)
    return {
        **{f"a{k}": A[:, k] for k in range(A.shape[1])},
        "pressure_angle_max_deg": q.psi_max,
        # the least radius of the convex part, where a roller can undercut (the profile
        # radius is rho_p - rf: a concave pitch curve gives < -rf, never an undercut,
        # whatever its size); inf for a wholly concave profile
        "curvature_min_mm": np.min(np.where(con.curvature > -m.rf, con.curvature, np.inf),
                                   axis=1) / MM,
        # unbounded where the follower dwells (Fn = T / arm, arm = 0 there)
        "normal_force_max_n": np.where(np.isfinite(dwell), np.inf,
                                       row_max(con.normal_force)),
        "follower_dwell_deg": dwell,
        "eq39_sum_n": eq39, "eq39_mean_n": eq39 / c.positions,
        "output_start_deg": ends[:, 0], "output_end_deg": ends[:, 1],
    }


def design_metrics(ev: Evaluation) -> dict[str, object]:
    """One design's metrics from its described evaluation (one row): every extra as a
    float, the output's start and end as its range (least, greatest), and feasibility
    (1.0 or 0.0)."""
    out: dict[str, object] = {k: float(v[0]) for k, v in ev.extras.items()}
    ends = [float(ev.extras[k][0]) for k in ("output_start_deg", "output_end_deg")]
    del out["output_start_deg"], out["output_end_deg"]
    out["output_range_deg"] = [min(ends), max(ends)]
    out["feasible"] = float(ev.feasible[0])
    return out


def stroke_curves(m: VcbModel, A: Floats, kc: Floats, link: Floats, rod_offset: float,
                  load: Loads, pre: Floats | None) -> dict[str, Floats]:
    """Analysis curves of one design (law ``A``, spring rates ``kc``, linkage ``link``,
    one row each; closing-spring compressions ``pre`` where set) along the closing stroke,
    display units: the cam's pitch curve and profile, the follower and pressure angles,
    curvature, normal force and contact stresses, the output angle and rod travel, the
    output and resisting forces (Eq 39's terms) and the driving and resisting works."""
    kin = m.kinematics(A, link, rod_offset)
    torque = m.closing_torque(kc, pre=pre)
    bal = m.balance(kin, kc, torque, load, pre)
    con = m.contact(kin.follower, torque)
    xc, yc = cam.profile(con.xp, con.yp, con.dxp, con.dyp, m.rf)
    return {
        "cam_angle_deg": m.theta_c / DEG,
        "pitch_x_mm": con.xp[0] / MM, "pitch_y_mm": con.yp[0] / MM,
        "profile_x_mm": xc[0] / MM, "profile_y_mm": yc[0] / MM,
        "follower_angle_deg": kin.follower.phi[0] / DEG,
        "pressure_angle_deg": cam.pressure_angle(m.l2, m.l6, kin.follower)[0] / DEG,
        "curvature_mm": con.curvature[0] / MM,
        "normal_force_n": con.normal_force[0],
        "sigma_max_mpa": con.sigma[0] / MPA, "tau_max_mpa": con.tau[0] / MPA,
        "output_angle_deg": m.output_angle(kin)[0] / DEG,
        "rod_travel_mm": kin.s1[0] / MM,
        "fo_n": np.r_[np.nan, m.output_force(bal)[0]], "fr_n": np.r_[np.nan, bal.fr[0]],
        # works along the stroke as exact potential differences
        "driving_work_j": m.closing_energy(kc, m.spring_ext, pre)[0, 0]
        - m.closing_energy(kc, m.spring_ext, pre)[0],
        "resistant_work_j": load.resistant_energy(kin.s1[0]),
    }


def motion_curves(mo: ClosingMotion) -> dict[str, Floats]:
    """The closing of one design (the first row of ``mo``) against time, display units,
    where its time is defined."""
    shown = np.isfinite(mo.time[0])
    return {
        "time_ms": mo.time[0, shown] * TO_MS,
        "dyn_cam_angle_deg": mo.theta_c[shown] / DEG,
        "dyn_rod_travel_mm": mo.rod[0, shown] / MM,
        "dyn_rod_velocity_m_s": mo.rod_velocity[0, shown],
        "dyn_contact_travel_mm": mo.contact[0, shown] / MM,
        "dyn_contact_velocity_m_s": mo.contact_velocity[0, shown],
        "dyn_cam_torque_nm": mo.cam_torque[0, shown],
    }
