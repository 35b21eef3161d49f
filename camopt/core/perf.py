"""Process-level tuning for the vectorised hot path.

A population evaluation creates many temporary arrays of about 100 KB (100
designs x 141 cam positions). glibc returns freed memory at the top of the heap
to the system once it exceeds M_TRIM_THRESHOLD (128 KB), so the next temporary
page-faults on first touch: that doubled the VCB evaluation time. Raising the trim
and mmap thresholds keeps those pages mapped. No library does this for us; it is a
no-op off glibc.

Its imports are where they are used: the command line calls it before numpy loads.
"""

from __future__ import annotations

import contextlib
import os
import signal
from typing import TYPE_CHECKING

if TYPE_CHECKING:  # imported where used: the CLI starts without them
    import ctypes
    from concurrent.futures import ProcessPoolExecutor

import functools
import sys

_M_TRIM_THRESHOLD = -1
_M_MMAP_THRESHOLD = -3
_done = False
_one_on_load = False  # BLAS was told one thread before numpy loaded


@functools.cache
def _libc() -> ctypes.CDLL:
    """The C library, found once per process and inherited by forked workers
    (``find_library`` runs ``ldconfig`` in a subprocess: ~10 ms, more in a large parent)."""
    import ctypes
    import ctypes.util

    return ctypes.CDLL(ctypes.util.find_library("c") or "libc.so.6", use_errno=True)


def tune_allocator(trim_bytes: int = 256 * 2**20, mmap_bytes: int = 32 * 2**20) -> bool:
    """Raise glibc's trim and mmap thresholds once per process; True if applied."""
    global _done
    if _done:
        return True
    if not sys.platform.startswith("linux"):
        return False
    try:
        libc = _libc()
        ok = bool(libc.mallopt(_M_TRIM_THRESHOLD, trim_bytes)) and bool(
            libc.mallopt(_M_MMAP_THRESHOLD, mmap_bytes))
    except (OSError, AttributeError):  # not glibc (musl, ...)
        return False
    _done = ok
    return ok


def pin_blas_threads() -> None:
    """Run BLAS/LAPACK on one thread in this process (forked workers inherit it).

    Threaded BLAS splits a product's inner sums across threads, so the rounding of a
    result depends on the thread count (``OPENBLAS_NUM_THREADS``, the machine's cores, a
    Dask worker's setting): the same sweep gave different cells on different executors.
    camopt's parallelism is across processes (repeats, cells), so one BLAS thread per
    process costs nothing there and makes every result independent of where it ran.

    scipy's BLAS (a library of its own, loaded with ``scipy.linalg``) is not loaded here
    (``validate`` would pay ~0.1 s CPU for it): OpenBLAS reads ``OPENBLAS_NUM_THREADS``
    when it loads, so one loaded later starts on one thread (tests/core/test_perf.py).

    When :func:`one_blas_thread_on_load` ran before numpy loaded (the command line) and
    nothing has imported threadpoolctl since (the one way a caller raises a loaded BLAS's
    threads), every BLAS in the process read one thread when it loaded: threadpoolctl is
    not imported (~5 ms, ``camopt validate`` evaluates nothing)."""
    import numpy  # noqa: F401  (loads numpy's BLAS, so threadpoolctl finds it)

    one_blas_thread_on_load()  # for a BLAS loaded later (read when it loads)
    if _one_on_load and "threadpoolctl" not in sys.modules:
        return
    from threadpoolctl import threadpool_limits

    threadpool_limits(limits=1, user_api="blas")  # again each time: a caller may raise it


BLAS_THREADS = ("OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "BLIS_NUM_THREADS")
"""The variables a BLAS reads, once, when it loads for its number of threads."""


def one_blas_thread_on_load() -> None:
    """Tell every BLAS loaded from now on to start on one thread (:data:`BLAS_THREADS`):
    the half of :func:`pin_blas_threads` that imports nothing.

    The command line calls it first (``camopt.cli.main``), before anything imports numpy:
    camopt computes on one BLAS thread anyway (:func:`pin_blas_threads`), and an OpenBLAS
    that loads with its default starts a thread per core whose start-up cost ~0.06 s of
    CPU on every command, numpy's import being most of what a command that evaluates
    nothing pays for (bench/bench_startup.py)."""
    global _one_on_load
    for name in BLAS_THREADS:
        os.environ[name] = "1"
    if "numpy" not in sys.modules:  # numpy's BLAS, and any later, will read it
        _one_on_load = True


PYDANTIC_PLUGINS = "PYDANTIC_DISABLE_PLUGINS"
"""pydantic's switch for its plugins (``__all__``: none; a comma-separated list: those)."""


def no_pydantic_plugins() -> None:
    """Tell pydantic to look for no plugins, unless the user set :data:`PYDANTIC_PLUGINS`
    (an empty value: every installed plugin, as pydantic's default).

    The command line calls it first (``camopt.cli.main``): on the first model it
    validates, pydantic otherwise reads the entry points of every installed distribution
    to find its plugins (observability hooks; camopt uses none), ~0.017 s of CPU with 80
    distributions installed and more in a larger environment, paid by every command that
    reads a case file (bench/bench_startup.py)."""
    os.environ.setdefault(PYDANTIC_PLUGINS, "__all__")


_PR_SET_PDEATHSIG = 1


def die_with_parent() -> bool:
    """Ask Linux to SIGKILL this process when its parent dies (pool workers of a sweep
    whose parent was killed would otherwise wait for work forever); True if applied."""
    if not sys.platform.startswith("linux"):
        return False

    try:
        return _libc().prctl(_PR_SET_PDEATHSIG, int(signal.SIGKILL), 0, 0, 0) == 0
    except (OSError, AttributeError):
        return False


def worker_start() -> None:
    """Set-up of every camopt pool worker: die with the parent (a killed camopt leaves no
    worker blocked forever), leave Ctrl-C to the parent (which stops the pool), restore
    SIGTERM's default, tune the allocator."""
    die_with_parent()
    pin_blas_threads()
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    signal.signal(signal.SIGTERM, signal.SIG_DFL)
    tune_allocator()


def fork_pool(jobs: int) -> ProcessPoolExecutor:
    """A process pool of ``jobs`` forked workers, started now (they inherit the parent's
    problem and solver objects, so tasks pass only indices and small results).

    The workers are forked with the parent's objects frozen out of the garbage collector
    (``gc.freeze``): a worker's collections then never walk them, so it neither spends
    time on them nor writes their headers, which would copy every page they sit on
    (copy-on-write). Measured: a worker's first tiny cell (~3 ms later on) took 14-24 ms
    of CPU without it, 3-20 ms with it."""
    import gc
    from concurrent.futures import ProcessPoolExecutor
    from multiprocessing import get_context

    pool = ProcessPoolExecutor(max_workers=jobs, mp_context=get_context("fork"),
                               initializer=worker_start)
    with contextlib.suppress(OSError):  # found here once, not by every worker
        _libc()
    gc.freeze()
    try:  # a fork pool forks all its workers at its first task (not on demand)
        pool.submit(int)
    finally:
        gc.unfreeze()  # the parent's own collections as before
    return pool


def kill_pool(pool: ProcessPoolExecutor) -> None:
    """Stop a pool at once: its workers are killed, not waited for (interrupted work)."""
    for proc in list(getattr(pool, "_processes", {}).values()):
        proc.kill()
    pool.shutdown(wait=True, cancel_futures=True)
