"""The batched evaluation path: chunked calls give the same Evaluation as one call, bit for
bit, for every case (no case shares a quantity across rows) - except where a case's
matrix product goes through BLAS (the EMB spline, ``r @ M``), whose kernels sum in an
order that depends on the block's row count: there equal to 1e-12 relative."""

from __future__ import annotations

import numpy as np
import pytest

from camopt.cases import build_problem
from camopt.core import batch
from camopt.core.problem import Evaluation
from camopt.engine.driver import load
from tests.conftest import CONFIGS

CASES = ["vcb_velocity.toml", "vcb_fourbar.toml", "vcb_identify.toml", "emb.toml",
         "fast_switch.toml", "opening_spring_lse6.toml", "opening_spring_identify.toml"]
"""One config per Problem class and mode (VCB with its closing dynamics)."""


BLAS_ROUNDING = {"emb.toml"}
"""Cases whose rows go through a BLAS matrix product (compared to 1e-12 relative)."""


def _same(a: Evaluation, b: Evaluation, exact: bool = True) -> None:
    def check(x, y, msg=""):
        if exact:
            np.testing.assert_array_equal(x, y, err_msg=msg)
        else:
            np.testing.assert_allclose(x, y, rtol=1e-12, atol=0, err_msg=msg)
    check(a.f, b.f)
    check(a.g, b.g)
    assert a.f.dtype == b.f.dtype and a.g.shape == b.g.shape
    assert list(a.extras) == list(b.extras)
    for k in a.extras:
        check(a.extras[k], b.extras[k], k)


@pytest.mark.parametrize("config", CASES)
def test_chunks_are_bit_identical_to_one_call(config):
    problem = build_problem(load(CONFIGS / config).case)
    X = problem.sample(np.random.default_rng(np.random.SeedSequence(7)), 150)
    exact = config not in BLAS_ROUNDING
    _same(batch.evaluate(problem, X, size=48), problem.evaluate(X), exact)
    few = X[:11]  # describe simulates each opening-spring design: a few rows
    _same(batch.describe(problem, few, size=4), problem.describe(few), exact)


def test_case_fields_are_chunked_with_their_rows():
    problem = build_problem(load(CONFIGS / "vcb_velocity.toml").case)
    rng = np.random.default_rng(np.random.SeedSequence(8))
    X = np.tile(problem.vendor_x(), (150, 1))
    l1 = problem.config.l1_mm + rng.uniform(-0.1, 0.1, 150)
    _same(batch.describe(problem, X, {"l1_mm": l1}, size=40),
          problem.describe_with(X, {"l1_mm": l1}))


def test_chunks_cover_every_row_once():
    assert [(s.start, s.stop) for s in batch.chunks(5, 2)] == [(0, 2), (2, 4), (4, 5)]
    assert list(batch.chunks(0, 3)) == []
    with pytest.raises(ValueError):
        list(batch.chunks(3, 0))


def test_metrics_that_change_between_chunks_are_refused(sphere_case):
    from tests.conftest import SphereConfig

    problem = sphere_case(SphereConfig())
    calls = iter([{"a": np.zeros(2)}, {"b": np.zeros(1)}])
    real = problem.evaluate
    problem.evaluate = lambda X: Evaluation(real(X).f, real(X).g, next(calls))
    with pytest.raises(ValueError, match="differ from the first chunk"):
        batch.evaluate(problem, np.zeros((3, 4)), size=2)


def test_progress_is_told_each_chunk_and_changes_nothing():
    """The progress callback (issue #36) hears the rows done after every chunk, ending
    at all rows, and the Evaluation is the one without it."""
    problem = build_problem(load(CONFIGS / "fast_switch.toml").case)
    X = problem.sample(np.random.default_rng(np.random.SeedSequence(9)), 50)
    heard: list[tuple[int, int]] = []
    ev = batch.evaluate(problem, X, size=16, progress=lambda d, n: heard.append((d, n)))
    assert heard == [(16, 50), (32, 50), (48, 50), (50, 50)]
    _same(ev, batch.evaluate(problem, X, size=16))
    heard.clear()
    batch.describe(problem, X[:3], size=16, progress=lambda d, n: heard.append((d, n)))
    assert heard == [(3, 3)]  # one chunk: told once, at the end


def _chunked_calls(mixed: bool) -> tuple[list[np.ndarray], list[tuple[int, int]]]:
    """23 robust VCB rows of alternating variants through ``batch.describe_variants`` in
    chunks of 8 (the case judging mixed variants in one call or not): checked equal, bit
    for bit, to one call of the case; each call's variants and the progress heard."""
    problem = build_problem(load(CONFIGS / "vcb_velocity_robust.toml").case)
    problem.mixed_variants = mixed
    X = problem.sample(np.random.default_rng(np.random.SeedSequence(10)), 23)
    variant = np.arange(23) % 2
    whole = problem.describe_variants(X, {}, variant, detail=False)
    seen: list[np.ndarray] = []
    real = problem.describe_variants
    problem.describe_variants = lambda Xc, f, v, detail: (seen.append(v), real(Xc, f, v, detail))[1]
    heard: list[tuple[int, int]] = []
    ev = batch.describe_variants(problem, X, {}, variant, size=8, detail=False,
                                 progress=lambda d, n: heard.append((d, n)))
    _same(ev, whole)
    return seen, heard


def test_variants_are_chunked_apart_and_give_one_call_s_rows():
    """Rows of mixed model variants (robust draws alternate them row by row) are chunked
    per variant: each call of the case's describe_variants holds one variant, the calls
    are as few as the chunk size allows per variant, the progress ends at every row, and
    the rows are the one call's, in the caller's order, bit for bit (a row's evaluation
    is its own, whatever rows share its call)."""
    seen, heard = _chunked_calls(mixed=False)  # a case that judges one variant a call
    assert [len(np.unique(v)) for v in seen] == [1] * 4  # 12 rows of 0: 8 + 4; 11 of 1: 8 + 3
    assert [len(v) for v in seen] == [8, 4, 8, 3]
    assert heard[-1] == (23, 23) and [d for d, _ in heard] == sorted(d for d, _ in heard)


def test_mixed_variants_are_chunked_together():
    """A case whose one call judges rows of every variant (the VCB: ``mixed_variants``)
    gets chunks of both, ``size`` rows per variant, in the caller's order, and the rows
    are the one call's, bit for bit (a row's evaluation is its own)."""
    assert build_problem(load(CONFIGS / "vcb_velocity_robust.toml").case).mixed_variants
    seen, heard = _chunked_calls(mixed=True)
    assert [len(v) for v in seen] == [16, 7]  # 8 rows a variant a call
    np.testing.assert_array_equal(np.concatenate(seen), np.arange(23) % 2)
    assert heard == [(16, 23), (23, 23)]


def test_vcb_chunks_rows_as_its_batch_rows_says():
    """The VCB's chunks are its own 512 rows (robust draws cost less per row than at the
    default 256), every other case's the default."""
    vcb = build_problem(load(CONFIGS / "vcb_velocity.toml").case)
    assert batch.chunk_rows(vcb) == 512
    assert batch.chunk_rows(build_problem(load(CONFIGS / "fast_switch.toml").case)) == \
        batch.CHUNK_ROWS
