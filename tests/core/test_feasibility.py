"""One feasibility rule (issue #34, docs/design.md "Feasibility"): requirements, the run's
constraints, success and ``sweep --check`` judge a design alike.

The rule: a quantity meets its limit when it lies beyond it by at most FEASIBILITY_TOL
times its scale; a normalised constraint has scale 1. A requirement that mirrors a
constraint (its margin is the constraint's -g times a constant c) must therefore have a
scale of at least c, or a design the constraints call feasible fails the verdict on
round-off (fast_switch_de, seed 3: "-9.99923e-08 %" against a feasible run).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

from camopt.cases import build_problem, get_case
from camopt.cli import app
from camopt.core.problem import FEASIBILITY_TOL
from camopt.core.requirements import Requirement
from camopt.core.runview import record_view
from tests.conftest import CONFIGS
from tests.helpers import load

SHIPPED = sorted(CONFIGS.glob("*.toml")) + sorted((CONFIGS / "reference").glob("*.toml"))
DRAWS = 64
"""Random designs per shipped config: enough for a mirrored pair to show on a quarter of
them, cheap even for the VCB's dynamics (one vectorised describe call)."""


def mirrors(margin: np.ndarray, g: np.ndarray) -> float | None:
    """The constant c with margin = -c g on at least a quarter of the designs where both
    are finite and g is clear of 0 (the same quantity, as a requirement and as a
    normalised constraint), else None."""
    ok = np.isfinite(margin) & np.isfinite(g) & (np.abs(g) > 1e-6)
    if ok.sum() < 8:
        return None
    ratio = -margin[ok] / g[ok]
    rounded = np.array([float(f"{r:.6g}") for r in ratio])
    values, counts = np.unique(rounded, return_counts=True)
    best = int(np.argmax(counts))
    if counts[best] < max(8, ok.sum() // 4) or values[best] <= 0:
        return None
    # a quantity that moves with the designs: two constant columns have a constant ratio
    matched = margin[ok][rounded == values[best]]
    if np.unique(np.round(matched, 9)).size < 8:
        return None
    return float(values[best])


@pytest.mark.parametrize("path", SHIPPED, ids=lambda p: p.name)
def test_no_requirement_is_stricter_than_the_constraint_it_mirrors(path: Path):
    config = load(path)
    with np.errstate(all="ignore"):
        problem = build_problem(config.case)
        X = problem.sample(np.random.default_rng(np.random.SeedSequence(34)), DRAWS)
        ev = problem.describe(X)
    spec = get_case(config.case.kind)
    values = {**{k: np.asarray(v, dtype=float) for k, v in ev.extras.items()},
              **{n: X[:, i] * problem.scale[i] for i, n in enumerate(problem.names)}}
    case = {"kind": config.case.kind, **config.effective()["case"]}
    reqs = spec.requirements(case, set(values)) if spec.requirements else ()
    found = 0
    for r in reqs:
        if r.flag or r.quantity not in values:
            continue
        with np.errstate(invalid="ignore"):
            margin = r.margin(values[r.quantity])
        for j, name in enumerate(problem.constraint_names):
            c = mirrors(margin, np.asarray(ev.g[:, j], dtype=float))
            if c is None:
                continue
            found += 1
            assert r.tol_scale >= c * (1 - 1e-6), (
                f"{path.name}: requirement '{r.name}' mirrors constraint {name} (margin = "
                f"-{c:g} g) but passes only within {FEASIBILITY_TOL:g} x {r.tol_scale:g}: "
                f"set its scale to {c:g}")
    if config.case.kind == "fast_switch":
        assert found >= 1  # R14/R15 against the spring's stress margin, at least


def test_the_rule_is_the_printed_resolution():
    """A requirement passes within half its resolution (one unit of the 6th significant
    digit of its scale) beyond its limit and fails beyond it; that is looser than the
    run's FEASIBILITY_TOL, so a constraint that holds never fails its requirement."""
    stress = Requirement("stress margin", "m_pct", "%", lower=0.0, scale=100.0)
    assert stress.resolution == pytest.approx(1e-3)  # 100 %: 6 digits, 0.001 %
    assert bool(stress.passes(-0.49e-3)) and not bool(stress.passes(-0.51e-3))
    assert bool(stress.passes(-2 * FEASIBILITY_TOL * 100))  # a constraint's round-off
    angle = Requirement("angle", "t_deg", "deg", upper=30.0)  # scale: the limit, 30
    assert angle.tol_scale == 30.0 and angle.resolution == pytest.approx(1e-4)
    assert bool(angle.passes(30.0 + 0.49e-4)) and not bool(angle.passes(30.0 + 0.51e-4))
    count = Requirement("sets", "n", upper=0.0, count=True)
    assert bool(count.passes(0.0)) and not bool(count.passes(1.0))
    assert not count.at_limit(0.0)  # 0 <= 0 is met exactly, never "at limit"


@pytest.mark.slow
def test_fast_switch_de_seed_3_verdict_feasibility_and_check_agree(tmp_path):
    """The issue's case: ``run configs/fast_switch_de.toml --repeats 10 --seed 3``. Its
    best design is feasible, a success, passes the verdict (at its limits, not FAIL), and
    ``sweep --check`` on the best repeat's seed (the same child of SeedSequence(3))
    passes with the same objective, bit for bit (the same computation)."""
    from camopt.engine.driver import execute
    from camopt.reporting import report

    record = execute(load(CONFIGS / "fast_switch_de.toml", "run.seed=3", "run.repeats=10"))
    view = record_view(record, str(tmp_path / "fs3.h5"))
    judged = report.verdict(view)
    assert view.best.feasible and record.best.success
    assert judged.verdict == "pass", judged.sentence
    assert all(c.passed for c in judged.checks)
    k = record.best.index
    out = tmp_path / "check.h5"
    r = CliRunner().invoke(app, ["sweep", str(CONFIGS / "fast_switch_de.toml"), "--set",
                                 "run.seed=3", "--set", "run.min_success_rate=1",
                                 "--seeds", f"{k}:{k + 1}", "--check", "--out", str(out),
                                 "--quiet", "--jobs", "1"])
    assert r.exit_code == 0, r.output
    doc = report.rank_sweep(*__import__("camopt.archive.sweeps", fromlist=["load_sweep"])
                            .load_sweep(out))
    assert doc.verdict.verdict == "pass"
    assert doc.ranking[0].row["best"] == record.best.fun
