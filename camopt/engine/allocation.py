"""Tolerance allocation: the cheapest tolerance class a design reaches its yield target in,
and what tightening one input buys (``camopt tolerance RUN --allocate``).

Every class of the case (:meth:`camopt.cases.CaseSpec.class_names`, cheapest first) is
evaluated on the same unit draws (common random numbers: ``SeedSequence(seed)``, scaled by
each class's half-widths), so the yields of two classes differ by what the tolerances
change, not by sampling noise. A class *reaches* the target when the Clopper-Pearson lower bound of
its yield does (the rule of a robust run's final check, :mod:`camopt.engine.robust`).
Then, starting from the cheapest class, each input alone is tightened to the tolerance the
cheapest class that reaches the target gives it (the tightest class when none does): the
yield each of these one-input changes buys says where the money is best spent.

The classes' relative costs are documented by each case (docs/tolerance.md), not computed:
they rank the classes, nothing more.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np

from camopt.cases import get_case
from camopt.core.problem import FEASIBILITY_TOL
from camopt.core.runview import RunView
from camopt.core.stats import success_rate
from camopt.core.variation import Distribution, Vary, assign_variants, variants_of
from camopt.engine.tolerance import (
    class_varies,
    draw_inputs,
    evaluate_inputs,
    nominal_inputs,
    problem_of,
)
from camopt.errors import CamoptError


@dataclass(frozen=True)
class ClassYield:
    """One class's yield on the common draws: the share of samples meeting every
    constraint of the run, its Clopper-Pearson interval and whether its lower bound reaches the
    target."""

    name: str
    relative_cost: float
    yield_: float
    low: float
    high: float
    reaches_target: bool


@dataclass(frozen=True)
class Tightening:
    """The cheapest class with one input tightened to the chosen class's tolerance."""

    input: str
    tolerance_from: str
    tolerance_to: str
    yield_: float
    gain: float


@dataclass(frozen=True)
class Allocation:
    """``camopt tolerance --allocate``'s result (``to_json`` is its JSON document)."""

    run: str
    samples: int
    seed: int
    target: float
    confidence: float
    classes: tuple[ClassYield, ...]
    chosen: str | None
    """The cheapest class that reaches the target; None when none does."""
    tightenings: tuple[Tightening, ...]

    def to_json(self) -> dict[str, object]:
        def row(obj: object) -> dict[str, object]:
            d = asdict(obj)  # type: ignore[call-overload]
            d["yield"] = d.pop("yield_")
            return d

        return {"run": self.run, "samples": self.samples, "seed": self.seed,
                "target": self.target, "confidence": self.confidence,
                "classes": [row(c) for c in self.classes], "chosen": self.chosen,
                "tightenings": [row(t) for t in self.tightenings]}


def class_yield(name: str, cost: float, passed: int, samples: int, target: float,
                confidence: float) -> ClassYield:
    """A class's yield ``passed`` / ``samples`` with its Clopper-Pearson interval; the
    class reaches ``target`` when the interval's lower end does (low >= target): the
    point estimate alone would pick a class that misses the target by sampling luck
    as often as not when its true yield sits at the target."""
    rate = success_rate(passed, samples, confidence)
    return ClassYield(name, cost, passed / samples, rate["ci_low"], rate["ci_high"],
                      rate["ci_low"] >= target)


def _text(v: Vary) -> str:
    return f"±{v.tolerance:g}{'%' if v.relative else ''}"


def allocate(run: RunView, target: float, samples: int, seed: int,
             distribution: Distribution = Distribution.uniform,
             confidence: float = 0.95) -> Allocation:
    """Yield of the run's best design in every tolerance class of its case, the cheapest
    class whose yield's lower bound reaches ``target``, and the yield each input
    tightened alone from the cheapest class buys (module docstring)."""
    if not 0 < target <= 1:
        raise CamoptError(f"{run.path}: --target: {target}: a share in (0, 1]")
    if samples < 2:
        raise CamoptError(f"{run.path}: --samples: {samples}: at least 2")
    spec = get_case(run.kind)
    problem = problem_of(run)
    names = spec.class_names()
    plans = {name: class_varies(run, problem, name) for name in names}
    inputs = [v.name for v in plans[names[0]]]
    if any([v.name for v in plans[n]] != inputs for n in names):
        raise CamoptError(f"{run.path}: --allocate: the classes of case '{run.kind}' "
                          "tolerance different inputs; compare them with --class")
    nominal = nominal_inputs(run, problem, plans[names[0]])
    unit = draw_inputs(seed, samples, np.zeros(len(inputs)), np.ones(len(inputs)),
                       distribution)
    # each draw judged under one of the case's model variants, as in camopt tolerance
    variant = assign_variants(samples, len(variants_of(problem)))

    def passes(varies: list[Vary]) -> int:
        half = np.array([v.half_width(x) for v, x in zip(varies, nominal)])
        ev, _ = evaluate_inputs(run, problem, varies, nominal + unit * half, describe=False,
                                variant=variant)
        return int(np.count_nonzero((ev.g <= FEASIBILITY_TOL).all(axis=1)))

    classes = [class_yield(name, spec.class_cost(name), passes(plans[name]), samples, target,
                           confidence) for name in names]
    chosen = next((c.name for c in classes if c.reaches_target), None)
    cheapest = plans[names[0]]
    goal = plans[chosen if chosen is not None else names[-1]]
    base = classes[0].yield_
    tightenings = []
    for j, (loose, tight) in enumerate(zip(cheapest, goal)):
        if _text(loose) == _text(tight):
            continue
        varies = [*cheapest[:j], tight, *cheapest[j + 1:]]
        y = passes(varies) / samples
        tightenings.append(Tightening(loose.name, _text(loose), _text(tight), y, y - base))
    tightenings.sort(key=lambda t: -t.gain)
    return Allocation(run.path, samples, seed, target, confidence, tuple(classes), chosen,
                      tuple(tightenings))
