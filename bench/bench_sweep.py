"""Sweeps: cost per cell as sweeps grow (issue #12), a 10,000-cell sweep killed in its
middle and resumed, and the 3 x 5 VCB sweep on 1 and 2 workers. Every figure is a ratio
measured in this run."""

from __future__ import annotations

import json
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from camopt import sweep as sw
from camopt.archive.sweeps import load_sweep
from camopt.driver import load
from camopt.sweep.run import run_sweep

ROOT = Path(__file__).resolve().parents[1]
VCB = ROOT / "configs" / "vcb.toml"
# tiny cells: fast_switch_de's search without its polish, 5 generations of 8
TINY = f'''extends = "{ROOT / "configs" / "fast_switch_de.toml"}"
[solver]
name = "de_gr"
population = 8
generations = 5
'''


def _tiny_spec(n_seeds: int, folder: Path) -> tuple[sw.SweepSpec, Path]:
    case = folder / "tiny.toml"
    case.write_text(TINY)
    cfg = load(case)
    return sw.SweepSpec(cfg.effective(), str(case), cfg.text, [], (0, n_seeds)), case


def per_cell_scaling() -> None:
    """Wall time per cell of a 400-cell sweep against a 25-cell one (target <= 1.5x)."""
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        per_cell = {}
        for n in (25, 400):
            spec, _ = _tiny_spec(n, folder)
            t0 = time.perf_counter()
            run_sweep(spec, folder / f"s{n}.h5", {}, jobs=1)
            per_cell[n] = (time.perf_counter() - t0) / n
    print(f"tiny cells, one job: {per_cell[25] * 1e3:.2f} ms per cell for 25 cells, "
          f"{per_cell[400] * 1e3:.2f} ms for 400: ratio {per_cell[400] / per_cell[25]:.2f} "
          "(target <= 1.5)")


def ten_thousand_cells(n: int = 10_000) -> None:
    """A 10,000-cell sweep through the CLI, SIGKILLed in its middle and resumed; the
    resumed archive against an uninterrupted one, and the share of wall time outside the
    cells' own solver time (target <= 10 %)."""
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        _, case = _tiny_spec(n, folder)
        cmd = [sys.executable, "-m", "camopt", "sweep", str(case), "--seeds", f"0:{n}",
               "--jobs", "1", "--quiet"]
        killed = folder / "killed.h5"
        proc = subprocess.Popen([*cmd, "--out", str(killed)], stdout=subprocess.DEVNULL,
                                stderr=subprocess.DEVNULL)
        while True:  # kill once about half the cells are stored
            time.sleep(0.5)
            if killed.exists() and len(load_sweep(killed)[1]) >= n // 2:
                break
        proc.send_signal(signal.SIGKILL)
        proc.wait()
        stored = len(load_sweep(killed)[1])
        subprocess.run([*cmd[:4], "--resume", str(killed), "--jobs", "1", "--quiet"],
                       check=True, stdout=subprocess.DEVNULL)
        full = folder / "full.h5"
        spec, _ = _tiny_spec(n, folder)
        t0 = time.perf_counter()
        run_sweep(spec, full, {}, jobs=1)  # in this process: no interpreter start counted
        wall = time.perf_counter() - t0
        a, b = load_sweep(killed)[1], load_sweep(full)[1]
        same = a.keys() == b.keys() and all(
            {**vars(a[k]), "wall_s": 0} == {**vars(b[k]), "wall_s": 0} for k in a)
        inside = sum(r.wall_s for r in b.values())
    print(f"{n} tiny cells: killed with {stored} stored, resumed: identical to an "
          f"uninterrupted sweep: {same}; uninterrupted {wall:.1f} s, "
          f"{100 * (1 - inside / wall):.1f} % outside the cells' solvers (target <= 10 %; "
          "counts each cell's solver set-up as outside)")


def vcb_workers() -> None:
    """The 3 x 5 VCB sweep with 1 and 2 workers: identical summaries, wall-time ratio."""
    cfg = load(VCB)
    spec = sw.SweepSpec(cfg.effective(), str(VCB), cfg.text,
                        sw.parse_grid(["solver.population=50,100,200"]), (0, 5))
    times, tables = {}, {}
    with tempfile.TemporaryDirectory() as tmp:
        for jobs in (1, 2):
            path = Path(tmp) / f"jobs{jobs}.h5"
            t0 = time.perf_counter()
            results = run_sweep(spec, path, {}, jobs=jobs)
            times[jobs] = time.perf_counter() - t0
            rows = sw.summary(spec, results.values())
            tables[jobs] = json.dumps([{k: v for k, v in r.items() if not k.startswith("wall")}
                                       for r in rows], sort_keys=True)
    print(f"3 x 5 VCB sweep: jobs=1 {times[1]:.1f} s, jobs=2 {times[2]:.1f} s, "
          f"speed-up {times[1] / times[2]:.2f}x (target >= 1.7); identical summaries: "
          f"{tables[1] == tables[2]}")


def main() -> None:
    per_cell_scaling()
    ten_thousand_cells()
    vcb_workers()


if __name__ == "__main__":
    main()
