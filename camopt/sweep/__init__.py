"""Sweeps: grid points x seeds, each cell one solver run, resumable.

:mod:`camopt.sweep.spec` says what a sweep runs (plain data; a finished cell is a
:class:`camopt.record.Repeat`); :mod:`camopt.sweep.run` runs it (imported on its own: it
writes archives)."""

from __future__ import annotations

from camopt.sweep.spec import CellSpec, SweepSpec, parse_grid, parse_seeds, summary

__all__ = ["CellSpec", "SweepSpec", "parse_grid", "parse_seeds", "summary"]
