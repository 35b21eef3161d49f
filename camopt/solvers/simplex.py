"""``simplex``: the modified simplex method, i.e. scipy's Nelder-Mead with bounds
(adaptive parameters), as a generic local optimiser from one or several starts.

scipy.optimize is imported where a start is solved (scipy is slow to import)."""

from __future__ import annotations

import math
from typing import Literal

import numpy as np
from pydantic import Field

from camopt.config.models import MAX_LOCAL_ITERATIONS, MAX_STARTS
from camopt.core.problem import FEASIBILITY_TOL
from camopt.mechanics import Bools, Floats
from camopt.solvers.multistart import MultiStart, MultiStartOptions, StartRecord
from camopt.solvers.registry import register_solver


class SimplexOptions(MultiStartOptions):
    """Options of ``simplex``."""

    name: Literal["simplex"] = "simplex"
    starts: int = Field(1, ge=1, le=MAX_STARTS, description="starts: the case's design (or "
                        f"x0), then random (at most {MAX_STARTS})")
    x0: dict[str, float] | None = Field(None, description="first start (display units)")
    maxiter: int = Field(4000, ge=1, le=MAX_LOCAL_ITERATIONS,
                         description=f"iterations per start (at most {MAX_LOCAL_ITERATIONS})")
    xatol: float = Field(1e-9, gt=0, description="normalised step tolerance")
    fatol: float = Field(1e-14, gt=0, description="objective tolerance")
    adaptive: bool = Field(True, description="dimension-adapted Nelder-Mead parameters")
    initial_step: float = Field(0.1, gt=0, le=0.5, description="simplex edge, normalised")
    penalty: float = Field(1e6, ge=0, description="weight of the constraint violation")
    distinct_tol: float = Field(1e-3, gt=0, description="optima closer (normalised) are one")
    optimum_tol: float = Field(
        1e-6, ge=0, description="end points within this of the best objective reached it")


@register_solver
class Simplex(MultiStart):
    """Nelder-Mead (scipy) on the objective plus a violation penalty, in bounds-normalised
    coordinates; reports how many distinct optima the starts reach."""

    name = "simplex"
    Options = SimplexOptions
    options: SimplexOptions
    summary = "modified simplex: scipy Nelder-Mead with bounds, multi-start (generic)"
    test_options = {"starts": 3}

    def _objective(self, u: Floats) -> float:
        """The objective plus ``penalty`` times the violation (:attr:`Evaluation.violation`,
        here for the one row in Python: scipy calls this once per evaluation and the
        array path's dozen numpy calls on two numbers were a tenth of its cost; the same
        sum, term by term in the same order)."""
        ev = self.problem.evaluate(self.problem.from_unit(u)[None, :])
        violation = 0.0
        for g in ev.g[0].tolist():
            if g > FEASIBILITY_TOL:
                violation += g - FEASIBILITY_TOL
            elif g != g:  # NaN: infinitely violated
                violation = math.inf
        return float(ev.f[0]) + self.options.penalty * violation

    def local_solve(self, x0: Floats) -> tuple[Floats, StartRecord]:
        from scipy.optimize import minimize  # scipy.optimize: 0.5 s, only for a run

        o = self.options
        u0 = np.clip(self.problem.to_unit(x0), 0.0, 1.0)
        # scipy's default simplex is 5 % of each coordinate: degenerate near a bound
        step = np.where(u0 + o.initial_step <= 1.0, o.initial_step, -o.initial_step)
        simplex = np.vstack([u0, u0 + np.diag(step)])
        res = minimize(self.metered(self._objective, float), u0, method="Nelder-Mead",
                       bounds=[(0.0, 1.0)] * self.problem.n_var,
                       options={"maxiter": o.maxiter, "xatol": o.xatol, "fatol": o.fatol,
                                "adaptive": o.adaptive, "initial_simplex": simplex})
        x = self.problem.from_unit(res.x)
        return x, {"success": bool(res.success), "message": str(res.message),
                   "nfev": int(res.nfev)}

    def reached(self) -> Bools:
        """Starts whose end point is feasible and within optimum_tol of the best objective
        (Nelder-Mead's own flag only says whether its tolerances were met in maxiter: on a
        flat valley a start can reach the optimum's level without meeting them). The
        best design is still taken only from starts that met them (``converged``)."""
        assert self.ev is not None
        best = np.min(np.where(self.ev.feasible, self.ev.f, np.inf))
        in_bounds = np.array([r["in_bounds"] for r in self.results], dtype=bool)
        return self.ev.feasible & (self.ev.f <= best + self.options.optimum_tol) & in_bounds

    def notes(self) -> list[str]:
        return [self.distinct_summary("optima", "starts ended above the best objective"),
                *self.convergence_notes()]
