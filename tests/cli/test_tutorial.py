"""docs/tutorial-my-breaker.md: its shell blocks run as written (in a temporary copy of the
files they read) and each exits 0."""

from __future__ import annotations

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


@pytest.mark.slow
def test_the_tutorial_runs_as_written(tmp_path):
    shutil.copytree(ROOT / "tests" / "data" / "curves", tmp_path / "tests" / "data" / "curves")
    env = {**os.environ, "PATH": f"{Path(sys.executable).parent}{os.pathsep}"
           f"{os.environ.get('PATH', '')}", "COLUMNS": "100"}
    found = blocks()
    assert len(found) == 6
    for block in found:
        proc = subprocess.run(["bash", "-e", "-c", block], cwd=tmp_path, env=env,
                              capture_output=True, text=True, timeout=300)
        assert proc.returncode == 0, (block, proc.stderr)
    assert "release_offset_deg" in (tmp_path / "my_breaker_calibrated.toml").read_text()
    assert (tmp_path / "my_cam" / "my_design.dxf").is_file()
