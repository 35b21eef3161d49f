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
    # tau (MPa) vs closing velocity (m/s), both minimised: on the feasible set the least
    # stress falls as the velocity rises, from ~357 MPa at 0.90 m/s (none found feasible at
    # 0.85) to ~295 MPa at the 1.10 m/s cap (docs/assumptions.md), a front 0.2 m/s
    # wide; the config's 20,000 evaluations cover 0.077-0.159 m/s of it over seeds 0-8 and
    # 2023 (0.140 at 2023): >= 0.05 m/s, a quarter of the physics' span, covered
    ("vcb_pareto.toml", 0.05),
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
