"""Manufacturing variation of a design: which inputs vary, how they are drawn, and what a
draw outside an input's physical range means. Shared by ``camopt tolerance`` (one design,
many samples) and robust design (every candidate of a generation, a few samples each).

An input is a design variable (display units, ``kc1_n_per_mm``) or ``case.FIELD`` for a
case field the Problem can take per design (capability
:class:`~camopt.core.capabilities.VariesCase`). A draw that leaves the input's physical range
(a negative spring rate, a zero radius) is *marked*: the sample stays in the count and is
counted as failed (every constraint violated, objective and metrics NaN), so it can never
raise a yield (docs/tolerance.md, "Draws outside the physical range").
"""

from __future__ import annotations

import enum
import math
import re
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import annotated_types
import numpy as np

from camopt.config.models import CaseConfig, Plausible
from camopt.core import batch
from camopt.core.capabilities import HasVariants, VariesCase
from camopt.core.problem import Evaluation, Problem
from camopt.errors import CamoptError
from camopt.mechanics import Bools, Floats, Ints

CASE_PREFIX = "case."
_SPEC = re.compile(r"^(?P<name>[A-Za-z_][\w.]*)=(?:±|\+-|\+/-)(?P<value>[0-9.eE+-]+)"
                   r"(?P<pct>%?)$")


class Distribution(str, enum.Enum):
    """How a varied input is drawn within its tolerance."""

    uniform = "uniform"
    normal = "normal"


@dataclass(frozen=True)
class Vary:
    """One ``NAME=±X[%]``: the input, its tolerance and whether it is relative."""

    name: str
    tolerance: float
    relative: bool

    @property
    def is_case_field(self) -> bool:
        return self.name.startswith(CASE_PREFIX)

    @property
    def field(self) -> str:
        """The case field's own name (``l1_mm``), or the design variable's."""
        return self.name.removeprefix(CASE_PREFIX)

    def half_width(self, nominal: float) -> float:
        """X in the input's unit: a share of |nominal| when relative."""
        return abs(nominal) * self.tolerance / 100 if self.relative else self.tolerance


def parse_vary(source: str, text: str, key: str = "--vary") -> Vary:
    """``NAME=±X%`` (relative) or ``NAME=±X`` (in the input's unit); ``+-`` for ``±``."""
    m = _SPEC.match(text.replace(" ", ""))
    value = float("nan")
    if m:
        try:
            value = float(m["value"])
        except ValueError:
            pass
    if not m or not np.isfinite(value) or value < 0:
        raise CamoptError(f"{source}: {key}: {text!r}: expected NAME=±X% or NAME=±X with "
                          "X >= 0 (NAME a design variable or case.FIELD)")
    return Vary(m["name"], value, bool(m["pct"]))


def offered_fields(problem: Problem) -> tuple[str, ...]:
    """The case fields the Problem can vary per design (none without VariesCase)."""
    return problem.case_fields() if isinstance(problem, VariesCase) else ()


def applicable_defaults(problem: Problem, tolerances: Mapping[str, str], source: str,
                        key: str = "--vary") -> list[Vary]:
    """The case's documented tolerances (``CaseSpec.tolerances``) that apply to this
    Problem: its continuous design variables and the case fields it can vary per design."""
    applies = [v.name for v in problem.variables if not v.integer]
    applies += [CASE_PREFIX + f for f in offered_fields(problem)]
    return [parse_vary(source, f"{name}={tol}", key)
            for name, tol in tolerances.items() if name in applies]


def check_varies(problem: Problem, varies: Sequence[Vary], source: str, kind: str,
                 key: str = "--vary") -> None:
    """Every input is a continuous design variable or a case field the Problem can vary,
    named once (CamoptError naming ``key`` otherwise)."""
    offered = offered_fields(problem)
    for v in varies:
        if v.is_case_field:
            if v.field not in offered:
                can = ", ".join(CASE_PREFIX + f for f in offered) or "none"
                raise CamoptError(f"{source}: {key}: {v.name}: case '{kind}' cannot "
                                  f"vary it per design (case fields it can: {can})")
        elif v.name in problem.names:
            if problem.variables[problem.names.index(v.name)].integer:
                raise CamoptError(f"{source}: {key}: {v.name}: an integer variable "
                                  "(a count has no tolerance)")
        else:
            whose = "of the run" if key == "--vary" else "of the case"
            raise CamoptError(f"{source}: {key}: {v.name}: not a design variable {whose} "
                              f"({', '.join(problem.names)}) nor case.FIELD")
    names = [v.name for v in varies]
    twice = sorted({n for n in names if names.count(n) > 1})
    if twice:
        raise CamoptError(f"{source}: {key}: {twice[0]}: given twice")


def physical_range(problem: Problem, case_model: type[CaseConfig], vary: Vary
                   ) -> tuple[float, bool, float]:
    """``(lower, strict, upper)`` of an input's physical range in its own unit: a case
    field's range is what the case file accepts for it (``gt``/``ge`` and
    :class:`Plausible` metadata); a design variable whose search bounds lie at or above
    zero is a magnitude (length, radius, rate: > 0); other variables are unbounded."""
    if not vary.is_case_field:
        var = problem.variables[problem.names.index(vary.name)]
        return (0.0, True, math.inf) if var.lower >= 0 else (-math.inf, False, math.inf)
    lower, strict, upper = -math.inf, False, math.inf
    info = case_model.model_fields.get(vary.field)
    for meta in (info.metadata if info is not None else ()):
        if isinstance(meta, annotated_types.Gt) and float(meta.gt) >= lower:  # type: ignore[arg-type]
            lower, strict = float(meta.gt), True  # type: ignore[arg-type]
        elif isinstance(meta, annotated_types.Ge) and float(meta.ge) > lower:  # type: ignore[arg-type]
            lower, strict = float(meta.ge), False  # type: ignore[arg-type]
        elif isinstance(meta, Plausible):
            if meta.lower > lower:
                lower, strict = meta.lower, False
            upper = min(upper, meta.upper)
    return lower, strict, upper


def outside(values: Floats, ranges: Sequence[tuple[float, bool, float]]) -> Bools:
    """(rows,) bool: a row of input values (rows, k) with any input outside its range."""
    values = np.asarray(values, dtype=float)
    low = np.array([r[0] for r in ranges])
    strict = np.array([r[1] for r in ranges])
    high = np.array([r[2] for r in ranges])
    below = np.where(strict, values <= low, values < low)
    return np.asarray((below | (values > high)).any(axis=1))


def mark(ev: Evaluation, bad: Bools) -> Evaluation:
    """``ev`` with the rows ``bad`` (rows,) counted as failed: every constraint +inf,
    objective and metrics NaN (no physical part was made; its numbers mean nothing).

    Written into ``ev``'s own arrays where they are float arrays that own their data
    (what :mod:`camopt.core.batch` allocates for more than one chunk): a marked copy of
    a 10^6-sample VCB evaluation was another 520 bytes a sample; a Problem
    returns new arrays from every call and keeps none. Any other array (a view, which
    may share memory with another output, a read-only or a non-float array) is replaced
    by a marked copy and left as it was."""
    if not np.any(bad):
        return ev
    return Evaluation(_marked(ev.f, bad, np.nan), _marked(ev.g, bad[:, None], np.inf),
                      {k: _marked(v, bad, np.nan) for k, v in ev.extras.items()})


def _marked(a: Floats, rows: Bools, value: float) -> Floats:
    """``a`` with ``value`` where ``rows`` (broadcast to ``a``), in place when ``a`` is a
    writeable float array owning its data, else in a float copy."""
    a = np.asarray(a)
    if a.dtype.kind == "f" and a.flags.owndata and a.flags.writeable:
        np.copyto(a, value, where=np.broadcast_to(rows, a.shape))
        return a
    return np.where(rows, value, np.asarray(a, dtype=float))


def unit_draws(rng: np.random.Generator, n: int, k: int, distribution: Distribution
               ) -> Floats:
    """(n, k) draws in units of the half-width: uniform on [-1, 1], or normal with
    sigma = 1/3 (so ±X is the 3-sigma range)."""
    if distribution is Distribution.uniform:
        return rng.uniform(-1.0, 1.0, (n, k))
    return rng.standard_normal((n, k)) / 3


def draw(rng: np.random.Generator, n: int, nominal: Floats, half: Floats,
         distribution: Distribution) -> Floats:
    """``n`` samples of the inputs, (n, k): uniform on nominal +- half, or normal with
    sigma = half / 3."""
    return nominal + unit_draws(rng, n, len(nominal), distribution) * half


def variants_of(problem: Problem) -> tuple[str, ...]:
    """The model variants a Problem offers to draw over (capability
    :class:`~camopt.core.capabilities.HasVariants`; none without it)."""
    return problem.variants() if isinstance(problem, HasVariants) else ()


def assign_variants(n: int, m: int) -> Ints:
    """The variant of each of ``n`` draws among ``m`` (n,) int: draw ``j`` takes variant
    ``j mod m`` (stratified: each variant the same share, the draws being independent and
    identically distributed whatever their index; -1 for every draw when m = 0)."""
    return np.arange(n) % m if m else np.full(n, -1)


def apply(problem: Problem, X: Floats, varies: Sequence[Vary], values: Floats,
          describe: bool = False, size: int | None = None,
          progress: batch.RowsDone | None = None,
          variant: Ints | None = None) -> Evaluation:
    """Designs ``X`` (rows, n_var), SI, with the varied inputs set to ``values`` (rows, k)
    in the inputs' own units (display units for variables), evaluated in row chunks of
    ``size`` (:mod:`camopt.core.batch`; unset: its default): the case's ``describe_with`` when a
    case field varies, else ``describe`` or ``evaluate``; with ``variant`` (rows,) the
    case's ``describe_variants`` (capability :class:`HasVariants`), each row under its
    variant, with the descriptive metrics only if ``describe``."""
    X = np.array(X, dtype=float)
    fields = {}
    for j, v in enumerate(varies):
        if v.is_case_field:
            fields[v.field] = values[:, j]
        else:
            i = problem.names.index(v.name)
            X[:, i] = values[:, j] / problem.variables[i].scale
    assert not fields or isinstance(problem, VariesCase)
    if variant is not None and np.any(variant >= 0):
        assert isinstance(problem, HasVariants)
        # without ``describe`` the case's descriptive metrics are left out: robust
        # design's draws read the constraints and objective alone (~30 % of a VCB draw)
        return batch.describe_variants(problem, X, fields, variant, size, progress,
                                       detail=describe)
    if fields or describe:
        return batch.describe(problem, X, fields, size, progress)
    return batch.evaluate(problem, X, size, progress)
