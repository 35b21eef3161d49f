"""The consoles: a closed pipe on stdout (``camopt show RUN | head -1``) ends camopt with
exit 0 and nothing on stderr, as a Unix filter does."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
ARCHIVE = str(ROOT / "tests" / "data" / "archives" / "run_main_52e31ad.h5")


def with_reader_gone(*args: str) -> subprocess.CompletedProcess[str]:
    """``camopt ARGS`` whose stdout is a pipe closed by its reader before camopt writes to
    it (the parent closes its only read end at once: every write then fails with EPIPE,
    whatever the timing, as ``| head -1`` does to all output after the first line)."""
    proc = subprocess.Popen([sys.executable, "-m", "camopt", *args], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True, cwd=ROOT)
    assert proc.stdout is not None and proc.stderr is not None
    proc.stdout.close()
    stderr = proc.stderr.read()
    proc.stderr.close()
    return subprocess.CompletedProcess(proc.args, proc.wait(timeout=60), "", stderr)


@pytest.mark.parametrize("args", [
    ("show", ARCHIVE),  # rich's tables (rich's own handler exited 1)
    ("show", ARCHIVE, "--format", "json"),  # sys.stdout.write inside the command
    ("runs", str(Path(ARCHIVE).parent)),
    ("--help",),  # typer's help
    ("solvers",),
])
def test_a_closed_pipe_on_stdout_ends_camopt_quietly_with_exit_0(args: tuple[str, ...]) -> None:
    done = with_reader_gone(*args)
    assert (done.returncode, done.stderr) == (0, ""), done


def test_the_probe_sees_a_failure_too() -> None:
    """The check can fail: a command that fails exits 2 with its error, reader or not."""
    done = with_reader_gone("show", str(ROOT / "no_such_archive.h5"))
    assert done.returncode == 2 and done.stderr.startswith("error: "), done
