"""Pareto fronts of multi-objective runs, read from their archives: the rows ``show``
prints and the hypervolume ``compare`` reports (pymoo's indicator).

A run is multi-objective when its solver's options name ``objectives`` (``nsga2``); its
archive's table holds the Pareto set, one row per design with every metric.

pymoo is imported where used (the hypervolume; pymoo is slow to import)."""

from __future__ import annotations

import numpy as np

from camopt.core.documents import FrontsCompared, ParetoSummary, Row
from camopt.core.runview import RunView
from camopt.mechanics import Floats

REFERENCE_MARGIN = 0.1
"""The common reference point lies this share of the union's range beyond its nadir."""


def objectives(run: RunView) -> tuple[tuple[str, ...], Floats]:
    """A run's objective names and their signs (+1 minimised, -1 maximised); no names for a
    single-objective run."""
    names = tuple(run.solver.get("objectives") or ())
    maximise = set(run.solver.get("maximise") or ())
    return names, np.array([-1.0 if n in maximise else 1.0 for n in names])


def rows(run: RunView) -> list[Row] | None:
    """The Pareto set as rows of the objectives' metrics and ``feasible`` (None for a
    single-objective run)."""
    names, _ = objectives(run)
    if len(names) < 2:
        return None
    return [{**{n: row.get(n) for n in names}, "feasible": bool(row.get("feasible"))}
            for row in run.table]


def summary(run: RunView) -> ParetoSummary | None:
    """What a Pareto run found, for the summary ``show`` and ``report`` lead with (None
    for a single-objective run): the objectives with their senses, the feasible front's
    size and extent (least and greatest of each objective), its knee, and what the
    headline (best) design is. The knee is the front member nearest the ideal point with
    every objective normalised by the front's extent (0 at the best, 1 at the worst
    value). The headline design is the case's scalar objective's best, which need not
    be on the front: ``headline`` says whether it is, or how many front designs dominate
    it."""
    names, sign = objectives(run)
    if len(names) < 2:
        return None
    f = front(run)
    doc: ParetoSummary = {
        "objectives": [{"name": n, "sense": "min" if s > 0 else "max"}
                       for n, s in zip(names, sign)],
        "front_size": int(len(f)), "designs": len(run.table)}
    if not len(f):
        doc["extent"], doc["knee"] = None, None
        doc["headline"] = "no feasible design on the front"
        return doc
    doc["extent"] = {n: [float(lo), float(hi)] for n, lo, hi in
                     zip(names, f.min(axis=0), f.max(axis=0))}
    g = f * sign  # minimisation form
    ideal, nadir = g.min(axis=0), g.max(axis=0)
    span = np.where(nadir > ideal, nadir - ideal, 1.0)
    knee = int(np.argmin(np.linalg.norm((g - ideal) / span, axis=1)))
    feasible_rows = [r for r in run.table if r.get("feasible")]
    doc["knee"] = {n: feasible_rows[knee].get(n) for n in (*run.best.x, *names)}
    best = np.array([float(run.best.metrics.get(n, np.nan)) for n in names]) * sign
    if not np.all(np.isfinite(best)):
        doc["headline"] = "the headline design does not report the objectives"
        return doc
    dominated = int(np.sum(np.all(g <= best, axis=1) & np.any(g < best, axis=1)))
    on_front = bool(np.any(np.all(np.isclose(g, best, rtol=1e-9, atol=0), axis=1)))
    what = f"the best by the run's scalar objective ({run.objective_name})"
    doc["headline_on_front"] = on_front and not dominated
    doc["headline_dominated_by"] = dominated
    doc["headline"] = (f"{what}, a member of the front" if on_front and not dominated else
                       f"{what}, dominated by {dominated} of the {len(f)} front designs"
                       if dominated else f"{what}, not on the front")
    return doc


def front(run: RunView) -> Floats:
    """The feasible Pareto designs' objectives, (n, n_obj), in their own units."""
    names, _ = objectives(run)
    values = [[r[n] for n in names] for r in rows(run) or [] if r["feasible"]]
    return np.array(values, dtype=float).reshape(-1, len(names))


def compare_fronts(runs: list[RunView]) -> FrontsCompared | None:
    """Hypervolume of each run's feasible front with one reference point for all (None
    unless every run is multi-objective on the same objectives and senses).

    Objectives are put in minimisation form and normalised by the union of the fronts
    (0 at its ideal, 1 at its nadir); the reference point is ``1 + REFERENCE_MARGIN`` on
    every axis, so each front's extreme designs count. A larger value is a better front;
    a run without a feasible design scores 0."""
    first = objectives(runs[0])
    if len(first[0]) < 2 or any(objectives(r)[0] != first[0]
                                or not np.array_equal(objectives(r)[1], first[1])
                                for r in runs):
        return None
    names, sign = first
    fronts = [front(r) * sign for r in runs]
    union = np.concatenate(fronts)
    if not len(union):
        return {"objectives": list(names), "reference_point": None,
                "values": [0.0 for _ in runs], "sizes": [0 for _ in runs]}
    ideal, nadir = union.min(axis=0), union.max(axis=0)
    span = np.where(nadir > ideal, nadir - ideal, 1.0)
    ref = np.full(len(names), 1.0 + REFERENCE_MARGIN)
    from pymoo.indicators.hv import HV  # pymoo only when a front is measured

    indicator = HV(ref_point=ref)
    values = [float(indicator((f - ideal) / span)) if len(f) else 0.0 for f in fronts]
    return {"objectives": list(names),
            "reference_point": ((ideal + ref * span) * sign).tolist(),
            "normalisation": {"ideal": (ideal * sign).tolist(), "nadir": (nadir * sign).tolist()},
            "values": values, "sizes": [len(f) for f in fronts]}
