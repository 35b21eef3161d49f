"""One batched evaluation path: a Problem over many designs in row chunks sized for the cache.

A case's ``evaluate`` is vectorised over rows, but its temporaries grow with the row count
(a VCB design carries curves of ``positions`` samples and ``dynamics_steps`` intervals), so
one call over 10^6 rows needs tens of GiB and even 10^4 rows fall out of the cache: measured
on VCB, 250 rows per call cost 60-70 us a design, 10^4 rows 410-440 us (docs/design.md).
:func:`evaluate` and :func:`describe` cut ``X`` (n, n_var) into chunks of
:data:`CHUNK_ROWS` (or the Problem's own ``batch_rows``), evaluate each and write it into
arrays allocated once for all n rows: peak memory is the result plus one chunk's
temporaries, whatever n. Every case computes row by row (no quantity shared across a
population), so the result is bit-identical to one call over all rows
(tests/core/test_batch.py pins it for every case).

Tolerance analysis, the ``evaluate`` solver, tables of designs and robust search use it;
a search's own population (tens to hundreds of rows) is already one chunk.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator, Mapping
from typing import cast

import numpy as np

from camopt.core.problem import Evaluation, Problem
from camopt.mechanics import Floats, Ints

RowsDone = Callable[[int, int], None]
"""A progress callback: ``(rows evaluated so far, rows in all)``, called after each chunk
(the CLI draws it as a bar on stderr; the engine never prints)."""

CHUNK_ROWS = 256
"""Rows per call by default: the fastest per design on VCB (100-1,000 rows were 1.4-5x
faster per design than 10^4, bench/bench_batch.py), and small enough that no case's
temporaries for one chunk pass ~100 MiB."""


def chunk_rows(problem: Problem) -> int:
    """Rows per call for ``problem``: its ``batch_rows`` attribute if it sets one (cheap
    cases amortise Python overhead over more rows), else :data:`CHUNK_ROWS`."""
    return int(getattr(problem, "batch_rows", CHUNK_ROWS))


def chunks(n: int, size: int) -> Iterator[slice]:
    """Consecutive row slices of at most ``size`` rows covering ``range(n)``."""
    if size < 1:
        raise ValueError(f"chunk size {size}: at least 1")
    for start in range(0, n, size):
        yield slice(start, min(start + size, n))


def evaluate(problem: Problem, X: Floats, size: int | None = None,
             progress: RowsDone | None = None) -> Evaluation:
    """``problem.evaluate`` of designs ``X`` (n, n_var), SI, in chunks of ``size`` rows;
    the same Evaluation as one call. ``progress`` is told after each chunk."""
    return _chunked(lambda Xc, _: problem.evaluate(Xc), X, {}, size or chunk_rows(problem),
                    progress)


def describe(problem: Problem, X: Floats, fields: Mapping[str, Floats] | None = None,
             size: int | None = None, progress: RowsDone | None = None) -> Evaluation:
    """``problem.describe`` of designs ``X`` (n, n_var), SI, in chunks; with ``fields``
    (case field name -> (n,) values, capability :class:`~camopt.core.capabilities.VariesCase`)
    ``problem.describe_with`` instead. The same Evaluation as one call. ``progress`` is
    told after each chunk."""
    size = size or chunk_rows(problem)
    if fields:
        return _chunked(problem.describe_with, X, fields, size,  # type: ignore[attr-defined]
                        progress)
    return _chunked(lambda Xc, _: problem.describe(Xc), X, {}, size, progress)


VARIANT = "\0variant"
"""Key of the variant column among the chunked fields (no case field can be named so)."""


def describe_variants(problem: Problem, X: Floats, fields: Mapping[str, Floats],
                      variant: Ints, size: int | None = None,
                      progress: RowsDone | None = None, detail: bool = True) -> Evaluation:
    """``problem.describe_variants`` (capability
    :class:`~camopt.core.capabilities.HasVariants`) of designs ``X`` (n, n_var) with
    ``fields`` and each row's ``variant`` (n,), in chunks: the same Evaluation as one call
    (``detail``: as the capability's). The rows of each variant are chunked apart (a
    chunk holds one variant: one call of the case's per-variant evaluation, not one per
    variant it happens to hold; robust draws alternate variants row by row), unless the
    problem's ``mixed_variants`` says one call judges rows of every variant (then chunks
    of ``size`` rows per variant)."""
    def call(Xc: Floats, f: Mapping[str, Floats]) -> Evaluation:
        return problem.describe_variants(  # type: ignore[attr-defined]
            Xc, {k: v for k, v in f.items() if k != VARIANT}, f[VARIANT], detail=detail)
    kinds = np.unique(variant)
    size = size or chunk_rows(problem)
    if len(kinds) < 2 or getattr(problem, "mixed_variants", False):
        # a case that judges every variant's rows in one call (``mixed_variants``) takes
        # chunks of as many rows per variant as one variant's chunk
        return _chunked(call, X, {**fields, VARIANT: np.asarray(variant)},
                        size * len(kinds), progress)
    order = np.argsort(variant, kind="stable")
    starts = np.searchsorted(np.asarray(variant)[order], kinds)
    ends = np.r_[starts[1:], len(order)]
    pieces = []
    for a, b in zip(starts, ends, strict=True):
        rows = order[a:b]
        group = {k: np.asarray(v)[rows] for k, v in fields.items()}
        group[VARIANT] = cast(Floats, np.asarray(variant)[rows])  # ints, as one call's
        pieces.append(_chunked(call, np.asarray(X)[rows], group, size,
                               _offset(progress, int(a), len(X))))
    return Evaluation.concat(pieces).take(np.argsort(order, kind="stable"))


def _offset(progress: RowsDone | None, done: int, n: int) -> RowsDone | None:
    """``progress`` told of a group's rows after ``done`` rows of n (None stays None)."""
    if progress is None:
        return None
    told = progress

    def after(rows: int, _: int) -> None:
        told(done + rows, n)
    return after


def _chunked(fn: Callable[[Floats, Mapping[str, Floats]], Evaluation], X: Floats,
             fields: Mapping[str, Floats], size: int,
             progress: RowsDone | None = None) -> Evaluation:
    """Call ``fn`` on each row chunk of ``X`` and of every ``fields`` column, writing the
    results into arrays allocated after the first chunk (dtypes and column counts from
    it). One chunk (n <= size) is a plain call."""
    X = np.asarray(X, dtype=float)
    n = len(X)
    if n <= size:
        ev = fn(X, fields)
        if progress is not None:
            progress(n, n)
        return ev
    out: Evaluation | None = None
    for rows in chunks(n, size):
        ev = fn(X[rows], {k: np.asarray(v)[rows] for k, v in fields.items()})
        if out is None:
            out = Evaluation(
                f=np.empty((n, *np.shape(ev.f)[1:]), dtype=np.asarray(ev.f).dtype),
                g=np.empty((n, *np.shape(ev.g)[1:]), dtype=np.asarray(ev.g).dtype),
                extras={k: np.empty((n, *np.shape(v)[1:]), dtype=np.asarray(v).dtype)
                        for k, v in ev.extras.items()})
        if ev.extras.keys() != out.extras.keys():
            raise ValueError(f"rows {rows.start}-{rows.stop - 1}: metrics "
                             f"{sorted(ev.extras)} differ from the first chunk's")
        out.f[rows] = ev.f
        out.g[rows] = ev.g
        for k, v in ev.extras.items():
            out.extras[k][rows] = v
        if progress is not None:
            progress(rows.stop, n)
    assert out is not None
    return out
