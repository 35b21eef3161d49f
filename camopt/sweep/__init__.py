"""Sweeps: grid points x seeds, each cell one solver run, resumable.

:mod:`camopt.sweep.spec` says what a sweep runs (plain data, also what the archive
stores); :mod:`camopt.sweep.run` runs it (imported on its own: it writes archives)."""

from __future__ import annotations

from camopt.sweep.spec import CellResult, CellSpec, SweepSpec, parse_grid, parse_seeds, summary

__all__ = ["CellResult", "CellSpec", "SweepSpec", "parse_grid", "parse_seeds", "summary"]
