"""Calibration on travel curves (issue #32), the full check behind the fast tests: the two
synthetic spring-set curves of tests/data/curves made again with several noise seeds and
with analyser spikes (1 % of the samples off by up to +-0.5 mm), each calibrated jointly:
every parameter's error against the independent ODE's truth, whether the truth is inside
its 95 % profile interval, a third design's closing velocity against the ODE's, and the
time per calibration (run from the repository root: ``python -m bench.bench_calibrate``)."""

from __future__ import annotations

import time

import numpy as np

from camopt.cases.vcb.calibrate import CurveCase, calibrate
from camopt.cases.vcb.calibration_model import Design
from camopt.cases.vcb.curves import TravelCurve, noise_level
from camopt.cases.vcb.forms import get_form
from camopt.cases.vcb.problem import VcbProblem
from camopt.units import MM, MS, N_PER_MM
from tests.cases import vcb_ode
from tests.conftest import CONFIGS
from tests.helpers import load

SEEDS = (10, 11, 12)
THIRD = (8.5, 8.5)  # kc1, kc2 N/mm: a design neither curve has


def _curve(t: np.ndarray, s: np.ndarray, name: str) -> TravelCurve:
    return TravelCurve(name, t, s, noise_level(s))


def main() -> None:
    problem = VcbProblem(load(CONFIGS / "vcb.toml").case)
    truth = {"cam_inertia_kg_m2": vcb_ode.TRUTH.cam_kg_m2, "rod_mass_kg": vcb_ode.TRUTH.rod_kg,
             "contacts_mass_kg": vcb_ode.TRUTH.contacts_kg,
             "release_offset_deg": vcb_ode.TRUTH.release_offset_deg,
             "cam_friction_nm": vcb_ode.TRUTH.friction_nm,
             "latch_delay_ms": vcb_ode.LATCH_DELAY_S / MS}
    rods = {name: vcb_ode.closing(problem, kc)[0] for name, kc in vcb_ode.SPRING_SETS.items()}
    _, _, v_third = vcb_ode.closing(problem, THIRD)
    designs = {name: Design(name, problem.model.vendor_a, np.array(kc) * N_PER_MM)
               for name, kc in {**vcb_ode.SPRING_SETS, "third": THIRD}.items()}
    inside = total = 0
    for seed in SEEDS:
        for spikes in (False, True):
            curves = []
            for k, (name, rod) in enumerate(rods.items()):
                t, s = vcb_ode.sample(rod, seed=100 * seed + k)
                if spikes:
                    rng = np.random.default_rng(seed)
                    hit = rng.random(t.size) < 0.01
                    s = s + hit * rng.uniform(-0.5e-3, 0.5e-3, t.size)
                curves.append(CurveCase(_curve(t, s, name), designs[name]))
            t0 = time.perf_counter()
            (fit,) = calibrate(problem.config, curves, [get_form("efficiency_coulomb")],
                               [designs["third"]])
            wall = time.perf_counter() - t0
            errors = []
            for p in fit.parameters:
                total += 1
                inside += p.low <= truth[p.name] <= p.high
                errors.append(f"{p.name.split('_')[0]} {100 * (p.value / truth[p.name] - 1):+.1f}%"
                              f"{'' if p.identified else '(n.i.)'}")
            (pred,) = fit.predictions
            print(f"seed {seed} spikes {spikes!s:5}: rms {fit.rms / MM:.4f} mm, "
                  f"{', '.join(errors)}; third design v {pred.closing_velocity:.4f} vs ODE "
                  f"{v_third:.4f} ({100 * (pred.closing_velocity / v_third - 1):+.2f} %), "
                  f"{wall:.1f} s")
    print(f"truth inside the 95 % interval: {inside} of {total}")


if __name__ == "__main__":
    main()
