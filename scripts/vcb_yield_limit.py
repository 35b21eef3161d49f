"""How much of a friction tolerance a VCB design can pass (issue #33).

Every draw of `camopt tolerance` scales the cam shaft's Coulomb friction torque by a
factor s, uniform on 1 +- w (the case's tolerance class: w = 0.25 in ``standard`` and
``graded``). With every other input of a draw held, the draw passes a requirement only for
the s in some set; its length over 2 w is the most of that draw's friction range the
requirement can pass, and the yield over the draws is at most the largest such share.

The bound from the equations (docs/tolerance.md, "VCB: what the friction tolerance
leaves"; tests/cases/test_vcb_parts.py): while the cam latches, the energy left at the
latch falls with s by at least T_f theta_end m_rod / (m_rod + m_c) per unit s, so a latch
window of W joules passes at most W / (that x 2 w) of a uniform friction range, for any
design. The script prints it per form, and measures on ``DESIGNS`` designs drawn
uniformly within the search bounds of ``configs/vcb_velocity_robust.toml`` (``DRAWS``
draws each of the class's other inputs, ``GRID`` friction scales across 1 +- w, each kept
model form alone, one vectorised call per form) the largest share of the range that
passes the latch window [``latch_energy_min_j``, ``LATCH_MAX``] and the velocity window,
and the least slope of the weakest set's latch energy: the sample's, not bounds.

    python scripts/vcb_yield_limit.py [DESIGNS] [DRAWS] [SEED] [WIDTH] [LATCH_MAX]

``LATCH_MAX`` (J) replaces the config's ``latch_energy_max_j`` (30 J, its closing buffer):
5 gives the window of the contact springs' stop alone.
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

from camopt.cases.vcb import TOLERANCES
from camopt.cases.vcb.problem import VcbProblem
from camopt.core.variation import parse_vary
from camopt.engine.driver import load

CONFIG = Path(__file__).resolve().parents[1] / "configs" / "vcb_velocity_robust.toml"
GRID = 41


def _pass_share(ok: np.ndarray) -> np.ndarray:
    """Share of the grid (…, GRID) that passes, the ends counted half (trapezoid)."""
    weights = np.ones(ok.shape[-1])
    weights[[0, -1]] = 0.5
    return (ok * weights).sum(axis=-1) / weights.sum()


def main(designs: int = 200, draws: int = 10, seed: int = 20261127,
         width: float = 0.25, latch_max: float | None = None) -> None:
    config = load(CONFIG).case
    if latch_max is not None:
        config = config.model_copy(update={"latch_energy_max_j": latch_max})
    problem = VcbProblem(config)
    rng = np.random.default_rng(seed)
    lower = np.array([v.lower for v in problem.variables])
    upper = np.array([v.upper for v in problem.variables])
    X = lower + (upper - lower) * rng.random((designs, len(lower)))
    # the other inputs of the class, drawn around each design (variables) or the case
    fields: dict[str, np.ndarray] = {}
    names = [v.name for v in problem.variables]
    n = designs * draws
    Xd = np.repeat(X, draws, axis=0)
    for key, text in TOLERANCES.items():
        if key == "case.cam_friction_nm":
            continue
        vary = parse_vary("vcb", f"{key}={text}")
        u = rng.uniform(-1, 1, n)
        if key.startswith("case."):
            name = key.removeprefix("case.")
            if name not in problem.case_fields():
                continue
            nominal = float(getattr(config, name))
            fields[name] = nominal + vary.half_width(nominal) * u
        elif key in names:
            j = names.index(key)
            scale = problem.variables[j].scale
            shown = Xd[:, j] * scale
            half = np.array([vary.half_width(float(x)) for x in shown])
            Xd[:, j] = (shown + half * u) / scale
    scales = np.linspace(1 - width, 1 + width, GRID)
    rows = np.repeat(Xd, GRID, axis=0)
    grid_fields = {k: np.repeat(v, GRID) for k, v in fields.items()}
    grid_fields["cam_friction_nm"] = config.cam_friction_nm * np.tile(scales, n)
    lo_e, hi_e = config.latch_energy_min_j, config.latch_energy_max_j
    v_lo, v_hi = config.closing_velocity_m_s
    print(f"{designs} designs x {draws} draws of the other inputs, friction scale "
          f"1 +- {width} on {GRID} points; latch window [{lo_e}, {hi_e}] J, velocity "
          f"[{v_lo}, {v_hi}] m/s")
    theta_end = np.deg2rad(140.0)  # the cam's stroke from the pick-up to the latch
    for v, form in enumerate(problem.variants() or ("the case's",)):
        sets = [problem.forms[v].nominal] + ([] if problem.forms[v].members is None
                                             else [problem.forms[v].members])
        friction = min(float(np.min(np.ravel(s.friction_nm))) for s in sets)
        rod_share = min(float(np.min(np.ravel(s.rod_kg) / (np.ravel(s.rod_kg)
                                                          + np.ravel(s.contacts_kg))))
                        for s in sets)
        bound = friction * theta_end * rod_share
        print(f"form {form}: the equations' least slope T_f theta_end m_rod / (m_rod + "
              f"m_c) = {bound:.2f} J per unit s: a {hi_e - lo_e:g} J window passes at most "
              f"{min(1.0, (hi_e - lo_e) / (bound * 2 * width)):.3f} of the range, any design")
        ev = problem.describe_variants(rows, grid_fields, np.full(len(rows), v))
        e_low = ev.extras["latch_kinetic_energy_low_j"].reshape(n, GRID)
        e_high = ev.extras["latch_kinetic_energy_high_j"].reshape(n, GRID)
        vel_low = ev.extras["closing_velocity_low_m_s"].reshape(n, GRID)
        vel_high = ev.extras["closing_velocity_high_m_s"].reshape(n, GRID)
        latches = (e_low > 0).any(axis=1)
        latch_ok = (e_low >= lo_e) & (e_high <= hi_e)
        vel_ok = (vel_low >= v_lo) & (vel_high <= v_hi)
        slope = -np.diff(e_low, axis=1) / np.diff(scales)
        inside = (e_low[:, 1:] >= lo_e) & (e_low[:, :-1] <= hi_e)
        print(f"form {form}: {latches.sum()} of {n} draws latch somewhere on the grid")
        if latches.any():
            print(f"  latch window: at most {_pass_share(latch_ok[latches]).max():.3f} of the "
                  "friction range passes")
            print(f"  velocity window: at most {_pass_share(vel_ok[latches]).max():.3f}")
            print(f"  both: at most {_pass_share((latch_ok & vel_ok)[latches]).max():.3f}")
        if inside.any():
            least = float(slope[inside].min())
            print(f"  the least slope of the weakest set's latch energy in this sample: "
                  f"{least:.2f} J per unit s (the sample's, not a bound)")


if __name__ == "__main__":
    main(*(int(a) for a in sys.argv[1:4]), *(float(a) for a in sys.argv[4:6]))
