"""docs/tutorial-my-breaker.md: its shell blocks run as written (in a temporary copy of the
files they read), each exits 0, and each step's verdict is the one the tutorial promises."""

from __future__ import annotations

import json
import os
import re
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from tests.conftest import ROOT

TUTORIAL = ROOT / "docs" / "tutorial-my-breaker.md"


def blocks() -> list[str]:
    return re.findall(r"```sh\n(.*?)```", TUTORIAL.read_text(), flags=re.S)


def _json(cwd, env, *args):
    proc = subprocess.run([sys.executable, "-m", "camopt", *args, "--format", "json"],
                          cwd=cwd, env=env, capture_output=True, text=True, timeout=120)
    assert proc.returncode == 0, proc.stderr
    return json.loads(proc.stdout)


@pytest.mark.slow
def test_the_tutorial_runs_as_written(tmp_path):
    shutil.copytree(ROOT / "tests" / "data" / "curves", tmp_path / "tests" / "data" / "curves")
    env = {**os.environ, "PATH": f"{Path(sys.executable).parent}{os.pathsep}"
           f"{os.environ.get('PATH', '')}", "COLUMNS": "100"}
    found = blocks()
    assert len(found) == 6
    out = []
    for block in found:
        proc = subprocess.run(["bash", "-e", "-c", block], cwd=tmp_path, env=env,
                              capture_output=True, text=True, timeout=300)
        assert proc.returncode == 0, (block, proc.stderr)
        out.append(proc.stdout)
    init, validate, calibrate, design, tolerance, export = out
    assert "[case]" in (tmp_path / "my_breaker.toml").read_text()
    assert validate.startswith("ok: my_breaker.toml")  # step 2: the case as written is valid
    # step 3: the calibrated fragment carries the calibrated values and their band
    fragment = (tmp_path / "my_breaker_calibrated.toml").read_text()
    assert "release_offset_deg" in fragment and "dynamics_band" in fragment
    assert "explained by" in calibrate and "NOT EXPLAINED" not in calibrate  # "the verdict"
    assert "latch_delay_ms" in fragment
    # step 4: "It ends PASS at nominal", and show says so again
    assert "PASS at nominal" in design
    shown = _json(tmp_path, env, "show", "my_design.h5")
    assert shown["verdict"] == "pass", shown["verdict_sentence"]
    # step 5: "its yield is low (a few per cent here)": below a tenth
    assert "yield (feasible share)" in tolerance
    assert shown["expected_yield"]["value"] < 0.1
    # step 6: the drawing of that (passing) design
    drawing = (tmp_path / "my_cam" / "my_design.dxf").read_text()
    assert "NOT FOR RELEASE" not in drawing  # the design passes: a drawing to release
