"""What the release at the end of life asks of a VCB's closing springs, and what it leaves
at the latch: the numbers of docs/tolerance.md ("Adjustments at assembly and the end of
life", "No bound from the release at the end of life").

A breaker of friction scale s (as built) whose release passes at the end of its life
(eps T_s >= 1.2 x (1 + rise) s T_f in every set, the springs' compressions x (1 - relax),
the nut held) has, as built, a force F at the release of at least
(1.2 (1 + rise) s max(T_f / eps) / rate_max - relax K |ext|) / (1 - relax), rate_max the
springs' rate at the latest release the latch's space allows. Linear springs then give
the cam, from the meeting of the roller (theta_c = 0) to the latch (theta_end), at
least eps ((F - K dL_free) dL - K dL^2 / 2), dL the springs' extension over that stroke
and dL_free the free rotation's. With the resistant springs' potential V_r at the end of
the rod's travel and the friction's work s T_f theta_end, the kinetic energy at the latch
(as built) is at least

    E(s) = eps ((F(s) - K dL_free) dL - K dL^2 / 2) - V_r - s T_f theta_end - L_touch

(the cam's energy at the meeting >= 0; L_touch >= 0 the contacts' impact, left out, so
E(s) is larger than what the model's lower bound is). Printed per model form for the
stiffest springs the space allows (K = 2 x ``kc_max``, where K dL^2 / 2 is largest) and
the softest, the least over the form's sets where the least is the safe side. If E(s)
exceeded the latch's upper window (``latch_energy_max_j``) on part of the friction range,
no design could pass there: a bound. The test
tests/cases/test_vcb_life.py checks the force and work inequalities against the model.

    python scripts/vcb_life_release_work.py [CONFIG] [KC_MIN_N_PER_MM] [KC_MAX_N_PER_MM]
"""

from __future__ import annotations

import sys
from pathlib import Path
from typing import cast

import numpy as np

from camopt.cases.vcb.config import VcbConfig
from camopt.cases.vcb.problem import VcbProblem
from camopt.engine.driver import load
from camopt.units import DEG, MM

CONFIG = Path(__file__).resolve().parents[1] / "configs" / "vcb_velocity_serviced.toml"
EARLIEST_RELEASE_DEG = 14.0 - 2.33
"""The earliest release: the latch's lower bound with the band's sets 2.33 deg before it
(the longest free rotation)."""
LATEST_RELEASE_DEG = 23.03
"""The latest release past the dead centre: the fit's latch at its 20.70 deg cap plus the
band's sets' 2.33 deg (docs/tolerance.md, "The latch's seat is capped by the crank's
phase")."""
THETA_END_DEG = 140.0
"""The cam's stroke from the roller's pick-up to the latch."""


def main(config_path: Path = CONFIG, kc_min: float = 2.0, kc_max: float = 20.0) -> None:
    c = cast(VcbConfig, load(config_path).case)
    problem = VcbProblem(c)
    m = problem.model
    rise, relax = 0.25, c.life_spring_relaxation or 0.03
    release = m.dead_centre + LATEST_RELEASE_DEG * DEG - m.contact_crank_angle
    ext, rate = m.closing_spring_geometry(np.array([release, 0.0, THETA_END_DEG * DEG]))
    rate_max = float(rate[0])
    lows = m.closing_spring_geometry(np.linspace(-30 * DEG, release, 400))[1]
    assert float(lows.max()) <= rate_max * (1 + 1e-12), "the rate must rise to the release"
    earliest = m.dead_centre + EARLIEST_RELEASE_DEG * DEG - m.contact_crank_angle
    free = m.closing_spring_geometry(np.linspace(earliest, 0.0, 400))[0]
    d_free, d_l = ext[1] - float(free.min()), ext[2] - ext[1]
    travel = (c.rod_travel_mm - c.rod_travel_tolerance_mm) * MM
    v_r = float(problem.load.resistant_energy(np.array([travel]))[0])
    theta_end = THETA_END_DEG * DEG
    print(f"{config_path.name}: rate at the latest release ({LATEST_RELEASE_DEG} deg) "
          f"{rate_max / MM:.3f} mm/rad, springs' extension pick-up to latch "
          f"{d_l / MM:.2f} mm, free rotation at most {d_free / MM:.2f} mm; resistant "
          f"springs at {travel / MM:.1f} mm of rod travel {v_r:.2f} J; end of life: "
          f"friction +{rise:.0%}, springs -{relax:.0%}")
    for form in problem.forms:
        sets = [s.columns(np.size(s.cam_kg_m2), c.efficiency)
                for s in [form.nominal] + ([] if form.members is None else [form.members])]
        t_rel_eps = max(float(np.max(np.ravel(s.release_friction_nm) / np.ravel(s.efficiency)))
                        for s in sets)
        t_f = min(float(np.min(np.ravel(s.friction_nm))) for s in sets)
        t_f_max = max(float(np.max(np.ravel(s.friction_nm))) for s in sets)
        eps = min(float(np.min(np.ravel(s.efficiency))) for s in sets)
        for kc in (kc_min, kc_max):
            k = 2 * kc * 1e3
            per_s = 1.2 * (1 + rise) * t_rel_eps / rate_max / (1 - relax)
            offset = relax * k * abs(ext[0]) / (1 - relax)
            work_s = eps * per_s * d_l
            work_0 = eps * (-offset * d_l - k * d_free * d_l - k * d_l ** 2 / 2)
            slope = work_s - t_f_max * theta_end
            least = [slope * s + work_0 - v_r for s in (0.75, 1.0, 1.25)]
            print(f"  {form.name}, K {2 * kc:g} N/mm: force at the release >= {per_s:.0f} s"
                  f" N; springs' work >= {work_s:.1f} s {work_0:+.1f} J; friction "
                  f"{t_f:.2f}-{t_f_max:.2f} N m x {THETA_END_DEG:g} deg; latch energy >= "
                  f"{slope:.1f} s {work_0 - v_r:+.1f} J: "
                  + ", ".join(f"{e:.1f} J at s = {s}" for e, s in zip(least, (0.75, 1.0, 1.25))))


if __name__ == "__main__":
    args = sys.argv[1:]
    main(Path(args[0]) if args else CONFIG, *(float(a) for a in args[1:3]))
