"""A 3 x 5 sweep (populations x seeds) of the VCB case with 1 and 2 workers: identical
summaries, and the wall-time ratio (target >= 1.7x on 2 cores)."""

from __future__ import annotations

import json
import tempfile
import time
from pathlib import Path

from camopt import sweep as sw
from camopt.driver import load
from camopt.sweep.run import run_sweep

CONFIG = Path(__file__).resolve().parents[1] / "configs" / "vcb.toml"


def main() -> None:
    cfg = load(CONFIG)
    spec = sw.SweepSpec(cfg.effective(), str(CONFIG), cfg.text,
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


if __name__ == "__main__":
    main()
