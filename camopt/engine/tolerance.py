"""Tolerance analysis of a run's optimum: what survives parts made to tolerance.

Each varied input (a design variable of the run, or a ``case.`` field the case can take
per design, capability :class:`~camopt.core.capabilities.VariesCase`) is drawn around its
nominal value, uniformly within +-X or normally with sigma = X / 3, X relative (``%``) or
in the input's own unit. The nominal design, one row per input at each end of its
tolerance (the tornado chart's one-at-a-time swings) and every sample are evaluated
together in cache-sized row chunks (``Problem.describe`` through :mod:`camopt.core.batch`):
memory is the per-sample columns (inputs, objective, metrics, constraints: ~0.6 GB at
10^6 VCB samples, metrics constant on every row held once) plus one chunk's temporaries
and the summary's ranks, whatever the sample count (10^6 VCB samples peak at 0.90 GiB:
docs/design.md, bench/bench_tolerance.py). Reported: the
share of feasible samples (yield), the yield of each requirement of the case
(:mod:`camopt.core.requirements`) and the one that limits it, the 5th/50th/95th percentiles
of every raw metric (the objective over feasible samples only: elsewhere it holds the
search's penalty), and the Spearman rank correlation of every metric with every input
(scipy.stats), strongest first.
"""

from __future__ import annotations

import math
import shlex
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import cast

import numpy as np
from numpy.typing import NDArray

from camopt.cases import build_problem, get_case, run_requirements
from camopt.core.batch import RowsDone
from camopt.core.documents import (
    AdjustmentUse,
    Percentiles,
    RequirementSpread,
    Sensitivity,
    Swing,
    ToleranceDoc,
)
from camopt.core.problem import FEASIBILITY_TOL, Evaluation, Problem
from camopt.core.record import ExpectedYield
from camopt.core.runview import RunView
from camopt.core.stats import per_variant, share_interval
from camopt.core.variation import (  # noqa: F401 - Distribution, parse_vary: the CLI's names
    Distribution,
    Vary,
    applicable_defaults,
    apply,
    assign_variants,
    check_varies,
    draw,
    mark,
    outside,
    parse_vary,
    physical_range,
    variants_of,
)
from camopt.engine import interrupts
from camopt.engine.driver import validate
from camopt.errors import CamoptError

YIELD_CONFIDENCE = 0.95
"""Level of the yield's interval ``camopt tolerance`` reports."""


@dataclass
class Tolerance:
    """The result of :func:`analyse`: the inputs' nominal values and samples (input units),
    the evaluation of nominal, one-at-a-time ends and samples, and the summaries."""

    run_path: str
    varies: list[Vary]
    distribution: Distribution
    seed: int
    nominal_inputs: NDArray  # (k,)
    inputs: NDArray  # (n, k)
    nominal: Evaluation  # one row
    swings: Evaluation  # 2k rows: input j at -X (row 2j) and +X (row 2j + 1)
    samples: Evaluation  # n rows
    objective_name: str
    constraint_names: tuple[str, ...]
    summary: ToleranceDoc = field(default_factory=lambda: cast(ToleranceDoc, {}))
    """The ``tolerance --format json`` document (:func:`summarise`; set by :func:`analyse`)."""
    outside: NDArray = field(default_factory=lambda: np.zeros(0, dtype=bool))
    """(n,) samples with an input outside its physical range (counted as failed)."""
    run: RunView | None = None
    """The analysed run (its case's requirements give the yield per requirement)."""
    tolerance_class: str | None = None
    """The case's tolerance class the inputs were drawn from (None: ``--vary`` given)."""
    variants: tuple[str, ...] = ()
    """The case's model variants the samples were drawn over (none: one model)."""
    variant: NDArray = field(default_factory=lambda: np.zeros(0, dtype=int))
    """(n,) each sample's variant, an index into ``variants`` (empty without variants)."""

    def metric_columns(self, ev: Evaluation) -> dict[str, NDArray]:
        """The objective and every metric of an evaluation, (rows,) each. The objective is
        NaN where a row is infeasible: there it holds the search's penalty, not a value of
        the design (a penalised 23,517 against a nominal 1.56 J); metrics are raw."""
        f = np.where(ev.feasible, ev.f, np.nan)
        return {self.objective_name: f, **{k: np.asarray(v, dtype=float)
                                           for k, v in ev.extras.items()}}


def problem_of(run: RunView) -> Problem:
    config = validate({"case": run.case, "solver": run.solver, "run": run.run}, run.path)
    return build_problem(config.case)


def default_varies(run: RunView, tolerance_class: str | None = None) -> list[Vary]:
    """The tolerances of the case's class ``tolerance_class`` (None: the run's
    ``case.tolerance_class``, else the case's default class; docs/tolerance.md) that apply
    to this run: its design variables, and the case fields its Problem can vary per
    design."""
    return class_varies(run, problem_of(run), tolerance_class)


def class_varies(run: RunView, problem: Problem, tolerance_class: str | None,
                 key: str = "--class") -> list[Vary]:
    """:func:`default_varies` for a Problem already built."""
    name = tolerance_class if tolerance_class is not None else run.case.get("tolerance_class")
    tolerances = get_case(run.kind).tolerances_of(
        name, run.path, key if tolerance_class is not None else "case.tolerance_class")
    chosen = applicable_defaults(problem, tolerances, run.path)
    if not chosen:
        raise CamoptError(f"{run.path}: --vary: case '{run.kind}' documents no tolerance for "
                          "this run's inputs; give --vary")
    return chosen


def nominal_inputs(run: RunView, problem: Problem, varies: Sequence[Vary]) -> NDArray:
    """Nominal value of each varied input in its own unit (display units for variables)."""
    check_varies(problem, varies, run.path, run.kind)
    return np.array([float(run.case[v.field]) if v.is_case_field else float(run.best.x[v.name])
                     for v in varies], dtype=float)


def analyse(run: RunView, varies: Sequence[Vary], samples: int, seed: int,
            distribution: Distribution = Distribution.uniform,
            tolerance_class: str | None = None,
            progress: RowsDone | None = None) -> Tolerance:
    """Draw ``samples`` sets of the varied inputs from ``SeedSequence(seed)`` and evaluate
    them, the nominal design and the one-at-a-time ends together (row chunks; ``progress``
    is told the rows done, of 1 + 2 k + samples, after each). Where the case offers model
    variants (its kept model forms) sample ``j`` is judged under variant ``j mod m``;
    the nominal row and the ends under every variant at once (the case's own verdict)."""
    if not varies:
        raise CamoptError(f"{run.path}: --vary: give at least one input to vary")
    if not 2 <= samples <= EXACT_RANK_ROWS:
        raise CamoptError(f"{run.path}: --samples: {samples}: from 2 to {EXACT_RANK_ROWS}")
    problem = problem_of(run)
    nominal = nominal_inputs(run, problem, varies)
    half = np.array([v.half_width(x) for v, x in zip(varies, nominal)])
    k = len(varies)
    # one array of every row's inputs (nominal, ends, draws) and the draws a view of it:
    # a stacked copy was 8 k bytes a sample (120 MB at 10^6 draws of 15 inputs)
    values = np.empty((1 + 2 * k + samples, k))
    values[0] = nominal
    ends = values[1:1 + 2 * k]
    ends[:] = nominal
    ends[np.arange(0, 2 * k, 2), np.arange(k)] -= half
    ends[np.arange(1, 2 * k, 2), np.arange(k)] += half
    drawn = values[1 + 2 * k:]
    drawn[:] = draw_inputs(seed, samples, nominal, half, distribution)
    variants = variants_of(problem)
    variant = assign_variants(samples, len(variants))
    ev, bad = evaluate_inputs(run, problem, varies, values, describe=True,
                              progress=interrupts.checked(progress),
                              variant=np.r_[np.full(1 + 2 * k, -1), variant])
    ev = shared_constants(ev)
    result = Tolerance(run.path, list(varies), distribution, seed, nominal, drawn,
                       ev.take(0), ev.take(slice(1, 1 + 2 * k)),
                       ev.take(slice(1 + 2 * k, None)), problem.objective_name,
                       problem.constraint_names, outside=bad[1 + 2 * k:], run=run,
                       tolerance_class=tolerance_class, variants=variants,
                       variant=variant if variants else np.zeros(0, dtype=int))
    result.summary = summarise(result)
    return result


def shared_constants(ev: Evaluation) -> Evaluation:
    """``ev`` with each metric that holds one value on every row, to the bit (a design
    coefficient no varied input moves, a flag, a quantity the design does not have: NaN),
    held as that value broadcast to the rows: a read-only view of 8 bytes instead of
    8 bytes a row (the VCB describes 50 metrics, several of them constant: 8 MB each at
    10^6 samples). Every value read is the same."""
    extras = {}
    for name, values in ev.extras.items():
        a = np.asarray(values)
        if a.ndim == 1 and a.size > 1 and a.dtype.itemsize in (1, 2, 4, 8):
            bits = a.view(f"u{a.itemsize}")
            if np.all(bits == bits[0]):
                a = np.broadcast_to(a[:1].copy(), a.shape)
        extras[name] = a
    return Evaluation(ev.f, ev.g, extras)


def draw_inputs(seed: int, samples: int, nominal: NDArray, half: NDArray,
           distribution: Distribution) -> NDArray:
    """(samples, k) inputs drawn from ``SeedSequence(seed)``: the same unit draws for every
    tolerance class of the same inputs (common random numbers across classes)."""
    rng = np.random.default_rng(np.random.SeedSequence(seed))
    return draw(rng, samples, nominal, half, distribution)


def evaluate_inputs(run: RunView, problem: Problem, varies: Sequence[Vary], values: NDArray,
              describe: bool, progress: RowsDone | None = None,
              variant: NDArray | None = None) -> tuple[Evaluation, NDArray]:
    """The run's best design with its varied inputs set to ``values`` (rows, k), rows
    whose inputs leave their physical range counted as failed (docs/tolerance.md), and
    those rows (rows,) bool. ``progress`` is told the rows done after each chunk;
    ``variant`` (rows,) each row's model variant (-1 or None: every variant)."""
    x0 = problem.from_display(run.best.x)
    # apply makes the one full copy it sets the inputs in (a tiled x0 was a second one)
    ev = apply(problem, np.broadcast_to(x0, (len(values), len(x0))), varies, values,
               describe=describe, progress=progress, variant=variant)
    ranges = [physical_range(problem, get_case(run.kind).config, v) for v in varies]
    bad = outside(values, ranges)
    return mark(ev, bad), bad


def summarise(t: Tolerance) -> ToleranceDoc:
    """The ``tolerance --format json`` document."""
    nominal = {k: float(v[0]) for k, v in t.metric_columns(t.nominal).items()}
    columns = t.metric_columns(t.samples)
    swings = t.metric_columns(t.swings)
    metrics: dict[str, Percentiles] = {}
    sensitivity: dict[str, list[Sensitivity]] = {}
    tornado: dict[str, list[Swing]] = {}
    rhos = spearman_columns(t.inputs, columns)
    for name, values in columns.items():
        with np.errstate(invalid="ignore"):
            finite = values[~np.isnan(values)]
            p = np.percentile(finite, [5, 50, 95]) if finite.size else [np.nan] * 3
        metrics[name] = {"p05": float(p[0]), "p50": float(p[1]), "p95": float(p[2])}
        rho = rhos[name]  # the inputs by |rho|, strongest first (stable: unknown ones last)
        order = sorted(range(len(t.varies)),
                       key=lambda j: -abs(r) if (r := rho[j]) is not None else 1.0)
        sensitivity[name] = [{"input": t.varies[j].name, "spearman": rho[j]} for j in order]
        tornado[name] = [{"input": t.varies[j].name, "low": float(swings[name][2 * j]),
                          "high": float(swings[name][2 * j + 1])} for j in order]
    yields = requirement_yields(t, columns)
    low, high = _interval(int(np.count_nonzero(t.samples.feasible)), len(t.inputs))
    return {
        "run": t.run_path, "samples": int(len(t.inputs)), "seed": t.seed,
        "distribution": t.distribution.value,
        "vary": [{"input": v.name, "nominal": float(x), "tolerance": v.tolerance,
                  "unit": "%" if v.relative else "own", "half_width": v.half_width(x)}
                 for v, x in zip(t.varies, t.nominal_inputs)],
        "yield": float(np.mean(t.samples.feasible)),
        "yield_low": low, "yield_high": high, "yield_confidence": YIELD_CONFIDENCE,
        "forms": list(t.variants),
        "per_form": per_variant(t.samples.feasible, t.variant, t.variants, YIELD_CONFIDENCE),
        "tolerance_class": t.tolerance_class,
        "nominal_feasible": bool(t.nominal.feasible[0]),
        "nominal": nominal, "metrics": metrics, "sensitivity": sensitivity,
        "one_at_a_time": tornado,
        "outside_share": float(np.mean(t.outside)) if t.outside.size else 0.0,
        "violated_share": {c: float(np.mean(~(t.samples.g[:, i] <= FEASIBILITY_TOL)))
                           for i, c in enumerate(t.constraint_names)},
        "objective_over": "feasible samples (infeasible ones carry the search's penalty)",
        "requirements": yields,
        "limiting": _limiting(yields, columns),
        "adjustments": adjustment_use(t, columns),
    }


ADJUSTMENT_BINS = 10
"""Equal bins of an adjustment's reach in its histogram (``adjustment_use``)."""


def adjustment_use(t: Tolerance, columns: dict[str, NDArray]) -> list[AdjustmentUse]:
    """Each adjustment the case declares and the samples report (its metric): the travel
    the draws needed, at the 5th, 50th and 95th percentiles of the draws within reach, a
    histogram of those over the reach (``ADJUSTMENT_BINS`` equal bins), and the share of
    draws that need more than the reach (or that no travel sets: +inf)."""
    if t.run is None:
        return []
    from camopt.cases.registry import get_case

    out: list[AdjustmentUse] = []
    for adj in get_case(t.run.kind).adjustments:
        if adj.metric not in columns or adj.reach not in t.run.case:
            continue
        need, reach = columns[adj.metric], float(t.run.case[adj.reach])
        within = np.abs(need) <= reach  # NaN and +-inf: out of reach
        used = need[within]
        p = np.percentile(used, [5, 50, 95]) if used.size else [np.nan] * 3
        counts, edges = np.histogram(used, bins=ADJUSTMENT_BINS, range=(-reach, reach))
        out.append({"name": adj.name, "metric": adj.metric, "unit": adj.unit,
                    "target": adj.target, "reach": reach,
                    "p05": float(p[0]), "p50": float(p[1]), "p95": float(p[2]),
                    "histogram": {"edges": [float(e) for e in edges],
                                  "counts": [int(c) for c in counts]},
                    "out_of_reach_share": float(np.mean(~within))})
    return out


def _interval(passed: int, samples: int) -> tuple[float, float]:
    """The yield's 95 % interval (Clopper-Pearson, :func:`camopt.core.stats.share_interval`:
    the interval every yield camopt states comes with)."""
    low, high = share_interval(passed, samples, YIELD_CONFIDENCE)
    return float(low), float(high)


def _limiting(yields: list[RequirementSpread], columns: dict[str, NDArray]) -> str | None:
    """The quantity of the requirement with the least yield (first declared on a tie)
    among those the samples report as a metric: the tornado's default."""
    rows = [r for r in yields if r["quantity"] in columns]
    return min(rows, key=lambda r: r["yield"])["quantity"] if rows else None


def requirement_yields(t: Tolerance, columns: dict[str, NDArray]) -> list[RequirementSpread]:
    """Yield per requirement of the case (:mod:`camopt.core.requirements`) over the samples,
    with its margin's 5th and 50th percentiles and whether the nominal design passes;
    requirements whose quantity the samples do not report are left out."""
    from camopt.core.requirements import yields

    requirements = run_requirements(t.run) if t.run is not None else ()
    samples = {**columns, "feasible": t.samples.feasible.astype(float)}
    nominal = {**t.metric_columns(t.nominal), "feasible": t.nominal.feasible.astype(float)}
    out = yields(requirements, samples)
    by_name = {r.name: r for r in requirements}
    for row in out:
        row["nominal_pass"] = bool(by_name[row["name"]].passes(nominal[row["quantity"]])[0])
    return out


def average_ranks(values: NDArray) -> NDArray:
    """Ranks 1..n of a 1-D array, ties given the average of their ranks: what
    ``scipy.stats.rankdata`` (method "average") returns, the same floats (each rank is a
    whole or half number), without importing scipy.stats (~1.2 s: ``camopt
    show`` estimates an older archive's yield)."""
    a = np.asarray(values)
    order = np.argsort(a, kind="mergesort")
    ordered = a[order]
    new = np.r_[True, ordered[1:] != ordered[:-1]]
    first = np.flatnonzero(new)  # each tie group's start in sorted order
    ends = np.r_[first[1:], a.size]
    mean_rank = 0.5 * (first + 1 + ends)  # average of ranks first+1 .. ends
    ranks = np.empty(a.size, dtype=float)
    ranks[order] = np.repeat(mean_rank, ends - first)
    return ranks


def spearman_columns(inputs: NDArray, columns: dict[str, NDArray]
                     ) -> dict[str, list[float | None]]:
    """Spearman's rank correlation of every metric column with every input column.

    ``inputs`` (n, k) are the drawn inputs (finite); each column of ``columns`` is (n,)
    with NaN where a sample has no value (the objective of an infeasible sample). For
    each metric, rows where it is NaN are dropped, and rho is Pearson's correlation of
    the ranks (average ranks for ties, :func:`average_ranks`), which is
    ``scipy.stats.spearmanr`` of the pair. Each column is ranked once: a metric once,
    the inputs once per distinct set of dropped rows (most metrics share one: none),
    instead of both columns again for every pair (k x metrics rankings of 10^6 values).
    Metrics are grouped by their dropped rows first, so one group's input ranks (n x k)
    are held at a time.

    The sums are exact: twice the centred ranks are integers
    (:func:`doubled_ranks`), the inputs' held as int32 (4 bytes an input and sample:
    10^6 samples under 1 GiB) and their products summed in int64 (:data:`EXACT_RANK_ROWS`),
    so rho is the exact ratio rounded once, whatever the summation order or the BLAS
    threads (float sums were off by up to 5e-12 at 10^6 rows, 1.0 read 0.9999999999987).
    None where either column is constant (an input at +-0, a metric the inputs do not
    move) or fewer than 3 rows remain."""
    k = inputs.shape[1]
    if len(inputs) > EXACT_RANK_ROWS:
        raise ValueError(f"{len(inputs)} samples: Spearman's sums are exact for at most "
                         f"{EXACT_RANK_ROWS}")
    out: dict[str, list[float | None]] = {}
    groups: dict[bytes, list[str]] = {}  # the kept rows (packed) -> metrics that keep them
    for name, values in columns.items():
        keep = ~np.isnan(values)
        kept = values[keep]
        if kept.size < 3 or np.all(kept == kept[0]):
            out[name] = [None] * k
        else:
            groups.setdefault(np.packbits(keep).tobytes(), []).append(name)
    for names in groups.values():
        keep = ~np.isnan(columns[names[0]])
        r_in = np.empty((int(keep.sum()), k), dtype=np.int32)
        squares_in = []
        for j in range(k):  # column by column: one column's sort temporaries at a time
            r = doubled_ranks(inputs[keep, j])
            squares_in.append(int(r @ r))  # 0: a constant input
            r_in[:, j] = r
        for name in names:
            r_m = doubled_ranks(columns[name][keep])
            squares_m = int(r_m @ r_m)
            products = np.einsum("i,ij->j", r_m, r_in, dtype=np.int64)
            out[name] = [_correlation(int(products[j]), squares_m, squares_in[j])
                         for j in range(k)]
    return {name: out[name] for name in columns}


EXACT_RANK_ROWS = 2**21
"""Rows up to which :func:`spearman_columns` sums exactly in int64: every sum it forms is
at most the sum of squares of twice the centred ranks 1..n, (n^3 - n) / 3 (ties make it
less), which stays below 2^63 for n <= 2^21 (``camopt tolerance`` draws at most 10^6)."""


def doubled_ranks(values: NDArray) -> NDArray:
    """Twice each value's centred average rank, 2 rank - (n + 1), (n,) int64: integers in
    [-(n - 1), n - 1] (average ranks are whole or half numbers, their mean (n + 1) / 2)."""
    return (2.0 * average_ranks(values) - (values.size + 1)).astype(np.int64)


def _correlation(products: int, squares_a: int, squares_b: int) -> float | None:
    """Pearson's r of two centred integer columns from their exact sums: sum(a b),
    sum(a^2), sum(b^2); r^2 as the exact ratio rounded once (Python's int division),
    so a perfect correlation is exactly +-1. None when either column is constant."""
    if squares_a == 0 or squares_b == 0:
        return None
    return math.copysign(math.sqrt(products * products / (squares_a * squares_b)), products)


EXPECTED_YIELD_SAMPLES = 300
"""Draws of the quick expected-yield estimate ``run`` stores: a few seconds for every case,
and a 95 % interval about +-5 points wide at a yield near one half (``camopt tolerance`` for
a sharper one)."""


def expected_yield(run: RunView, samples: int = EXPECTED_YIELD_SAMPLES) -> ExpectedYield:
    """The quick expected yield of a run's best design: the share of ``samples`` draws of
    the case's default tolerances (:func:`default_varies`, uniform) whose design meets every
    requirement of the run (the run's constraints included; outside a robust run no draw
    does when the run calls its best design infeasible), with its Clopper-Pearson 95 %
    interval, and per requirement the share that meets it and half the 5-95 % spread of its quantity
    (what :meth:`~camopt.core.requirements.Requirement.at_limit` reads).

    The draws come from ``SeedSequence(run.seed)`` itself (the repeats use its children), so
    ``camopt tolerance RUN --samples 300 --seed <run.seed>`` draws the same parts. A case
    that documents no tolerance for the run's inputs gives ``value`` None and the reason.
    Keys: value, low, high, samples, seed, vary, requirements, command (or reason)."""
    from camopt.core.requirements import all_pass
    from camopt.core.stats import success_rate

    seed = int(run.run.get("seed", 0))
    # quoted for a shell (a path with a space or ';' pastes as one argument): as show's
    command = f"camopt tolerance {shlex.quote(run.path)} --samples {samples} --seed {seed}"
    try:
        varies = default_varies(run)
        with np.errstate(all="ignore"):  # a non-assembling draw is data (NaN), not noise
            t = analyse(run, varies, samples, seed)
    except CamoptError as exc:
        return {"value": None, "low": None, "high": None, "samples": 0, "seed": seed,
                "reason": str(exc).split(": ", 2)[-1], "requirements": []}
    # tied to the nominal verdict: a best design the run itself calls infeasible (a
    # solver's own verdict, such as Newton's unconverged starts) fails in every draw. Not
    # a robust run's: its verdict is the yield target on its final check's draws, not a
    # property of any one breaker, and that check counts each draw as it passes (a best
    # design at 99.8 % against a 99.9 % target would read 0 % here)
    feasible = t.samples.feasible & bool(run.best.feasible or run.robust)
    columns = {**t.metric_columns(t.samples), "feasible": feasible.astype(float)}
    ok = all_pass(run_requirements(run), columns) & ~t.outside
    rate = success_rate(int(ok.sum()), samples)
    return {"value": rate["rate"], "low": rate["ci_low"], "high": rate["ci_high"],
            "samples": samples, "seed": seed,
            "vary": [f"{v.name}=±{v.tolerance:g}{'%' if v.relative else ''}" for v in varies],
            "requirements": [{"name": r["name"], "yield": r["yield"],
                              "half_spread": r["half_spread"]}
                             for r in t.summary["requirements"]],
            # what the factory set on each draw, where the case models it (else no key)
            **({"adjustments": t.summary["adjustments"]}
               if t.summary.get("adjustments") else {}),
            "command": command}
