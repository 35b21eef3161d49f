"""Which breakers of one model form a VCB design can still pass at the end of its life: the
friction frontier of docs/tolerance.md ("Adjustments at assembly and the end of life").

Each draw of ``camopt tolerance`` is judged in one kept model form in turn (half the draws
in each of the two), and scales every set's friction torques (the cam's and the free
rotation's) by one factor s, uniform on 1 +- 0.25 in class ``standard``. A yield of 0.95
then needs at least 0.90 in each form, so breakers up to s = 1.20 in both.

For each form and each scale s given, this writes a case (configs/vcb_velocity.toml's law
and solver, the serviced practice's nut, base circle and velocity range, springs 2-20
N/mm each, +25 % friction and 3 % relaxation over the life, the 30 J buffer) whose band is
that form's sets of the shipped ``dynamics_band`` with their friction torques times s,
every other part nominal (the band's coupler set left out), and runs a nominal
``camopt run`` of it (CMA-ES, ``--repeats`` restarts): whether any design passes such a
breaker, as built and at the end of its life. Where none does it is where the search
stopped, not a bound: the other parts are held nominal, not at their most favourable.

    python scripts/vcb_life_form_frontier.py [--seed N] [--repeats N] [--set K=V ...]
        FORM:S [FORM:S ...]

FORM is ``coulomb`` or ``efficiency_coulomb``; e.g. ``coulomb:0.9 coulomb:1.0``; ``--set``
is passed to ``camopt run`` (another keying of the crank: ``case.preset_qox_deg=105``).
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
CASE = """extends = "{base}"
[case]
rb_mm = 42.0
latch_energy_max_j = 30.0
velocity_setting_bounds_m_s = [0.75, 1.05]
preload_setting_range_mm = 30.0
preload_setting_resolution_mm = 0.5
life_friction_rise = 0.25
life_spring_relaxation = 0.03
kc1_bounds_n_per_mm = [2.0, 20.0]
kc2_bounds_n_per_mm = [2.0, 20.0]
band_coupler_mass_kg = 0.0
dynamics_band = [{rows}]
[run]
name = "frontier_{form}_{scale}"
target = 0.0
"""


def form_rows(form: str, scale: float) -> list[list[float]]:
    """The shipped band's sets of ``form`` (efficiency 1: ``coulomb``; below 1:
    ``efficiency_coulomb``), their cam and free-rotation friction torques times ``scale``."""
    from camopt.cases.vcb.config import IDENTIFIED_BAND

    coulomb = form == "coulomb"
    return [[*r[:5], r[5] * scale, r[6] * scale, r[7]] for r in IDENTIFIED_BAND
            if (r[7] == 1.0) == coulomb]


def run(form: str, scale: float, seed: int, repeats: int, folder: Path,
        overrides: list[str]) -> dict:
    rows = ", ".join(json.dumps(r) for r in form_rows(form, scale))
    case = folder / f"{form}_{scale:g}.toml"
    case.write_text(CASE.format(base=ROOT / "configs" / "vcb_velocity.toml", rows=rows,
                                form=form, scale=f"{scale:g}"))
    out = folder / f"{form}_{scale:g}.h5"
    camopt = [sys.executable, "-m", "camopt"]
    subprocess.run([*camopt, "run", str(case), "--seed", str(seed), "--repeats",
                    str(repeats), "--out", str(out), "--quiet",
                    *(a for o in overrides for a in ("--set", o))], check=True,
                   stdout=subprocess.DEVNULL)
    shown = subprocess.run([*camopt, "show", str(out), "--format", "json"], check=True,
                           capture_output=True, text=True).stdout
    return json.loads(shown)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("cases", nargs="+", help="FORM:S, e.g. coulomb:1.0")
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--set", action="append", default=[], dest="overrides",
                        help="section.key=value, passed to camopt run")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        for item in args.cases:
            form, scale = item.split(":")
            try:
                doc = run(form, float(scale), args.seed, args.repeats, Path(tmp),
                          args.overrides)
            except subprocess.CalledProcessError as exc:  # camopt printed its error line
                sys.exit(exc.returncode)
            metrics = doc["best"]["metrics"]
            print(f"{form} x {float(scale):g} (seed {args.seed}, {args.repeats} repeats"
                  f"{''.join(', ' + o for o in args.overrides)}): "
                  f"{doc['verdict']}; release margin at the end of life "
                  f"{metrics['life_end_release_torque_margin_low']:.4f}, latch energy at "
                  f"the end of life {metrics['life_end_latch_kinetic_energy_low_j']:.2f} J; "
                  f"{doc['verdict_sentence']}")


if __name__ == "__main__":
    main()
