"""bench/bench_peers.py's rows: every reduced setting is a valid config of its case."""

from __future__ import annotations

import pytest

from bench.bench_peers import CONFIGS, OBJECTIVES
from camopt.engine.driver import load


@pytest.mark.parametrize("objective", sorted(OBJECTIVES))
def test_every_row_loads(objective):
    """A row's overrides load over its shipped config (a renamed option would otherwise
    surface only when the bench runs)."""
    path, reduced = OBJECTIVES[objective]
    cfg = load(CONFIGS / path, ["run.repeats=1", *reduced])
    assert cfg.run.repeats == 1

