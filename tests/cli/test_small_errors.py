"""Small errors a new user makes are one ``error:`` line that names the slip: a length in
cm, a spring rate in N/m, a mistyped --grid key or command; --help shows examples."""

from __future__ import annotations

import subprocess
import sys

import pytest

from tests.conftest import CONFIGS

VCB = str(CONFIGS / "vcb.toml")


def camopt(*args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, "-m", "camopt", *args], capture_output=True,
                          text=True)


@pytest.mark.parametrize(("override", "words"), [
    ("case.rb_mm=2.3", "centimetres typed? 23 mm"),     # each value alone is in range
    ("case.kc1_n_per_mm=7720", "N/m typed?"),
    ("case.kc2_n_per_mm=0.02", "kN/mm typed?"),
])
def test_typed_units_are_checked_against_each_other(override, words):
    r = camopt("validate", VCB, "--set", override)
    assert r.returncode == 2 and r.stdout == ""
    (line,) = r.stderr.splitlines()
    assert line.startswith("error: ") and words in line
    # the check is a plausibility check: run.check_plausibility = false accepts it
    ok = camopt("validate", VCB, "--set", override, "--set", "run.check_plausibility=false")
    assert ok.returncode == 0, ok.stderr


def test_a_grid_typo_is_blamed_on_the_option(tmp_path):
    r = camopt("sweep", str(CONFIGS / "fast_switch.toml"), "--seeds", "0:1", "--grid",
               "case.max_joint_load_n=abc", "--out", str(tmp_path / "s.h5"))
    assert r.returncode == 2
    assert r.stderr.startswith("error: --grid: case.max_joint_load_n: ")
    assert len(r.stderr.splitlines()) == 1 and not (tmp_path / "s.h5").exists()


def test_a_mistyped_command_gets_a_did_you_mean():
    r = camopt("verfy", VCB)
    assert r.returncode == 2
    assert r.stderr == ("error: camopt: verfy: unknown command; did you mean 'validate' or "
                        "'solvers'? (camopt --help)\n")
    assert "did you mean 'show'" in camopt("shwo", "x.h5").stderr


def test_help_has_examples():
    r = camopt("--help")
    assert r.returncode == 0 and "Examples:" in r.stdout and "camopt run configs/CASE.toml" \
        in r.stdout
