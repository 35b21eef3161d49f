"""Solver plugins behind one ask/tell interface (``base.Solver``)."""

from __future__ import annotations

from camopt.solvers.base import Solver, StopReason
from camopt.solvers.registry import get_solver, register_solver, solvers

__all__ = ["Solver", "StopReason", "get_solver", "register_solver", "solvers"]
