"""Start-up cost of the command line (issues #22, #36): CPU time (user + system, from
``resource.getrusage`` of the children) of ``camopt --version`` and of every command that
evaluates nothing (``validate``, ``show``, ``runs``, ``init``, ``solvers``, ``compare``)
against ``python -c "import numpy, scipy"``, medians of 7 interleaved rounds, in the same
run (targets: :data:`TARGETS`, the others within 1.5x).

Archives: ``show``, ``runs`` and ``compare`` read a run archive this camopt writes first
(``camopt run configs/fast_switch.toml`` with two repeats, ~2 s), which stores its expected
yield (issue #34), and a copy of it: read as they are, nothing is evaluated. ``compare``
of two runs with repeats tests them (Mann-Whitney, Fisher's exact test: scipy.stats). An
older archive (tests/data/archives) has no stored yield, so ``show`` estimates it, which
evaluates the design 300 times: that is measured apart, ``show (older)``, without a target.

Bytecode: the children run with ``PYTHONPYCACHEPREFIX`` set to a temporary folder and
``PYTHONDONTWRITEBYTECODE`` unset, after one warm-up round, so camopt's modules load from
cached bytecode as they do for any installed copy (an editable checkout under
``PYTHONDONTWRITEBYTECODE=1`` compiles ~70 modules on every start: +0.15-0.35 s).

Floors: what is not camopt's, each also a ratio to the base (issue #36). A bare typer app
of two commands (typer converts a command's parameters through pydantic: ~0.07 s of
it); the same app whose command imports what ``validate`` cannot start without (numpy,
the TOML reader, rich's console: its line is printed and wrapped by rich) and what
``show`` and ``runs`` cannot (h5py, rich's console and tables); ``import numpy, typer,
pydantic`` and ``import h5py``; each with BLAS told one thread as the command line tells it
(``camopt.core.perf.one_blas_thread_on_load``). The second and third are each command's
floor (and ``show``'s that of ``runs``): what is above them is camopt's.

Last, the first VCB evaluation after installing, with an empty numba cache against a
filled one (:func:`first_evaluation`): the compile the README states."""

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


def _cpu(args: list[str], env: dict[str, str], cwd: Path = ROOT) -> float:
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    subprocess.run(args, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, check=True,
                   env=env, cwd=cwd)
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    return after.ru_utime - before.ru_utime + after.ru_stime - before.ru_stime


BARE_TYPER = """import typer

app = typer.Typer()


@app.command()
def hello(name: str, count: int = 1) -> None:
    {imports}print(name * count)


@app.command()
def bye() -> None:
    print("bye")


app()
"""
"""The floor of any typer command line: two commands, one run with an argument
(``{imports}``: what the command imports before it prints, as a library floor)."""

COMMAND_LIBRARIES = {
    "typer app + numpy + tomllib + rich (validate's)": "numpy, tomllib, rich.console",
    "typer app + h5py + rich (show's)": "h5py, rich.console, rich.table",
}
"""Typer apps whose command imports the libraries a camopt command cannot start without
(typer itself imports pydantic to convert the command's parameters, so every floor app
holds it, as ``validate`` needs it): ``validate`` numpy, the TOML reader (its input is a
TOML file) and rich's console (its line is wrapped as rich wraps); ``show`` and ``runs``
h5py (their input is HDF5; it imports numpy), rich's console and tables; each with
camopt's own BLAS setting."""


def floors(folder: Path) -> dict[str, list[str]]:
    """What is not camopt's, measured beside it (:data:`BARE_TYPER`'s apps written to
    ``folder``)."""
    script = folder / "bare_typer.py"
    script.write_text(BARE_TYPER.format(imports=""))
    apps = {}
    for i, (name, libraries) in enumerate(COMMAND_LIBRARIES.items()):
        app = folder / f"typer_libraries_{i}.py"
        app.write_text(BARE_TYPER.format(imports=f"import {libraries}\n\n    "))
        apps[name] = [sys.executable, str(app), "hello", "x"]
    return {
        "bare typer app": [sys.executable, str(script), "hello", "x"],
        **apps,
        "import numpy, typer, pydantic": [sys.executable, "-c",
                                          "import numpy, typer, pydantic"],
        "import h5py": [sys.executable, "-c", "import h5py"],
    }


ONE_BLAS_THREAD = dict.fromkeys(("OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS",
                                 "BLIS_NUM_THREADS"), "1")
"""The floors' BLAS setting: the command line's (numpy then starts no thread per core)."""


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
UNTARGETED = ("show (older)",)
TARGETS = {
    "--help": ("import numpy, scipy", 1.3),
    "solvers": ("import numpy, scipy", 1.3),
    "validate": ("floor: typer app + numpy + tomllib + rich (validate's)", 1.2),
    "show": ("floor: typer app + h5py + rich (show's)", 1.2),
    "runs": ("floor: typer app + h5py + rich (show's)", 1.2),
}
"""Issue #48's targets: a command that reads no case against the base; ``validate`` and
``show`` against their own floor apps (the other commands: 1.5x the base, issue #36).
``runs`` reads archives as ``show`` does, so its floor is show's app: against the base it
could not meet 1.3x (the bare typer app alone is ~1.4x, ``import h5py`` ~1.1x)."""


def write_archives(folder: Path, env: dict[str, str]) -> None:
    """A run archive of this camopt (two repeats of the fast switch) and a copy of it."""
    first, second = (folder / name for name in ARCHIVES)
    subprocess.run([sys.executable, "-m", "camopt", "run", str(RUN), "--out", str(first),
                    "--set", "run.repeats=2", "--quiet"], stdout=subprocess.DEVNULL,
                   check=True, env=env, cwd=ROOT)
    shutil.copy(first, second)


def measure(rounds: int = ROUNDS, before: Path | None = None) -> dict[str, float]:
    """Median CPU seconds per command, rounds interleaved (load hits every command);
    ``before``: another checkout of camopt (an earlier commit) whose commands are measured
    in the same rounds, as ``before: NAME``."""
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp) / "runs"
        folder.mkdir()
        env = {k: v for k, v in os.environ.items() if k != "PYTHONDONTWRITEBYTECODE"}
        env["PYTHONPYCACHEPREFIX"] = str(Path(tmp) / "pycache")
        write_archives(folder, env)
        floor_env = {**env, **ONE_BLAS_THREAD}
        cmds = {**{f"floor: {name}": (args, floor_env, ROOT)
                   for name, args in floors(Path(tmp)).items()},
                **{name: (args, env, ROOT) for name, args in commands(folder).items()}}
        if before is not None:
            old = {**env, "PYTHONPATH": str(before)}
            cmds.update({f"before: {name}": (args, old, before)
                         for name, args in commands(folder).items() if args[1] == "-m"})
        for args, cmd_env, cwd in cmds.values():  # warm-up: bytecode written, page cache
            _cpu(args, cmd_env, cwd)
        times: dict[str, list[float]] = {name: [] for name in cmds}
        for _ in range(rounds):
            for name, (args, cmd_env, cwd) in cmds.items():
                times[name].append(_cpu(args, cmd_env, cwd))
    return {name: statistics.median(t) for name, t in times.items()}


FIRST_EVALUATION = """
import numpy as np
from camopt.engine.setup import load, prepare
problem, _ = prepare(load("configs/vcb_velocity.toml"))
lower, upper = (np.array([getattr(v, end) for v in problem.variables])
                for end in ("lower", "upper"))
problem.evaluate(lower + np.random.default_rng(0).random((4, lower.size)) * (upper - lower))
"""
"""A child that builds configs/vcb_velocity.toml's problem and evaluates four designs drawn
in its bounds: the VCB closing runs its numba kernel."""


def first_evaluation(rounds: int = 3) -> tuple[float, float]:
    """Median CPU seconds of :data:`FIRST_EVALUATION` with an empty numba cache (the first
    VCB evaluation after installing: the kernel is compiled; a fresh ``NUMBA_CACHE_DIR``
    each round) and with that cache filled (every later run), rounds interleaved (README,
    "Installation")."""
    cold, warm = [], []
    with tempfile.TemporaryDirectory() as tmp:
        env = {k: v for k, v in os.environ.items() if k != "PYTHONDONTWRITEBYTECODE"}
        env.update(ONE_BLAS_THREAD, PYTHONPYCACHEPREFIX=str(Path(tmp) / "pycache"))
        args = [sys.executable, "-c", FIRST_EVALUATION]
        for i in range(rounds):
            cache = {**env, "NUMBA_CACHE_DIR": str(Path(tmp) / f"numba{i}")}
            cold.append(_cpu(args, cache))
            warm.append(_cpu(args, cache))
    return statistics.median(cold), statistics.median(warm)


def main(before: Path | None = None) -> None:
    """The table; ``before`` (``python -m bench.bench_startup --before DIR``): the
    commands of another checkout too, in the same rounds."""
    medians = measure(before=before)
    base = medians.pop("import numpy, scipy")
    print(f"python -c 'import numpy, scipy': {base:.3f} s CPU (median of {ROUNDS})")
    width = max(len(name) for name in medians)
    for name, cpu in medians.items():
        if name.startswith("floor: "):
            print(f"{name:{width + 7}s} {cpu:.3f} s CPU: ratio {cpu / base:.2f} (not camopt's)")
            continue
        own = name.removeprefix("before: ")
        target = "" if own in UNTARGETED else " (target <= 1.5)"
        if own in TARGETS:
            against, limit = TARGETS[own]
            ratio = cpu / (base if against == "import numpy, scipy" else medians[against])
            target = f" (target <= {limit} x {against}: {ratio:.2f})"
        print(f"camopt {name:{width}s} {cpu:.3f} s CPU: ratio {cpu / base:.2f}{target}")
    cold, warm = first_evaluation()
    print(f"first VCB evaluation (4 designs): {cold:.2f} s CPU with an empty numba cache, "
          f"{warm:.2f} s with it filled: the kernel's compile adds {cold - warm:.1f} s once")


if __name__ == "__main__":
    main(Path(sys.argv[2]).resolve() if sys.argv[1:2] == ["--before"] else None)
