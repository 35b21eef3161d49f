"""``newton_pp``: precision-point equations solved by scipy's root finder from several
starts (Ahn et al., Sec 3: n + 1 precision points give n equations).

scipy.optimize is imported where a start is solved (scipy is slow to import)."""

from __future__ import annotations

from typing import Literal

import numpy as np
from pydantic import Field

from camopt.config.models import MAX_STARTS
from camopt.core.capabilities import HasResiduals
from camopt.core.problem import Problem
from camopt.errors import SolverError
from camopt.mechanics import Floats
from camopt.solvers.multistart import MultiStart, MultiStartOptions, StartRecord
from camopt.solvers.registry import register_solver


class NewtonOptions(MultiStartOptions):
    """Options of ``newton_pp``."""

    name: Literal["newton_pp"] = "newton_pp"
    starts: int = Field(10, ge=1, le=MAX_STARTS,
                        description="starts: the case's design, then random "
                        f"(at most {MAX_STARTS})")
    method: Literal["hybr", "lm"] = Field("hybr", description="scipy.optimize.root method")
    xtol: float = Field(1e-13, gt=0, description="relative step tolerance")
    residual_tol: float = Field(1e-9, gt=0, description="a root needs max |residual| below")
    distinct_tol: float = Field(1e-6, gt=0, description="roots closer (normalised) are one")
    x0: dict[str, float] | None = Field(None, description="first start (display units)")


@register_solver
class NewtonPP(MultiStart):
    """Roots of a case's residual equations; reports every distinct root."""

    name = "newton_pp"
    Options = NewtonOptions
    options: NewtonOptions
    requires = (HasResiduals,)
    summary = "precision-point equations by scipy.optimize.root from several starts"

    def __init__(self, problem: Problem, options: NewtonOptions, rng: np.random.Generator
                 ) -> None:
        super().__init__(problem, options, rng)
        assert isinstance(problem, HasResiduals)
        self.equations: HasResiduals = problem
        n_eq = problem.residuals(self.starts[:1]).shape[1]
        if n_eq != problem.n_var:
            raise SolverError(f"newton_pp needs as many equations as unknowns: the case has "
                              f"{n_eq} equations for {problem.n_var} unknowns")

    def _residual(self, u: Floats) -> Floats:
        return self.equations.residuals(self.problem.from_unit(u)[None, :])[0]

    def jacobian_condition(self, x: Floats) -> float:
        """Condition number of the residuals' Jacobian (central differences, in the
        bounds-normalised variables), evaluated in one vectorised call."""
        u = self.problem.to_unit(x)
        h = 1e-6
        E = np.eye(len(u)) * h
        U = np.vstack([u + E, u - E])
        R = self.equations.residuals(self.problem.from_unit(U))
        J = (R[: len(u)] - R[len(u):]).T / (2 * h)
        return float(np.linalg.cond(J))

    def local_solve(self, x0: Floats) -> tuple[Floats, StartRecord]:
        from scipy.optimize import root  # scipy.optimize: 0.5 s, only for a run

        equations = self.metered(self._residual, lambda r: float(np.max(np.abs(r))))
        sol = root(equations, self.problem.to_unit(x0), method=self.options.method,
                   options={"xtol": self.options.xtol} if self.options.method == "hybr"
                   else {"xtol": self.options.xtol, "ftol": 1e-15})
        x = self.problem.from_unit(sol.x)
        residual = float(np.max(np.abs(self.equations.residuals(x[None, :])[0])))
        success = bool(residual <= self.options.residual_tol and np.all(np.isfinite(x)))
        return x, {"success": success, "residual_max": residual,
                   "jacobian_cond": self.jacobian_condition(x) if success else float("nan"),
                   "in_bounds": bool(np.all((x >= self.lo) & (x <= self.hi))),
                   "message": str(sol.message), "nfev": int(sol.nfev)}

    def stopped_record(self, x: Floats) -> StartRecord:
        """A start the run's budget stopped: its best point's largest residual (no
        condition number: it is not a root)."""
        residual = float(np.max(np.abs(self.equations.residuals(x[None, :])[0])))
        return {"residual_max": residual, "jacobian_cond": float("nan")}

    def notes(self) -> list[str]:
        return [self.distinct_summary("roots", "starts found no root inside the bounds"),
                *self.convergence_notes()]
