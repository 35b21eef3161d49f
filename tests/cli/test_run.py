"""``camopt run`` as scripts use it: --quiet prints exactly the path, the archive records
the config as run, Ctrl-C keeps the finished repeats."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time

import h5py
import numpy as np
import tomllib
from typer.testing import CliRunner

from camopt import archive
from camopt.cli import app
from tests.conftest import CONFIGS

CAMOPT = [sys.executable, "-m", "camopt"]
PP3 = str(CONFIGS / "opening_spring_pp3.toml")
runner = CliRunner()


def test_quiet_prints_exactly_the_long_path_at_80_columns(tmp_path):
    folder = tmp_path / ("d" * 60) / ("e" * 60)
    folder.mkdir(parents=True)
    out = folder / "run.h5"
    env = {**os.environ, "COLUMNS": "80"}
    proc = subprocess.run([*CAMOPT, "run", PP3, "--quiet", "--out", str(out)], env=env,
                          capture_output=True, text=True, timeout=120)
    assert proc.returncode == 0, proc.stderr
    assert len(str(out)) > 80 and proc.stdout == f"{out}\n"  # one line, not wrapped
    shown = subprocess.run([*CAMOPT, "show", proc.stdout.strip()], env=env,
                           capture_output=True, text=True, timeout=120)
    assert shown.returncode == 0 and "best design" in shown.stdout


def test_archive_holds_the_config_as_run(tmp_path):
    out = tmp_path / "a.h5"
    r = runner.invoke(app, ["run", PP3, "--quiet", "--out", str(out), "--seed", "7",
                            "--repeats", "2", "--set", "solver.starts=4"])
    assert r.exit_code == 0, r.output
    with h5py.File(out, "r") as f:
        as_run = tomllib.loads(f.attrs["config_as_run"])
        effective = json.loads(f.attrs["config_effective"])
        seeds = f["summary/seed"][()]
        assert f["summary/repeat"].dtype == np.int64
    assert as_run["run"]["seed"] == 7 and as_run["run"]["repeats"] == 2
    assert as_run["solver"]["starts"] == 4 and effective["run"]["seed"] == 7
    view = archive.load_run(out)
    assert seeds.dtype == np.int64 and seeds.tolist() == [r.seed for r in view.repeats]
    # the TOML as run runs again, giving the same best design
    again = tmp_path / "again.toml"
    with h5py.File(out, "r") as f:
        again.write_text(f.attrs["config_as_run"])
    r = runner.invoke(app, ["run", str(again), "--quiet", "--out", str(tmp_path / "b.h5")])
    assert r.exit_code == 0, r.output
    assert archive.load_run(tmp_path / "b.h5").best.x == view.best.x


def test_best_x_is_stored_in_the_units_of_its_names(tmp_path):
    out = tmp_path / "a.h5"
    assert runner.invoke(app, ["run", PP3, "--quiet", "--out", str(out)]).exit_code == 0
    view = archive.load_run(out)
    with h5py.File(out, "r") as f:
        names = json.loads(f.attrs["variables"])
        stored = dict(zip(names, f["best/x"][()].tolist()))
        assert int(f.attrs["schema_version"]) == 2
    assert stored == view.best.x
    # Table 1 of Ahn et al.: k about 26 N/mm (stored as 26, not 26 000 N/m)
    assert 10.0 < stored["k_n_per_mm"] < 60.0


# camopt run with every finished repeat recorded as a line in FINISHED (a journal of the
# run's repeats, which a run keeps only in memory)
RECORDING_RUN = """\
import os, sys
from camopt.engine import driver
_run_repeat = driver.run_repeat
def run_repeat(*args, **kwargs):
    record = _run_repeat(*args, **kwargs)
    with open(os.environ["FINISHED"], "a") as journal:
        journal.write(f"{record.index}\\n")
    return record
driver.run_repeat = run_repeat
from camopt.cli import main
sys.argv[0] = "camopt"
main()
"""


def test_ctrl_c_keeps_the_finished_repeats(tmp_path):
    """Ctrl-C sent on an observed event, not after a sleep: once the journal holds two
    finished repeats (the first is then surely among the run's records; a repeat's line
    is written just before the run takes its record). A fixed 2 s sleep failed at a load
    of 9-13 when no repeat had finished yet."""
    out, finished = tmp_path / "a.h5", tmp_path / "finished"
    proc = subprocess.Popen([sys.executable, "-c", RECORDING_RUN, "run", PP3, "--out",
                             str(out), "--quiet", "--set", "solver.starts=2",
                             "--repeats", "5000"],
                            env={**os.environ, "FINISHED": str(finished)},
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    deadline = time.monotonic() + 120
    while not (finished.exists() and finished.read_text().count("\n") >= 2):
        assert time.monotonic() < deadline and proc.poll() is None, "no repeat finished"
        time.sleep(0.02)
    proc.send_signal(signal.SIGINT)
    stdout, stderr = proc.communicate(timeout=60)
    assert proc.returncode == 130, stderr
    assert stderr.startswith("error: interrupted; kept the ") and stderr.count("\n") == 1
    assert stdout == f"{out}\n"
    view = archive.load_run(out)
    assert view.interrupted and 1 <= view.repeats_done == len(view.repeats) < 5000
    assert view.run["repeats"] == 5000  # the config as run; the archive says how many finished
    assert [r.index for r in view.repeats] == list(range(len(view.repeats)))
    shown = runner.invoke(app, ["show", str(out)])
    assert shown.exit_code == 0 and "interrupted" in shown.stdout
