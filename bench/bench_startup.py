"""Start-up cost of the command line (issue #22): CPU time (user + system, from
``resource.getrusage`` of the children) of ``camopt --version`` and ``camopt --help``
against ``python -c "import numpy, scipy"``, medians of 7 runs each, measured in the same
run (target: --version <= 1.5x)."""

from __future__ import annotations

import resource
import statistics
import subprocess
import sys

RUNS = 7


def cpu_seconds(args: list[str]) -> float:
    """Median CPU seconds (user + system) of ``RUNS`` runs of ``args``."""
    times = []
    for _ in range(RUNS):
        before = resource.getrusage(resource.RUSAGE_CHILDREN)
        subprocess.run(args, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, check=True)
        after = resource.getrusage(resource.RUSAGE_CHILDREN)
        times.append(after.ru_utime - before.ru_utime + after.ru_stime - before.ru_stime)
    return statistics.median(times)


def main() -> None:
    base = cpu_seconds([sys.executable, "-c", "import numpy, scipy"])
    for flag in ("--version", "--help"):
        ours = cpu_seconds([sys.executable, "-m", "camopt", flag])
        print(f"camopt {flag}: {ours:.3f} s CPU; import numpy, scipy {base:.3f} s: "
              f"ratio {ours / base:.2f}" + (" (target <= 1.5)" if flag == "--version" else ""))


if __name__ == "__main__":
    main()
