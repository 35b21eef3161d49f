"""Views of archives for ``show``, ``compare``, ``report`` and ``export`` (no printing
here): each function builds one of the typed views of :mod:`camopt.reporting.views`,
whose ``to_json()`` is the JSON output.

The case registry, config models, scipy-backed statistics and the tolerance engine are
imported where used: ``camopt show`` builds its view without them."""

from __future__ import annotations

import math
import shlex
import sys
from collections.abc import Mapping, Sequence
from dataclasses import replace
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from camopt.cases import run_requirements
from camopt.config.raw import RawDoc
from camopt.core import pareto, stats
from camopt.core.documents import DesignCheck, ParetoSummary
from camopt.core.record import ExpectedYield
from camopt.core.requirements import (
    DEFAULT_YIELD_TARGET,
    Check,
    Requirement,
    Spread,
    check,
    margin_text,
    positional,
    sentence,
    value_text,
)
from camopt.core.requirements import verdict as verdict_of
from camopt.core.runview import RunView, design_values
from camopt.errors import ConfigError
from camopt.reporting.views import (
    Reference,
    ReferenceVerdict,
    RepeatRow,
    RobustDoc,
    RobustRow,
    RobustSummary,
    RobustYield,
    ShowView,
    Summary,
    SummaryRow,
    Verdict,
)
from camopt.reporting.views import jsonable as jsonable  # re-exported for the printers

if TYPE_CHECKING:  # built where runs are compared or a sweep ranked: show needs none
    from camopt.reporting.comparisons import (
        Comparison,
        SameObjective,
        Significance,
        SweepRanking,
    )

SHOW_KEYS = ("case", "solver", "best", "repeats", "table")


NOISE = 1e-12
"""Values below this in magnitude are round-off (a margin of 2.2e-14 %, a residual of
5e-16) and print as 0; the archive and JSON keep them."""


def format_value(value: Any) -> str:
    """A value as tables and the HTML report print it: 6 significant digits; infinities as
    'inf' (a stress with no bound, a design that never closes), NaN as 'n/a' (a quantity
    that does not exist for this design), booleans as yes/no, None as '-', round-off
    (below :data:`NOISE`) as 0."""
    if isinstance(value, bool):
        return "yes" if value else "no"
    if isinstance(value, float):
        if math.isnan(value):
            return "n/a"
        if math.isinf(value):
            return "inf" if value > 0 else "-inf"
        if abs(value) < NOISE:
            return "0"
        return f"{value:.6g}"
    if isinstance(value, (list, tuple)):
        return ", ".join(format_value(v) for v in value)
    return "-" if value is None else str(value)


def show(run: RunView) -> ShowView:
    """``show``'s view (its ``to_json()`` is the ``show --format json`` document): verdict
    ("pass"/"fail") with its sentence and requirements (each with name, limit, value,
    margin, pass), case, solver, best, repeats, table, the reference design with its own
    verdict, and for a multi-objective run (a solver with ``objectives``) ``pareto``, and
    a case's findings under their own names (``model_forms``, ``identifiability``). These
    keys are a contract scripts rely on; the two-column view is :func:`summary`."""
    repeats = tuple(RepeatRow(r.seed, r.fun, r.feasible, r.nfev, r.wall_s, r.converged_nit,
                              tuple(r.spawn_key), tuple(r.notes)) for r in run.repeats)
    expected(run)  # an older archive's estimate, made once: the verdict's spreads read it
    judged = verdict(run)
    ref = reference(run)
    rows = pareto.rows(run)
    return ShowView(
        verdict=judged, expected_yield=expected(run), next=next_step(run, judged),
        case=run.case, solver=run.solver, best=run.best, repeats=repeats, table=run.table,
        reference=ReferenceVerdict(ref, verdict(run, dict(ref.values))) if ref else None,
        pareto=rows, pareto_summary=pareto.summary(run) if rows is not None else None,
        robust=RobustDoc(run.robust, run.robust_check) if run.robust else None,
        robust_yield=robust_yield(run) if run.robust else None, findings=run.findings)


NEAR_LIMIT = -0.05
"""Robust summaries list a constraint's margin when either design comes within 5 % of its
limit (normalised g above this) at its nominal design or at the yield target."""


def robust_summary(run: RunView) -> RobustSummary | None:
    """A robust run's final check, the robust optimum beside the best nominally feasible
    design the search saw, on the same fresh draws: objective (nominal, mean, quantile),
    yield with its Clopper-Pearson interval, and the margins (normalised g, <= 0 met) of the
    constraints near their limits at the nominal design and at the yield target's order
    statistic. None for a nominal run."""
    check = run.robust_check
    if not check:
        return None
    designs = [d for d in (check.get("robust"), check.get("nominal")) if d]
    scalars = [k for k in designs[0] if k.startswith("objective_") or k.startswith("yield")]
    objective = designs[0].get("case_objective", run.objective_name)  # older archives
    rows = [RobustRow(k.replace("objective_", f"{objective} "),
                      tuple(d.get(k) for d in designs)) for k in scalars]
    for i, form in enumerate(designs[0].get("per_form", [])):  # the case's model forms
        rows.append(RobustRow(f"yield in form {form['form']}",
                              tuple(d["per_form"][i]["yield"] if d.get("per_form") else None
                                    for d in designs)))
    for c in designs[0]["margins"]:
        pairs = [d["margins"][c] for d in designs]
        if any(max(p["nominal"], p["at_target"]) > NEAR_LIMIT for p in pairs):
            rows.append(RobustRow(f"{c} nominal", tuple(p["nominal"] for p in pairs)))
            rows.append(RobustRow(f"{c} at target", tuple(p["at_target"] for p in pairs)))
    labels = ("robust optimum", "nominal best seen")[:len(designs)]
    return RobustSummary(labels, designs[0]["samples"], run.robust.get("yield_target"),
                         tuple(rows))


REFERENCE_PREFIXES = ("initial_", "original_")
"""Metric prefixes under which cases report their reference (vendor's, original) design."""


def reference(run: RunView) -> Reference:
    """The reference design the optimum is shown beside, under one name everywhere
    (``reference: vendor, Sec 2.3 and Table 2``: the case file's ``reference_label`` when
    it has one, else the case's ``CaseSpec.reference``):
    the metrics a case reports with a prefix of :data:`REFERENCE_PREFIXES`, completed by
    the ``[case]`` fields named as the design variables (the vendor's spring rates are
    the config's), else the case's ``reference_values`` (a paper's optimum), else the
    paper's reported values under the optimum's own names: its label ('' when there is
    none; the view is then false) and ``{name: value}`` keyed by the optimum's names
    (``objective`` included)."""
    from camopt.cases import get_case

    spec = get_case(run.kind)
    metrics = run.best.metrics
    # a case file may name its own reference design (``[case] reference_label``: another
    # maker's current cam), else the case's paper reference
    own = run.case.get("reference_label")
    own = own if isinstance(own, str) and own.strip() else None
    for prefix in REFERENCE_PREFIXES:
        values = {k[len(prefix):]: v for k, v in metrics.items() if k.startswith(prefix)}
        if values:
            for name in run.best.x:
                if name not in values and isinstance(run.case.get(name), (int, float)):
                    values[name] = run.case[name]
            label = own or spec.reference or prefix.rstrip("_") + " design"
            return Reference(f"reference: {label}", values)
    names = {run.objective_name, *run.best.x, *metrics}
    source = spec.reference_values or spec.paper
    values = {k: v for k, v in source.items() if k in names and not isinstance(v, list)}
    if run.objective_name in values:
        values["objective"] = values[run.objective_name]
    if not values:
        return Reference()
    return Reference(f"reference: {spec.reference or 'paper'}", values)


_ESTIMATED: dict[str, ExpectedYield] = {}
"""Expected yields estimated at show time for archives that lack one, by path (a process
shows an old archive's estimate once)."""


def expected(run: RunView) -> ExpectedYield:
    """The best design's quick expected yield (``value``, ``low``, ``high``, ``samples``,
    per-requirement spreads): as ``camopt run`` stored it, else (an archive older than the
    estimate) estimated now, the same way (:func:`camopt.engine.tolerance.expected_yield`,
    a few seconds), and marked ``"estimated": "at show time"``."""
    if run.expected_yield:
        return run.expected_yield
    if run.path not in _ESTIMATED:
        from camopt.engine.tolerance import expected_yield

        with np.errstate(all="ignore"):
            _ESTIMATED[run.path] = {**expected_yield(run), "estimated": "at show time"}
    return _ESTIMATED[run.path]


def spreads(run: RunView) -> dict[str, Spread]:
    """Per requirement name, its quantity's spread under the default tolerances (the
    stored estimate, or the one :func:`expected` made for an older archive; never a new
    one: ``camopt runs`` lists verdicts of many archives), what decides which passing
    requirement is at its limit."""
    estimate = run.expected_yield or _ESTIMATED.get(run.path, {})
    return {r["name"]: Spread(r.get("half_spread"), r["yield"])
            for r in estimate.get("requirements", [])}


def _checked(run: RunView) -> DesignCheck:
    """A robust run's final check of its optimum ({} for a nominal run)."""
    return (run.robust_check or {}).get("robust") or {}


def robust_yield(run: RunView) -> RobustYield | None:
    """A robust run's answer: the final check's yield of the robust optimum with its
    interval, samples and the target (``value``, ``low``, ``high``, ``samples``,
    ``target``, ``meets_target``: the interval's low end at or above the target); None for
    a nominal run."""
    checked = _checked(run)
    if not checked:
        return None
    target = run.robust.get("yield_target")
    low = checked.get("yield_low")
    return RobustYield(checked.get("yield"), low, checked.get("yield_high"),
                       checked.get("samples"), target,
                       None if target is None or low is None else low >= target)


def yield_text(y: Mapping[str, Any]) -> str:
    """``expected yield 0.0 % [0.0, 1.3] (300 draws of the case's tolerances)``, or why
    there is none."""
    if y.get("value") is None:
        return f"expected yield: not estimated ({y.get('reason', 'no estimate')})"
    when = ", estimated at show time" if y.get("estimated") else ""
    return (f"expected yield {100 * y['value']:.1f} % [{100 * y['low']:.1f}, "
            f"{100 * y['high']:.1f}] ({y['samples']} draws of the case's default "
            f"tolerances{when})") + "".join(
        f"; {adjustment_text(a)}" for a in y.get("adjustments") or ())


def adjustment_text(a: Mapping[str, Any]) -> str:
    """One adjustment's use over the draws (``camopt.engine.tolerance.adjustment_use``):
    ``set at assembly: closing springs' preload nut, median +1.2 mm (5-95 %: -3.1 to
    +4.4 of ±10 mm); 0.5 % of draws out of reach``."""
    unit, reach = a["unit"], format_value(a["reach"])
    if a["out_of_reach_share"] >= 1.0:
        used = f"no draw within ±{reach} {unit}"
    else:
        used = (f"median {a['p50']:+.2f} {unit} (5-95 %: {a['p05']:+.2f} to {a['p95']:+.2f} "
                f"of ±{reach} {unit})")
    return (f"set at assembly: {a['name']}, {used}; {100 * a['out_of_reach_share']:.1f} % "
            "of draws out of reach")


def robust_text(y: RobustYield) -> str:
    """``robust: yield 96.5 % [95.8, 97.0] against a 95 % target (20000 fresh draws)``."""
    target = "" if y.target is None else f" against a {100 * y.target:.3g} % target"
    met = {True: ": meets it", False: ": below it", None: ""}[y.meets_target]
    return (f"robust: yield {100 * _share(y.value):.1f} % [{100 * _share(y.low):.1f}, "
            f"{100 * _share(y.high):.1f}]{target}{met if target else ''} "
            f"({y.samples} fresh draws)")


def _share(value: float | None) -> float:
    return math.nan if value is None else float(value)


def next_step(run: RunView, judged: Verdict) -> str:
    """One line saying what to do next, fitting the result: for a failing design, the case
    file that requires what the search left out (``run.next_config``) or, when every
    repeat ended infeasible (more budget rarely helps then), the robust config beside the
    run's (``*_robust.toml``); for a pass below the yield target or at a limit, tolerance
    analysis and the robust config; for a green pass, the report and the DXF. Paths are
    quoted for a shell where they need it (a space, ';')."""
    path = shlex.quote(run.path)
    robust_cfg = robust_sibling(run)
    robust_run = (f"camopt run {shlex.quote(robust_cfg)}" if robust_cfg
                  else "a [robust] table in the case file (docs/tolerance.md)")
    robust_yield_doc = robust_yield(run)
    if robust_yield_doc is not None:
        if robust_yield_doc.meets_target is False:
            return (f"next: the robust yield is below its target: another tolerance_class "
                    f"(camopt tolerance {path} --allocate), a lower robust.yield_target or "
                    f"more budget (--set {budget_key(run)}=...)")
        return f"next: camopt report {path} (or camopt export {path} --format dxf)"
    if not run.best.feasible:
        why = (f"violates {', '.join(run.best.violated[:2])}" if run.best.violated
               else status(run).removeprefix("INFEASIBLE: "))
        if len(run.repeats) > 1:
            return (f"next: every repeat ended infeasible ({why}): more budget "
                    f"rarely helps; for parts made to tolerance: {robust_run}, else a wider "
                    "bound on the variables the constraints push against")
        return (f"next: no feasible design ({why}): more budget (--set "
                f"{budget_key(run)}=... or --repeats) or a wider bound on the variables "
                "the constraints push against")
    if judged.verdict != "pass":
        required = next_config(run)
        if required:
            return (f"next: camopt run {shlex.quote(required)} (requires what this run's "
                    "search leaves out)")
        return ("next: the run's search leaves out the requirements it fails: run a case "
                "file that requires them (a config of this kind with them as constraints)")
    if judged.grade != "pass":
        return (f"next: camopt tolerance {path} --samples 2000; for parts made to "
                f"tolerance: {robust_run}")
    return f"next: camopt report {path} (or camopt export {path} --format dxf)"


def next_config(run: RunView) -> str:
    """The case file the run's ``run.next_config`` names (relative to the run's own case
    file) when it exists and is not the run's own, else ''."""
    name = run.run.get("next_config")
    if not name or not run.config_path:
        return ""
    own = Path(run.config_path)
    target = own.parent / str(name)
    if not target.is_file() or target.resolve() == own.resolve():
        return ""
    return str(target)


def budget_key(run: RunView) -> str:
    """The option that bounds the run's search: ``solver.evaluations`` where the solver has
    one (cmaes: its generations are a ceiling the evaluations reach first), else its
    ``generations``, ``starts`` or ``iterations``; ``solver.generations`` when none is
    recorded (an older archive)."""
    for key in ("evaluations", "generations", "starts", "iterations", "maxiter"):
        if key in run.solver:
            return f"solver.{key}"
    return "solver.generations"


def robust_sibling(run: RunView) -> str:
    """The robust config beside the run's case file (``configs/vcb_velocity.toml`` ->
    ``configs/vcb_velocity_robust.toml``; else that of the file it ``extends``, else
    ``<kind>_robust.toml``) when it exists, else ''."""
    if not run.config_path:
        return ""
    p = Path(run.config_path)
    stems = [p.stem]
    try:
        base = extends_of(p.read_text(encoding="utf-8"))
    except (OSError, ValueError):  # unreadable, not UTF-8
        base = None
    if isinstance(base, str):
        stems.append(Path(base).stem)
    for stem in (*stems, run.kind):  # fast_switch_de.toml -> fast_switch_robust.toml
        sibling = p.with_name(f"{stem}_robust.toml")
        if sibling.is_file() and sibling.resolve() != p.resolve():
            return str(sibling)
    return ""


def extends_of(text: str) -> object:
    """The top-level ``extends`` of TOML ``text`` (None: none, or not TOML). Text that
    holds neither the word nor a backslash (a quoted key's escape) cannot name it: it is
    not parsed (``show``'s start-up: the TOML reader is not imported)."""
    if "extends" not in text and "\\" not in text:
        return None
    if sys.version_info >= (3, 11):
        import tomllib
    else:  # pragma: no cover
        import tomli as tomllib
    try:
        return tomllib.loads(text).get("extends")
    except ValueError:
        return None


def yield_target(run: RunView) -> float:
    """The share of parts the case requires to meet every requirement: a robust run's
    ``robust.yield_target``, else :data:`~camopt.core.requirements.DEFAULT_YIELD_TARGET`
    (the same as ``[robust]``'s default)."""
    target = (run.robust or {}).get("yield_target")
    return float(target) if isinstance(target, (int, float)) else DEFAULT_YIELD_TARGET


def judged_yield(run: RunView) -> stats.YieldInterval | None:
    """The yield a run's verdict is graded on: a robust run's final check on fresh draws,
    else the stored expected yield (or the one :func:`expected` made at show time; never
    a new one, as :func:`spreads`); None when there is none."""
    checked = _checked(run)
    if checked.get("yield") is not None:
        return stats.YieldInterval.of(checked)
    return stats.YieldInterval.of(run.expected_yield or _ESTIMATED.get(run.path) or {})


def verdict(run: RunView, values: Mapping[str, object] | None = None) -> Verdict:
    """Requirements evaluated on the best design (or on ``values``, the reference's),
    with the verdict ("pass"/"fail", None: not judged) and its sentence; the best
    design's passing requirements are judged at their limit against the spread of the
    expected-yield estimate (:func:`spreads`), the reference's against its band."""
    reqs = run_requirements(run, run.best.violated if values is None else None)
    checks = check(reqs, design_values(run, values), spreads(run) if values is None else None)
    if values is None:
        return Verdict(tuple(checks), verdict_of(checks), sentence(checks),
                       judged_yield(run), yield_target(run))
    # a reference known by a few reported values: judged on those, incomplete when some
    # requirement's quantity is not among them (verdict None unless it already fails)
    known = [c for c in checks if c.passed is not None]
    judged = verdict_of(known) if known else None
    if judged == "pass" and len(known) < len(checks):
        judged = None
    words = sentence(known) if known else "no requirement can be checked on its values"
    if len(known) < len(checks):
        words += f" (checked {len(known)} of {len(checks)}: its other values are unknown)"
    return Verdict(tuple(known), judged, words)


VERDICT_COLUMNS = ("requirement", "limit", "value", "margin (% of band)", "pass")


def verdict_rows(checks: Sequence[Check]) -> list[list[str]]:
    """The verdict table's cells (:data:`VERDICT_COLUMNS`) of a :class:`Verdict`'s checks:
    values with their unit (6 significant digits), margins in 3 with their unit and, for
    a two-sided limit, as a share of its band; flags as yes/no; pass, FAIL or "at limit";
    a quantity the design does not reach is "n/a" and fails."""
    rows = []
    for c in checks:
        r = c.requirement
        raw = jsonable(c.value)  # not finite: a quantity the design does not reach
        flag = r.limit == "yes"
        unit = f" {r.unit}" if r.unit and raw is not None else ""
        value = (None if raw is None else bool(raw) if flag else raw)
        rows.append([r.name, r.limit, _value_cell(c, value, flag, unit),
                     _margin_cell(c, flag, unit), _pass_cell(c)])
    return rows


def _value_cell(c: Check, value: Any, flag: bool, unit: str) -> str:
    if value is None:
        return "n/a" if c.passed is False else "-"  # NaN: a quantity never reached
    if flag:
        return format_value(value)
    return value_text(c.requirement, float(value)) + unit


def _margin_cell(c: Check, flag: bool, unit: str) -> str:
    margin = jsonable(c.margin)  # an unbounded margin is shown as none
    if margin is None or flag:
        return "-"
    share = c.margin_share
    text = margin_text(c.requirement, float(margin)) + unit
    if share is None or text == "0" + unit:
        return text
    pct = float(f"{100 * share:.2g}")  # 2 significant digits, positional
    return text + f" ({positional(pct, 1 - math.floor(math.log10(abs(pct))) if pct else 0)}%)"


def _pass_cell(c: Check) -> str:
    if c.passed is None:
        return "-"
    if not c.passed:
        return "FAIL"
    return "at limit" if c.at_limit else "pass"


PARETO_COLUMNS = ("objective", "sense", "least", "greatest", "knee")


def pareto_rows(doc: ParetoSummary) -> list[list[str]]:
    """The Pareto summary's table (:data:`PARETO_COLUMNS`): each objective's extent over
    the feasible front and its value at the knee (``doc``: ``pareto.summary``'s)."""
    rows = []
    for o in doc["objectives"]:
        lo, hi = (doc["extent"] or {}).get(o["name"], (None, None))
        rows.append([o["name"], o["sense"], format_value(lo), format_value(hi),
                     format_value((doc["knee"] or {}).get(o["name"]))])
    return rows


def summary(run: RunView) -> Summary:
    """The run summary: the best design beside the reference design, row by row.

    ``rows`` are :class:`SummaryRow` s (section, name, optimum, reference) with sections
    ``objective``, ``variables`` and ``metrics``; the objective's name carries its unit
    (``objective_j``); reference-design metrics (``initial_*``) are folded into the
    ``reference`` column instead of being rows of their own. Values are raw (inf, NaN
    kept): ``to_json()`` turns them into null."""
    ref = reference(run)
    best = run.best
    prefixes = tuple(REFERENCE_PREFIXES)
    checked = _checked(run)
    case_objective = checked.get("case_objective", run.objective_name)
    rows = [SummaryRow("objective", run.objective_name, best.objective,
                       ref.get("objective", ref.get(run.objective_name)))]
    if case_objective != run.objective_name:
        # a robust run that minimised its margin: the reference's objective is the case's,
        # shown beside the optimum's own case objective, never beside the margin
        rows = [SummaryRow("objective", run.objective_name, best.objective, None),
                SummaryRow("objective", case_objective, checked.get("objective_nominal"),
                           ref.get("objective", ref.get(case_objective)))]
    rows.append(SummaryRow("objective", "feasible", best.feasible,
                           _bool_or_none(ref.get("feasible"))))
    rows += [SummaryRow("variables", k, v, ref.get(k)) for k, v in best.x.items()]
    shown = {run.objective_name, case_objective, "feasible", "objective", *best.x}
    rows += [SummaryRow("metrics", k, v, ref.get(k)) for k, v in best.metrics.items()
             if k not in shown and not k.startswith(prefixes)]
    return Summary(ref.label, tuple(rows))


def _bool_or_none(value: Any) -> bool | None:
    return None if value is None else bool(value)


def status(run: RunView) -> str:
    """One line on the best design: feasible with its active constraints, or infeasible
    naming what it violates (or, when no constraint is, why: the repeat's first note)."""
    best = run.best
    if best.feasible:
        active = ", ".join(best.active) or "none"
        return f"feasible; active constraints: {active}"
    if best.violated:
        return f"INFEASIBLE: violates {', '.join(best.violated)}"
    notes = next((r.notes for r in run.repeats if r.index == best.repeat), ())
    why = notes[0] if notes else "the solver returned no feasible design"
    return f"INFEASIBLE: {why}"


def _flatten(prefix: str, value: Any, out: RawDoc) -> None:
    if isinstance(value, dict):
        for k, v in value.items():
            _flatten(f"{prefix}.{k}" if prefix else k, v, out)
    else:
        out[prefix] = value


def repeat_statistics(run: RunView) -> stats.RunStatistics:
    """Statistics of the final objectives over a run's repeats (infeasible as +inf)."""
    return stats.run_statistics([r.fun for r in run.repeats],
                                [r.feasible for r in run.repeats], run.run.get("target"))


def _finals(run: RunView) -> tuple[np.ndarray, int]:
    """Final objectives as ranked (infeasible as +inf) and the number of successes."""
    f = stats.ranked([r.fun for r in run.repeats], [r.feasible for r in run.repeats])
    return f, repeat_statistics(run).successes


def significance(name_a: str, a: np.ndarray, k_a: int, name_b: str, b: np.ndarray,
                 k_b: int, equivalence: float | None = None, unit: str = ""
                 ) -> Significance:
    """Mann-Whitney test of the final objectives with the medians' difference (``effect``,
    B - A in ``unit``) beside the practical-equivalence ``threshold``
    (:func:`camopt.core.stats.equivalence_threshold`; ``equivalence`` an absolute one),
    success rates with Clopper-Pearson intervals and Fisher's exact test on them
    (``success_p_value``), ``decidable`` (whether these counts can give a p-value below
    alpha at all) and the verdict line."""
    from camopt.reporting.comparisons import Significance

    test = stats.compare_objectives(a, b)
    test = replace(test, threshold=stats.equivalence_threshold(test.median_a, test.median_b,
                                                               equivalence))
    return Significance(
        name_a, name_b, test, decidable=stats.min_p_value(len(a), len(b)) < stats.ALPHA,
        success_a=stats.success_rate(k_a, len(a)), success_b=stats.success_rate(k_b, len(b)),
        success_p_value=stats.compare_success(k_a, len(a), k_b, len(b)),
        verdict=stats.verdict(name_a, name_b, test, unit=unit))


def compare(runs: list[RunView], equivalence: float | None = None) -> Comparison:
    """Config differences, best objectives, variables, metrics and repeat statistics;
    for two runs with repeats, a significance test of their final objectives (with the
    practical-equivalence threshold ``equivalence`` in the objective's unit, else the
    case's ``CaseSpec.equivalence``, else relative: :func:`significance`). Runs of
    different case kinds or objectives are not comparable (ConfigError against the second
    run's ``case_kind`` or ``objective_name``). Values are raw (inf and NaN kept, for
    tables); ``to_json()`` makes them null."""
    from camopt.reporting.comparisons import Comparison

    for run in runs[1:]:
        for key, mine, first in (("case_kind", run.kind, runs[0].kind),
                                 ("objective_name", run.objective_name,
                                  runs[0].objective_name)):
            if mine != first:
                raise ConfigError(run.path, key, f"{mine!r}, but {runs[0].path} has "
                                  f"{first!r}: runs of different kinds are not comparable")
    flat = []
    for run in runs:
        cfg: RawDoc = {}
        _flatten("", {"case": run.case, "solver": run.solver, "run": run.run}, cfg)
        flat.append(cfg)
    keys = sorted(set().union(*flat))
    differences = {k: [c.get(k) for c in flat] for k in keys
                   if any(c.get(k) != flat[0].get(k) for c in flat)}

    def side_by_side(section: str) -> dict[str, list[Any]]:
        names: list[str] = []
        for run in runs:
            names += [n for n in getattr(run.best, section) if n not in names]
        return {n: [getattr(run.best, section).get(n) for run in runs] for n in names}

    for run in runs:
        expected(run)  # as show: at limit judged against the tolerance spread
    return Comparison(
        runs=tuple(run.path for run in runs), objective_name=runs[0].objective_name,
        verdicts=tuple(verdict(run) for run in runs), config_differences=differences,
        objective=tuple(run.best.objective for run in runs),
        feasible=tuple(run.best.feasible for run in runs),
        x=side_by_side("x"), metrics=side_by_side("metrics"),
        same_objective_different_designs=same_objective_different_designs(runs),
        statistics=tuple(repeat_statistics(run) for run in runs),
        labels=("A", "B") if len(runs) == 2 else tuple(f"run {i + 1}"
                                                      for i in range(len(runs))),
        tests=_pairwise(runs, equivalence), hypervolume=pareto.compare_fronts(runs))


SAME_OBJECTIVE_RTOL = 1e-6
"""Objectives this close (relative), or both at or below the run's target, are one
objective reached ..."""
DIFFERENT_DESIGN_RTOL = 1e-3
"""... by different designs when a variable differs by more than this share of its
magnitude."""


def same_objective_different_designs(runs: list[RunView]) -> tuple[SameObjective, ...]:
    """Pairs of feasible runs whose best objectives agree (:data:`SAME_OBJECTIVE_RTOL`, or
    both reach the first run's target) while their designs differ
    (:data:`DIFFERENT_DESIGN_RTOL`): a flat objective or several optima, which the
    objective alone hides."""
    from camopt.reporting.comparisons import SameObjective

    found = []
    for i, a in enumerate(runs):
        for j in range(i + 1, len(runs)):
            b = runs[j]
            fa, fb = a.best.objective, b.best.objective
            target = runs[0].run.get("target")
            if not (a.best.feasible and b.best.feasible and math.isfinite(fa)
                    and math.isfinite(fb)):
                continue
            at_target = target is not None and max(fa, fb) <= target
            if not at_target and abs(fa - fb) > SAME_OBJECTIVE_RTOL * max(abs(fa), abs(fb)):
                continue
            differ = [n for n, va in a.best.x.items() if n in b.best.x and abs(
                va - b.best.x[n]) > DIFFERENT_DESIGN_RTOL * max(abs(va), abs(b.best.x[n]), 1e-12)]
            if differ:
                found.append(SameObjective((i, j), fa, tuple(differ)))
    return tuple(found)


def _pairwise(runs: list[RunView], equivalence: float | None) -> tuple[Significance, ...]:
    from camopt.cases import get_case
    from camopt.config.models import unit_of

    if len(runs) != 2 or min(len(r.repeats) for r in runs) < 2:
        return ()
    if equivalence is None:
        equivalence = get_case(runs[0].kind).equivalence
    (fa, ka), (fb, kb) = _finals(runs[0]), _finals(runs[1])
    return (significance("A", fa, ka, "B", fb, kb, equivalence,
                         unit_of(runs[0].objective_name)),)


def rank_sweep(spec: Any, results: dict) -> SweepRanking:
    """Grid points ranked by success rate, then median objective; each tested against
    the best point; judged by ``run.min_success_rate`` when set."""
    from camopt.core.stats import sweep_summary as summary
    from camopt.reporting.comparisons import RankedPoint, SweepRanking

    rows = summary(spec, results.values())
    order = sorted(rows, key=lambda r: (-r["success_rate"], r["median"]))
    finals: dict[int, list[float]] = {}
    for r in results.values():
        finals.setdefault(r.point, []).append(float(stats.ranked([r.fun], [r.feasible])[0]))
    best = order[0]
    ranking = []
    for rank, row in enumerate(order, 1):
        label = _point_label(spec, row["point"])
        vs_best = None
        if row is not best:
            b = np.array(finals.get(best["point"], []))
            a = np.array(finals.get(row["point"], []))
            vs_best = significance(label, a, row["successes"],
                                   _point_label(spec, best["point"]), b, best["successes"])
        ranking.append(RankedPoint(rank, label, row, vs_best))
    floor = spec.data["run"].get("min_success_rate")
    reqs = [Requirement(f"success rate, {r.label}", "success_rate", lower=float(floor),
                        source="run.min_success_rate (sweep --check)")
            for r in ranking] if floor is not None else []
    checks = [check([q], {"success_rate": r.row["success_rate"]})[0]
              for q, r in zip(reqs, ranking)]
    judged = Verdict(tuple(checks), verdict_of(checks), sentence(checks, nominal=False),
                     nominal=False) if checks \
        else Verdict((), None, "not judged: run.min_success_rate is not set (the sweep's "
                     "--check needs it)", nominal=False)
    return SweepRanking(judged, spec.source, spec.grid, tuple(spec.seeds), tuple(ranking))


def _point_label(spec: Any, index: int) -> str:
    point = spec.points()[index]
    return ", ".join(f"{k}={v}" for k, v in point.items()) or "base"
