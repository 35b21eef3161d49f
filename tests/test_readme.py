"""The README's commands run: its make targets exist, every camopt command it names is
one (with --help), every file it names exists, and the first hour's first steps run on
a small budget and end with a verdict and a next: line."""

from __future__ import annotations

import re
import shlex
import subprocess
import sys

import pytest

from tests.conftest import CONFIGS

ROOT = CONFIGS.parent
README = (ROOT / "README.md").read_text(encoding="utf-8")
BLOCKS = re.findall(r"```sh\n(.*?)```", README, re.S)
LINES = [line.split("#")[0].strip() for block in BLOCKS for line in block.splitlines()]
CAMOPT = [shlex.split(line.replace("|", " "))[1] for line in LINES
          if line.startswith("camopt ")]


def camopt(*args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, "-m", "camopt", *args], capture_output=True,
                          text=True, cwd=ROOT)


def test_readme_is_short_and_its_make_targets_exist():
    assert len(README.splitlines()) < 120
    for target in ("run", "test"):  # make -n: what the target would run, without running it
        r = subprocess.run(["make", "-n", target], capture_output=True, text=True, cwd=ROOT)
        assert r.returncode == 0, r.stderr


@pytest.mark.parametrize("command", sorted(set(CAMOPT)))
def test_every_command_it_names_exists(command):
    r = camopt(command, "--help")
    assert r.returncode == 0, (command, r.stderr)


def test_every_file_it_names_exists():
    named = set(re.findall(r"\b((?:configs|docs)/[\w./-]+\.(?:toml|md))", README))
    assert len(named) > 5
    for name in named:
        assert (ROOT / name).is_file(), name


@pytest.mark.slow
def test_the_first_hour_starts(tmp_path):
    """Steps 1 and 2 of the first hour (a small budget): run, then show; both end with
    the verdict and its next: step, which names the design case."""
    out = tmp_path / "vcb.h5"
    r = camopt("run", "configs/vcb.toml", "--out", str(out), "--repeats", "1", "--set",
               "solver.generations=10", "--set", "solver.population=20")
    assert r.returncode == 0, r.stderr
    lines = r.stdout.splitlines()
    assert len(lines) < 40, r.stdout  # the verdict does not scroll away
    for text in (r.stdout, camopt("show", str(out)).stdout):
        tail = " ".join(text.splitlines()[-8:])
        assert "verdict: FAIL" in tail and "next: camopt run configs/vcb_velocity.toml" in tail
