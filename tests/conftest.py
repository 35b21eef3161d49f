"""Shared fixtures: paths, the paper data, and a tiny 'sphere' case for solver contracts."""

from __future__ import annotations

import sys
from pathlib import Path
from typing import Literal

import numpy as np
import pytest

from camopt.cases import CaseSpec, register_case
from camopt.config import models
from camopt.core.problem import Evaluation, Problem, Variable

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

ROOT = Path(__file__).resolve().parents[1]
DATA = Path(__file__).resolve().parent / "data"
CONFIGS = ROOT / "configs"
VELOCITY_PAPER = CONFIGS / "reference" / "vcb_velocity_paper.toml"
"""The VCB velocity design in the paper's space (tests that pin its behaviour)."""


@pytest.fixture(scope="session")
def reported() -> dict:
    """The papers' reported numbers (copied from shared/reference/reported.toml)."""
    return tomllib.loads((DATA / "reported.toml").read_text())


class SphereConfig(models.CaseConfig):
    """Test-only case: shifted sphere with one linear constraint and an integer variable."""

    kind: Literal["sphere"] = "sphere"
    n_var: int = 4
    integer_first: bool = False


class SphereProblem(Problem):
    """f = sum((x - 0.3)^2) on [-1, 1]^n; constraint x0 + x1 <= 1.5 (inactive at optimum)."""

    objective_name = "f"

    def __init__(self, config: SphereConfig) -> None:
        self.variables = tuple(
            Variable(f"x{i}", -1.0, 1.0, integer=(i == 0 and config.integer_first))
            for i in range(config.n_var)
        )
        self.constraint_names = ("sum01",)

    def evaluate(self, X: np.ndarray) -> Evaluation:
        X = np.atleast_2d(X)
        target = np.where(self.integer, 0.0, 0.3)
        f = np.sum((X - target) ** 2, axis=1)
        g = (X[:, 0] + X[:, 1] - 1.5)[:, None]
        return Evaluation(f, g, {"norm": np.linalg.norm(X, axis=1)})


SPHERE = register_case(CaseSpec(kind="sphere", config=SphereConfig, problem=SphereProblem,
                                default_solver="de_gr", summary="test-only shifted sphere"))
"""The test-only case, registered like any plugin case (no monkeypatching)."""


@pytest.fixture(scope="session")
def fast_run(tmp_path_factory) -> Path:
    """A finished fast-switch run archive (the paper's enumeration: seconds), to copy and
    craft; never written to."""
    from typer.testing import CliRunner

    from camopt.cli import app

    out = tmp_path_factory.mktemp("fast") / "run.h5"
    r = CliRunner().invoke(app, ["run", str(CONFIGS / "fast_switch.toml"), "--out", str(out),
                                 "--quiet"])
    assert r.exit_code == 0, r.output
    return out


@pytest.fixture
def sphere_case() -> type[SphereProblem]:
    """The sphere case's Problem class (the kind is registered at import)."""
    return SphereProblem
