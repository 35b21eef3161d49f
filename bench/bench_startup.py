"""Start-up cost of the command line (issues #22, #36): CPU time (user + system, from
``resource.getrusage`` of the children) of ``camopt --version`` and of every command that
evaluates nothing (``validate``, ``show``, ``runs``, ``init``, ``solvers``, ``compare``)
against ``python -c "import numpy, scipy"``, medians of 7 interleaved rounds, in the same
run (target: each within 1.5x).

Archives: ``show``, ``runs`` and ``compare`` read a run archive this camopt writes first
(``camopt run configs/fast_switch.toml`` with two repeats, ~2 s), which stores its expected
yield (issue #34), and a copy of it: read as they are, nothing is evaluated. ``compare``
of two runs with repeats tests them (Mann-Whitney, Fisher's exact test: scipy.stats). An
older archive (tests/data/archives) has no stored yield, so ``show`` estimates it, which
evaluates the design 300 times: that is measured apart, ``show (older)``, without a target.

Bytecode: the children run with ``PYTHONPYCACHEPREFIX`` set to a temporary folder and
``PYTHONDONTWRITEBYTECODE`` unset, after one warm-up round, so camopt's modules load from
cached bytecode as they do for any installed copy (an editable checkout under
``PYTHONDONTWRITEBYTECODE=1`` compiles ~70 modules on every start: +0.15-0.35 s)."""

from __future__ import annotations

import os
import resource
import shutil
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

ROUNDS = 7
ROOT = Path(__file__).resolve().parent.parent
OLDER = ROOT / "tests" / "data" / "archives" / "run_main_52e31ad.h5"
CASE = ROOT / "configs" / "vcb_velocity.toml"
RUN = ROOT / "configs" / "fast_switch.toml"


def _cpu(args: list[str], env: dict[str, str]) -> float:
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    subprocess.run(args, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, check=True,
                   env=env, cwd=ROOT)
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    return after.ru_utime - before.ru_utime + after.ru_stime - before.ru_stime


def commands(folder: Path) -> dict[str, list[str]]:
    """What is measured: the base, then camopt's commands that evaluate nothing (on the
    archives :func:`write_archives` put in ``folder``), then ``show`` of an older archive."""
    camopt = [sys.executable, "-m", "camopt"]
    a, b = (str(folder / name) for name in ARCHIVES)
    return {
        "import numpy, scipy": [sys.executable, "-c", "import numpy, scipy"],
        "--version": [*camopt, "--version"],
        "--help": [*camopt, "--help"],
        "validate": [*camopt, "validate", str(CASE)],
        "show": [*camopt, "show", a],
        "runs": [*camopt, "runs", str(folder)],
        "compare": [*camopt, "compare", a, b],
        "init": [*camopt, "init", "vcb"],
        "solvers": [*camopt, "solvers"],
        "show (older)": [*camopt, "show", str(OLDER)],
    }


ARCHIVES = ("fs-a.h5", "fs-b.h5")
UNTARGETED = ("--help", "show (older)")


def write_archives(folder: Path, env: dict[str, str]) -> None:
    """A run archive of this camopt (two repeats of the fast switch) and a copy of it."""
    first, second = (folder / name for name in ARCHIVES)
    subprocess.run([sys.executable, "-m", "camopt", "run", str(RUN), "--out", str(first),
                    "--set", "run.repeats=2", "--quiet"], stdout=subprocess.DEVNULL,
                   check=True, env=env, cwd=ROOT)
    shutil.copy(first, second)


def measure(rounds: int = ROUNDS) -> dict[str, float]:
    """Median CPU seconds per command, rounds interleaved (load hits every command)."""
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp) / "runs"
        folder.mkdir()
        env = {k: v for k, v in os.environ.items() if k != "PYTHONDONTWRITEBYTECODE"}
        env["PYTHONPYCACHEPREFIX"] = str(Path(tmp) / "pycache")
        write_archives(folder, env)
        cmds = commands(folder)
        for args in cmds.values():  # warm-up: bytecode written, files in the page cache
            _cpu(args, env)
        times: dict[str, list[float]] = {name: [] for name in cmds}
        for _ in range(rounds):
            for name, args in cmds.items():
                times[name].append(_cpu(args, env))
    return {name: statistics.median(t) for name, t in times.items()}


def main() -> None:
    medians = measure()
    base = medians.pop("import numpy, scipy")
    print(f"python -c 'import numpy, scipy': {base:.3f} s CPU (median of {ROUNDS})")
    for name, cpu in medians.items():
        target = "" if name in UNTARGETED else " (target <= 1.5)"
        print(f"camopt {name:12s} {cpu:.3f} s CPU: ratio {cpu / base:.2f}{target}")


if __name__ == "__main__":
    main()
