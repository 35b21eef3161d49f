"""``pin_blas_threads`` leaves every BLAS on one thread, also scipy's when it loads after
the call (it is not imported by the call, so ``validate`` does not pay for it);
``one_blas_thread_on_load`` does the same for a BLAS loaded after it, importing nothing."""

from __future__ import annotations

import json
import subprocess
import sys

CLEAN_ENV = """
import json, os, sys
for name in ("OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "BLIS_NUM_THREADS",
             "OMP_NUM_THREADS"):
    os.environ.pop(name, None)
"""  # each probe starts with no thread count set by the environment


def _probe(script: str) -> dict:
    """The last line of ``script`` run in a fresh interpreter, as JSON."""
    done = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True,
                          check=True)
    return json.loads(done.stdout.strip().splitlines()[-1])


PROBE = CLEAN_ENV + """from camopt.core.perf import pin_blas_threads
pin_blas_threads()
before = "scipy.linalg" in sys.modules
import scipy.linalg  # its BLAS loads now, after the pin
from threadpoolctl import threadpool_info, threadpool_limits
blas = [i for i in threadpool_info() if i["user_api"] == "blas"]
print(json.dumps({"before": before, "threads": [i["num_threads"] for i in blas],
                  "libs": [i["filepath"] for i in blas]}))
"""


def test_blas_loaded_after_the_pin_runs_on_one_thread() -> None:
    result = _probe(PROBE)
    assert not result["before"]
    assert any("scipy" in lib for lib in result["libs"]), result["libs"]
    assert result["threads"] and all(n == 1 for n in result["threads"]), result


ON_LOAD = CLEAN_ENV + """from camopt.core.perf import one_blas_thread_on_load
one_blas_thread_on_load()
before = "numpy" in sys.modules
import numpy  # its BLAS loads now, told one thread
from threadpoolctl import threadpool_info
print(json.dumps({"before": before, "threads": [i["num_threads"] for i in threadpool_info()
                                                if i["user_api"] == "blas"]}))
"""


def test_numpy_loaded_after_the_command_line_s_setting_starts_on_one_thread() -> None:
    """``camopt.cli.main`` calls ``one_blas_thread_on_load`` before numpy loads: its BLAS
    never starts a thread per core (issue #36: ~0.06 s of CPU at every start)."""
    result = _probe(ON_LOAD)
    assert not result["before"]
    assert result["threads"] and all(n == 1 for n in result["threads"]), result


SKIPPED = CLEAN_ENV + """from camopt.core.perf import one_blas_thread_on_load, pin_blas_threads
one_blas_thread_on_load()
pin_blas_threads()
skipped = "threadpoolctl" not in sys.modules
from threadpoolctl import threadpool_info, threadpool_limits
threads = [i["num_threads"] for i in threadpool_info() if i["user_api"] == "blas"]
threadpool_limits(limits=2, user_api="blas")  # a caller raises it: the pin lowers it again
pin_blas_threads()
again = [i["num_threads"] for i in threadpool_info() if i["user_api"] == "blas"]
print(json.dumps({"skipped": skipped, "threads": threads, "again": again}))
"""


def test_pin_after_the_command_line_s_setting_needs_no_threadpoolctl() -> None:
    """After ``one_blas_thread_on_load`` ran before numpy (the command line), numpy's BLAS
    started on one thread: the pin imports no threadpoolctl (issue #36), until something
    has imported it (a caller that may have raised the threads), when it pins again."""
    result = _probe(SKIPPED)
    assert result["skipped"]
    assert result["threads"] and all(n == 1 for n in result["threads"]), result
    assert result["again"] and all(n == 1 for n in result["again"]), result
