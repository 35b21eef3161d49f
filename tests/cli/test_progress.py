"""``camopt run``'s progress: measured on the binding budget, with the time left and the
best feasible value (or the worst constraint); plain lines when stderr is no terminal."""

from __future__ import annotations

from typer.testing import CliRunner

from camopt.cli import app
from camopt.cli.app import load_commands
from camopt.engine.driver import Progress
from tests.conftest import CONFIGS

load_commands()  # the command modules import each other once the app has them all
from camopt.cli import run as run_cli  # noqa: E402


def test_the_binding_budget_sets_the_share_done():
    # cmaes: 100000 generations allowed, 30000 evaluations: the evaluations bind
    p = Progress(1, 4, 50, 100_000, 0.5, "objective_j", nfev=15_000, max_nfev=30_000)
    assert p.fraction == 0.5
    line = run_cli.progress_line(p, elapsed=60.0)  # (1 + 0.5) / 4 done in 60 s
    assert line.startswith("repeat 2/4: 38 % of the budget, about 2 min left")
    assert line.endswith("best objective_j 0.5")
    seconds = Progress(0, 1, 3, 1000, 1.0, max_seconds=10.0, elapsed_s=9.0)
    assert seconds.fraction == 0.9  # a wall-time limit nearer its end than the iterations
    bad = Progress(0, 1, 3, 10, 1e9, feasible=False, worst="rod_travel")
    assert bad.best_text == "infeasible, worst: rod_travel"


def test_without_a_terminal_plain_lines_go_to_stderr(tmp_path, monkeypatch):
    monkeypatch.setattr(run_cli, "PLAIN_EVERY_S", 0.0)  # every iteration, not every minute
    r = CliRunner().invoke(app, ["run", str(CONFIGS / "fast_switch_de.toml"), "--out",
                                 str(tmp_path / "a.h5"), "--repeats", "1", "--set",
                                 "solver.generations=3", "--set", "solver.population=10"])
    assert r.exit_code == 0, r.output
    lines = [x for x in r.stderr.splitlines() if x.startswith("camopt run: ")]
    assert len(lines) >= 3, r.stderr
    assert "% of the budget" in lines[-1] and ("best " in lines[-1] or "worst: " in lines[-1])
    assert any(x.startswith("next: ") for x in r.stdout.splitlines()[-5:])
