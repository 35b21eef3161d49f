"""Hardening round 5 (issue #49): each test here failed on main before the fix it names.

Calls that could hang or fill memory on a broken camopt run as subprocesses with a time
limit and an address-space limit, so a regression fails the test instead of the machine."""

from __future__ import annotations

import os
import resource
import shlex
import subprocess
import sys
from collections.abc import Callable
from pathlib import Path

import pytest

from tests.cases.vcb_ode import CURVES
from tests.cli.test_faults import CAMOPT, one_error_line
from tests.conftest import CONFIGS

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

VCB = str(CONFIGS / "vcb.toml")
VENDOR = str(CURVES / "vendor.csv")
MEMORY = 3 * 2**29
"""Address space of a subprocess (1.5 GiB): camopt needs well under 1 GiB; a reader of
/dev/zero without a bound stops here with MemoryError instead of at the OOM killer."""


def _bounded() -> None:
    resource.setrlimit(resource.RLIMIT_AS, (MEMORY, MEMORY))


def camopt(*args: object, cwd: Path | None = None, timeout: float = 60
           ) -> subprocess.CompletedProcess[str]:
    return subprocess.run([*CAMOPT, *map(str, args)], capture_output=True, text=True,
                          timeout=timeout, cwd=cwd, preexec_fn=_bounded)


def _special(tmp_path: Path, kind: str) -> str:
    """A path that is not a regular file: a FIFO (opening it waits for a writer), a
    device that never ends, or a directory."""
    if kind == "fifo":
        path = tmp_path / "curve.csv"
        os.mkfifo(path)
        return str(path)
    if kind == "dir":
        path = tmp_path / "folder.csv"
        path.mkdir()
        return str(path)
    return "/dev/zero"


# ---- C1: every file input is a regular file of bounded size -----------------------------
@pytest.mark.parametrize("kind, what", [("fifo", "not a regular file"),
                                        ("zero", "not a regular file"),
                                        ("dir", "is a directory")])
@pytest.mark.parametrize("where", ["--curve", "cam_points", "reference_cam_points"])
def test_a_curve_or_points_file_that_is_no_regular_file_is_one_line(tmp_path, kind, what,
                                                                      where):
    """main: a FIFO as --curve hung for ever and /dev/zero read until the OOM killer ended
    camopt (23 GiB, exit 137). Now the shared reader (config.loader.read_regular_file,
    the case files' check) refuses it before reading: one line, exit 2."""
    special = _special(tmp_path, kind)
    if where == "--curve":
        args = ["calibrate", VCB, "--curve", special]
    elif where == "cam_points":
        args = ["calibrate", VCB, "--curve", VENDOR, "--set", f"cam_points={special}"]
    else:
        case = tmp_path / "case.toml"
        case.write_text(f'extends = "{VCB}"\n[case]\nreference_cam_points = "{special}"\n')
        args = ["validate", case]
    proc = camopt(*args, cwd=tmp_path)
    assert proc.returncode == 2 and one_error_line(proc.stderr), proc.stderr
    assert what in proc.stderr and special in proc.stderr


def test_a_curve_file_over_the_size_cap_is_refused_unread(tmp_path, monkeypatch):
    from camopt.cases.vcb import curves
    from camopt.errors import ConfigError

    big = tmp_path / "big.csv"
    big.write_text("time_ms,travel_mm\n" + "0,0\n" * 100)
    monkeypatch.setattr(curves, "MAX_TABLE_BYTES", 100)
    with pytest.raises(ConfigError, match="bytes; a CSV file is at most 100 bytes"):
        curves.read_curve(big)


# ---- C3: per-curve and predicted designs get the case's checks ---------------------------
@pytest.mark.parametrize("option", ["--set", "--predict"])
@pytest.mark.parametrize("value, what", [
    ("kc1_n_per_mm=1e300", "kc1_n_per_mm: 1e+300 is beyond 1e+12 in size"),
    ("kc2_n_per_mm=1e5", "kc2_n_per_mm: 100000 is outside the physical range [0.01, 10000] "
                         "N/mm"),
    ("kc1_n_per_mm=nan", "kc1_n_per_mm: Input should be a finite number"),
    ("a1=1e300", "a1: 1e+300 is beyond 1e+12 in size"),
    ("a3=-inf", "a3: not a finite number"),
])
def test_design_values_of_calibrate_get_the_case_checks(option, value, what):
    """main: kc1_n_per_mm=1e300 after a --curve ended 'internal error: ValueError' after 14
    RuntimeWarning lines; as a prediction it exited 0 with a 150-digit velocity. Now one
    line naming the curve file (or --predict) and the key, before any fit."""
    proc = camopt("calibrate", VCB, "--curve", VENDOR, option, value)
    assert proc.returncode == 2 and one_error_line(proc.stderr), proc.stderr
    where = VENDOR if option == "--set" else "--predict"
    assert proc.stderr.startswith(f"error: {where}: {what}"), proc.stderr
    assert "Warning" not in proc.stderr


@pytest.mark.parametrize("delay, what", [
    ("1e300", "Input should be less than or equal to 1000"),  # the case field's range
    ("-5", "Input should be greater than or equal to 0"),
    ("2000", "Input should be less than or equal to 1000")])
def test_a_measured_latch_delay_is_within_the_curve(delay, what):
    proc = camopt("calibrate", VCB, "--curve", VENDOR, "--set", f"latch_delay_ms={delay}")
    assert proc.returncode == 2 and one_error_line(proc.stderr), proc.stderr
    assert f"latch_delay_ms: {what}" in proc.stderr


def test_the_case_plausibility_switch_also_governs_design_values():
    from camopt.cli.calibrate import check_design_values
    from tests.helpers import load

    config = load(VCB, "run.check_plausibility=false")
    check_design_values(config, [("c.csv", ["kc1_n_per_mm=1e5"])], [])  # accepted


# ---- K1: user text in the TOML fragment stays text ----------------------------------------
@pytest.mark.slow
def test_a_curve_name_cannot_add_settings_to_the_fragment(tmp_path):
    """main: calibrate --out wrote the curve file's name into a TOML comment unescaped, so
    a name with a newline added live settings that every case extending the fragment
    inherited. The name is now in the comment with its newline as '\\n'."""
    name = "x\nrun = {repeats = 777, seed = 666}\n#.csv"
    curve = tmp_path / name
    curve.write_bytes(Path(VENDOR).read_bytes())
    out = tmp_path / "fragment.toml"
    proc = camopt("calibrate", VCB, "--curve", curve, "--form", "coulomb", "--out", out,
                  timeout=180)
    assert proc.returncode == 0, proc.stderr
    data = tomllib.loads(out.read_text())
    assert "run" not in data and set(data) == {"extends", "case"}
    assert "x\\nrun = {repeats = 777, seed = 666}\\n#.csv" in out.read_text()
    assert camopt("validate", out).returncode == 0


if sys.platform != "linux":  # pragma: no cover
    pytest.skip("FIFOs, /dev/zero and RLIMIT_AS", allow_module_level=True)


# ---- X1: every numeric option has a stated range ------------------------------------------
@pytest.mark.parametrize("step", ["1e-5", "0.001", "31", "nan"])
def test_export_step_is_bounded_below(fast_run, tmp_path, step):
    """main: --step-deg 1e-5 ran 78 s at 7.7 GB before 'error: out of memory'. The CNC
    points table's step is in [0.01, 30] deg, refused before any work."""
    proc = camopt("export", fast_run, "--format", "dxf", "--step-deg", step,
                  "--out", tmp_path / "e", timeout=30)
    assert proc.returncode == 2 and one_error_line(proc.stderr), proc.stderr
    assert f"--step-deg: {float(step):g}: must be in [0.01, 30] deg" in proc.stderr
    assert not (tmp_path / "e").exists()


@pytest.mark.parametrize("args, what", [
    (["compare", "{run}", "{run}", "--equivalence", "inf"],
     "--equivalence: inf: a finite threshold"),
    (["calibrate", VCB, "--curve", VENDOR, "--velocity-points", "1,inf"],
     "--velocity-points: 1,inf: need 0 < LOW < HIGH <= 500"),
    (["calibrate", VCB, "--curve", VENDOR, "--velocity-points", "1,1e300"],
     "--velocity-points: 1,1e300: need 0 < LOW < HIGH <= 500"),
])
def test_unbounded_numbers_are_refused_with_their_range(fast_run, args, what):
    proc = camopt(*(a.format(run=fast_run) for a in args))
    assert proc.returncode == 2 and one_error_line(proc.stderr), proc.stderr
    assert what in proc.stderr


def test_every_numeric_option_states_its_range():
    """Each int or float option of every command is a click range with a lower bound and
    an upper bound, or its help states its range in words ('0.01 to 30', '>= 0', 'at
    most'), or it is checked by the case's models (run --seed/--repeats set run.seed and
    run.repeats) or has its cap documented (sweep --jobs: docs/reliability.md)."""
    import typer

    from camopt.cli.app import app, load_commands

    load_commands([])
    group = typer.main.get_command(app)
    checked_by_models = {("run", "seed"), ("run", "repeats"), ("sweep", "jobs")}
    missing, numeric = [], 0
    for name, command in group.commands.items():  # type: ignore[attr-defined]
        for param in command.params:
            if param.type_descriptor.annotation not in (int, float):
                continue
            numeric += 1
            bounded = param.min is not None and param.max is not None
            stated = any(w in (getattr(param, "help", "") or "")
                         for w in (" to ", ">=", "at most", "<="))
            if not (bounded or stated or (name, param.name) in checked_by_models):
                missing.append(f"{name} --{param.name}")
    assert numeric >= 8 and not missing, missing


# ---- stdout: a failed or short write is one line and a non-zero exit ---------------------
def _commands(run: Path) -> dict[str, list[object]]:
    return {"show json": ["show", run, "--format", "json"], "show": ["show", run],
            "compare json": ["compare", run, run, "--format", "json"],
            "tolerance json": ["tolerance", run, "--samples", "50", "--format", "json"],
            "init": ["init", "fast_switch"],
            "validate": ["validate", CONFIGS / "fast_switch.toml"], "help": ["--help"]}


@pytest.mark.parametrize("name", ["show json", "show", "compare json", "tolerance json",
                                  "init", "validate", "help"])
def test_stdout_on_a_full_disk_is_one_line(fast_run, name):
    """main: 'error: internal error: OSError: [Errno 28] No space left on device (please
    report this)'."""
    with open("/dev/full", "w") as full:
        proc = subprocess.run([*CAMOPT, *map(str, _commands(fast_run)[name])], stdout=full,
                              stderr=subprocess.PIPE, text=True, timeout=60)
    assert proc.returncode == 2 and one_error_line(proc.stderr), proc.stderr
    assert proc.stderr.startswith("error: <stdout>: write: No space left on device; the "
                                  "output is incomplete"), proc.stderr


def _file_limit(limit: int) -> Callable[[], None]:
    def apply() -> None:  # the kernel's EFBIG past ``limit`` bytes (as `ulimit -f`)
        resource.setrlimit(resource.RLIMIT_FSIZE, (limit, limit))
    return apply


@pytest.mark.parametrize("name", ["show json", "show", "compare json", "tolerance json",
                                  "init"])
def test_stdout_over_a_file_size_limit_is_not_success(fast_run, tmp_path, name):
    """main: under `ulimit -f 1` `show --format json` exited 0 with its output cut at
    1,024 bytes (Python's buffered stdout let the short write pass). Each output here is
    over 1,024 bytes: the command exits 2 with one line saying the output is incomplete.
    (Python ignores SIGXFSZ, so the limit is an EFBIG error, as in a shell.)"""
    out = tmp_path / "out.txt"
    with out.open("w") as f:
        proc = subprocess.run([*CAMOPT, *map(str, _commands(fast_run)[name])], stdout=f,
                              stderr=subprocess.PIPE, text=True, timeout=60,
                              preexec_fn=_file_limit(1024))
    assert proc.returncode == 2 and one_error_line(proc.stderr), proc.stderr
    assert "<stdout>: write: File too large; the output is incomplete" in proc.stderr
    assert out.stat().st_size == 1024


def test_a_shell_ulimit_cuts_json_with_an_error(fast_run, tmp_path):
    """The issue's reproduction as a user types it: `ulimit -f 1` (1,024-byte blocks) in a
    shell, then show --format json into a file."""
    command = " ".join(map(shlex.quote, [*CAMOPT, "show", str(fast_run), "--format", "json"]))
    proc = subprocess.run(["bash", "-c", f"ulimit -f 1; {command} > out.json"],
                          cwd=tmp_path, capture_output=True, text=True, timeout=60)
    assert proc.returncode == 2 and one_error_line(proc.stderr), proc.stderr


def test_output_that_fits_is_unchanged(fast_run, tmp_path):
    """The checked stdout writes what Python's did: the same bytes as the in-process
    command, nothing on stderr."""
    from typer.testing import CliRunner

    from camopt.cli import app

    proc = camopt("show", fast_run, "--format", "json")
    assert proc.returncode == 0 and proc.stderr == ""
    inline = CliRunner().invoke(app, ["show", str(fast_run), "--format", "json"])
    assert proc.stdout == inline.stdout
