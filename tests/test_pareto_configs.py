"""The shipped fronts (configs/*_pareto.toml) beyond the EMB one
(tests/cases/test_emb_pareto.py): each run gives a front worth the name."""

from __future__ import annotations

import json

import numpy as np
import pytest
from typer.testing import CliRunner

from camopt.cli import app
from tests.conftest import CONFIGS

runner = CliRunner()


@pytest.mark.slow
@pytest.mark.parametrize(("config", "span"), [
    # tau (MPa, minimised) vs closing velocity (m/s, maximised): the identified friction
    # leaves ~0.03 m/s between the slowest design that latches and 1.1 m/s; >= 0.02 covered
    pytest.param("vcb_pareto.toml", 0.02, marks=pytest.mark.xfail(
        strict=True, reason="issue #31's margins (release torque >= 1.2 x friction, "
        "lift-off >= 5 % of the mean drive, the pick-up impact) leave vcb_pareto's search "
        "no feasible design, the latch and the quintic law as design variables too: it "
        "ends on lift-off (-5.1 % of the mean drive; docs/assumptions.md)")),
    # closure time (ms) vs spring stress margin (%): >= 50 % of margin covered
    ("fast_switch_pareto.toml", 50.0),
])
def test_front_is_feasible_non_dominated_and_spans_the_trade_off(tmp_path, config, span):
    out = tmp_path / "front.h5"
    r = runner.invoke(app, ["run", str(CONFIGS / config), "--out", str(out), "--quiet"])
    assert r.exit_code == 0, r.output
    doc = json.loads(runner.invoke(app, ["show", str(out), "--format", "json"]).stdout)
    names = doc["solver"]["objectives"]
    sign = np.array([-1.0 if n in doc["solver"]["maximise"] else 1.0 for n in names])
    F = np.unique([[p[n] for n in names] for p in doc["pareto"] if p["feasible"]], axis=0)
    assert len(F) >= 20
    M = F * sign
    dominated = ((M[None] <= M[:, None]).all(axis=2) & (M[None] < M[:, None]).any(axis=2))
    assert not dominated.any()
    assert np.ptp(F[:, 1]) >= span
    # a trade-off: the better the first objective, the worse the second
    order = np.argsort(M[:, 0])
    assert np.all(np.diff(M[order, 1]) <= 0)
