"""camopt's shipped config against other optimisers on the same Problem objects (issue #36).

Peers (optional, ``pip install 'camopt[peers]'``; a missing one is reported and skipped):
scipy's ``differential_evolution``, pycma (``cma``, BIPOP restarts), pymoo's DE and GA,
nevergrad's NGOpt, each at its documented settings and from camopt's start (:class:`Start`;
issue #48). Each solver minimises camopt's own Problem (``evaluate`` over a whole
population per call) for each objective, seeds interleaved in one process. A robust row
judges each solver's chosen design on fresh draws (:func:`score_fresh`); ``--peers
'scipy DE,pymoo DE'`` runs those peers alone; ``--set key=value`` changes camopt's config
(and so the budget) for a trial.

Constraints: pymoo takes the case's ``g`` as inequality constraints; scipy and pycma get a
scalar that ranks feasible designs by the objective and infeasible ones after every
feasible one, by their violation (``1e9 + 1e6 * violation``, each constraint's capped:
Deb's rules as a scalar).
Integer variables (fast switch coils) are rounded before every peer evaluation, as camopt's
solvers snap them.

Measured per solver and seed, through one wrapper around ``Problem.evaluate`` (the same
for camopt and every peer): the best design by Deb's rules among every one evaluated,
and the CPU time (``time.process_time``: other sessions on a shared host do not count)
at which each best-so-far was reached. Budget: the evaluations camopt's shipped config
used with that seed; a peer stops at its first generation at or past it. Reported:
the median over seeds of the best objective at equal budget, the feasible share of
seeds, and the median CPU to reach the best peer's median quality (``-`` when a solver
never reaches it; objectives within ``SAME`` relative are one quality).
Before any solver is timed the case's Problem evaluates a few designs once
(:func:`warm_up`): one-time costs (numba's kernels loaded from its cache, modules imported
on first use) would otherwise fall on whichever solver runs first, camopt at seed 0.
Quality is by Deb's rules (less violation, then lower objective): where no solver finds a
feasible design the least violation decides. Budgets are reduced (``OBJECTIVES``): the
seven rows at 5 seeds (16 for the robust VCB) take about 40 minutes in two processes on a
loaded 2-core host; ``--full`` runs the shipped budgets.
Run ``python -m bench.bench_peers [--full] [--peers names] [--set key=value ...] [seeds]
[objective ...]``; a row of :data:`MIN_SEEDS` runs with at least its seeds.
"""

from __future__ import annotations

import importlib.util
import statistics
import sys
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from camopt.core.problem import Problem
from camopt.engine.driver import load, prepare, run_repeat

CONFIGS = Path(__file__).resolve().parents[1] / "configs"
OBJECTIVES: dict[str, tuple[str, list[str]]] = {
    # the shipped configs with budgets reduced (the shipped budgets: `full`)
    "vcb_velocity": ("vcb_velocity.toml", ["solver.evaluations=15000"]),
    "emb": ("emb.toml", ["solver.iterations=100", "solver.polish.evaluations=3000"]),
    "fast_switch_de": ("fast_switch_de.toml", ["solver.generations=200"]),
    # the robust VCB at 3,600 evaluations of 8 draws: camopt's setting for that budget,
    # not the shipped search (DE 60 x 500 on 32 new draws a generation, then centring):
    # reduced to 20 x 120, DE ended 0.80 short of the target on fresh draws (median of 5
    # seeds; 0.71 of 16), a quarter of its seeds never nominally feasible. Active CMA-ES
    # from the centre, lambda = 50 (72 generations), on one set of draws for the repeat
    # (docs/design.md, "The robust VCB row"); no centring: the peers are compared as
    # searches
    "vcb_velocity_robust": ("vcb_velocity_robust.toml", [
        "solver.name=cmaes", "solver.active=true", "solver.population=50",
        "solver.evaluations=3600", "robust.samples=8", "robust.draws=repeat",
        "robust.check_samples=200", "robust.centre_generations=0"]),
    # the shipped budgets: each repeat takes 0.1-5 s
    "vcb_identify": ("vcb_identify.toml", []),
    "vcb_identify_dynamics": ("vcb_identify_dynamics.toml", []),
    "fast_switch_robust": ("fast_switch_robust.toml", []),
}
SEEDS = 9  # the reduced robust VCB reaches its peers' level in ~0.2 s: 5 seeds were noise
MIN_SEEDS = {"vcb_velocity_robust": 16}
"""Rows run with at least this many seeds whatever is asked: the robust VCB's chosen
designs fall 0.03-0.5 short of the target on fresh draws from seed to seed, for every
solver, and its 5-seed median moved by up to 0.07 from one set of seeds to the next."""
INFEASIBLE = 1e9  # a scalar peer's floor for infeasible designs (every feasible one is below)
SAME = 1e-6
"""Relative difference below which two objectives count as one quality: below the
models' own resolution (sampled measures, the local stages' tolerances); the fast
switch's 17.984828 and 17.984829 ms are one design."""


Quality = tuple[float, float]
"""(violation, objective) of a design, compared by Deb's rules: less violation first, then
the lower objective (violation 0: feasible). Where a solver finds no feasible design its least
violation is its quality."""


def at_least(q: Quality, ref: Quality) -> bool:
    """Whether ``q`` is as good as ``ref`` by Deb's rules, within ``SAME`` relative."""
    if ref[0] > 0:
        return q[0] <= ref[0] * (1 + SAME)
    return q[0] == 0 and q[1] <= ref[1] + SAME * abs(ref[1])


def median_quality(qs: list[Quality]) -> Quality:
    """The median seed's quality, seeds ordered by Deb's rules (the lower middle for an
    even count)."""
    return sorted(qs)[(len(qs) - 1) // 2]


def show(q: Quality) -> str:
    return f"{q[1]:.6f}" if q[0] == 0 else f"viol {q[0]:.9g}"


class Spent(Exception):
    """A peer asked for a batch when its budget was already spent (a polish or restart
    after the last generation): it stops there, with what it reached."""


@dataclass
class Trace:
    """Best design so far by Deb's rules against CPU seconds since the solver started."""

    budget: int | None = None
    start: float = field(default_factory=time.process_time)
    nfev: int = 0
    best: Quality = (np.inf, np.inf)
    best_x: NDArray | None = None
    cpu: list[float] = field(default_factory=list)
    value: list[Quality] = field(default_factory=list)
    total: float = np.inf
    """CPU seconds of the whole solve (set when it ends)."""
    fresh: Quality | None = None
    """A robust row: the chosen design's quality on fresh draws (:func:`score_fresh`)."""

    def record(self, X: NDArray, f: NDArray, violation: NDArray) -> None:
        self.nfev += len(f)
        v = np.where(np.isfinite(violation), violation, np.inf)
        f = np.where(np.isnan(f), np.inf, f)
        i = int(np.lexsort((f, v))[0])
        q = (float(v[i]), float(f[i]))
        if q < self.best:
            self.best, self.best_x = q, np.array(X[i], dtype=float)
            self.cpu.append(time.process_time() - self.start)
            self.value.append(q)

    def cpu_to(self, quality: Quality) -> float:
        """CPU seconds until the best-so-far was as good as ``quality`` (inf: never); a
        robust row: the whole solve's, if its fresh-draw quality is as good."""
        if self.fresh is not None:
            return self.total if at_least(self.fresh, quality) else np.inf
        for t, q in zip(self.cpu, self.value):
            if at_least(q, quality):
                return t
        return np.inf

    @property
    def quality(self) -> Quality:
        """What the solver's result is judged by: its best design's (violation,
        objective), a robust row's on fresh draws."""
        return self.best if self.fresh is None else self.fresh


def traced(problem: Problem, trace: Trace, snap_integers: bool) -> Callable[[NDArray], tuple]:
    """``X (n, n_var) -> (f, g, feasible, violation)`` through ``problem.evaluate``,
    recorded in ``trace``; integer variables rounded first when ``snap_integers``;
    :class:`Spent` once the trace's budget is spent."""
    lower, upper, integer = problem.lower, problem.upper, problem.integer

    def evaluate(X: NDArray) -> tuple[NDArray, NDArray, NDArray, NDArray]:
        if trace.budget is not None and trace.nfev >= trace.budget:
            raise Spent
        X = np.clip(np.atleast_2d(np.asarray(X, dtype=float)), lower, upper)
        if snap_integers and integer.any():
            X[:, integer] = np.rint(X[:, integer])
        ev = problem.evaluate(X)
        f = np.asarray(ev.f, dtype=float)
        trace.record(X, f, np.asarray(ev.violation, dtype=float))
        return f, np.asarray(ev.g, dtype=float), ev.feasible, ev.violation
    return evaluate


CAP = 1e3
"""A constraint's violation counted at most this in a scalar peer's penalty: a design
that does not assemble has infinite constraints (a robust candidate's order statistics
too), and with the sum capped instead of each term every such design had one penalty,
so scipy's DE saw a population of equal values and stopped (366 evaluations)."""


def scalar(evaluate: Callable[[NDArray], tuple], X: NDArray) -> NDArray:
    """Deb's rules as one number per design (for peers without constraints): the
    objective of a feasible design, else ``INFEASIBLE`` plus 10^6 x its violation, each
    constraint's capped at :data:`CAP`."""
    f, g, feasible, _ = evaluate(X)
    g = np.atleast_2d(np.where(np.isnan(g), np.inf, g)).reshape(len(f), -1)
    violation = np.minimum(np.maximum(g, 0.0), CAP).sum(axis=1)
    return np.where(feasible & np.isfinite(f), f, INFEASIBLE + 1e6 * violation)


def warm_up(problem: Problem) -> None:
    """Evaluate four designs of the case's own Problem (a robust run's base), untimed.
    Without it camopt, the first solver timed, was charged the VCB kernels' loading: 0.5 s
    to its first sampled candidate at seed 0 of the reduced robust VCB, against 0.17-0.29 s
    at seeds 1-3; a robust repeat's selection (its yield's interval) imported
    scipy.special on camopt's clock, ~0.8 s more at seed 0 of the robust fast switch."""
    base = getattr(problem, "base", problem)
    X = base.sample(np.random.default_rng(0), 4)
    base.evaluate(X)
    if base is not problem:  # a robust repeat's selection: scipy.special on first use
        score_fresh(problem, X[0])


@dataclass(frozen=True)
class Start:
    """Where camopt starts with a seed, handed to every peer: ``x0`` the single start
    of camopt's ``cmaes`` (the case's design, else the centre of the bounds; unit box),
    ``population(n)`` a first population drawn as camopt's population solvers draw
    theirs (uniform within the bounds from the repeat's generator; SI): its first rows
    are camopt's first generation when the sizes agree."""

    x0: NDArray
    child: np.random.SeedSequence
    problem: Problem

    def population(self, n: int) -> NDArray:
        return self.problem.sample(np.random.default_rng(self.child), n)


def start_of(problem: Problem, cfg, seed: int) -> Start:
    initial = problem.initial_x()
    x0 = (problem.lower + problem.upper) / 2 if initial is None else np.asarray(initial)
    child = np.random.SeedSequence(cfg.run.seed).spawn(seed + 1)[seed]
    return Start(np.clip(problem.to_unit(x0), 0, 1), child, problem)


SCORE_SEED = 20261128
"""The fresh draws a robust row's chosen designs are judged on: ``robust.check``'s draws
from this seed, none of any search's or camopt's selection's (those come from
``run.seed``)."""


def score_fresh(problem: Problem, x: NDArray | None) -> Quality:
    """A robust design on ``check_samples`` fresh draws: (shortfall of its yield's lower
    bound below the target, 0 when met; its nominal objective)."""
    from camopt.engine import robust

    if x is None:
        return (np.inf, np.inf)
    r = robust.check(problem, [x], SCORE_SEED)[0]  # type: ignore[arg-type]
    target = problem.plan.spec.yield_target  # type: ignore[attr-defined]
    return (max(0.0, target - r["yield_low"]), r["objective_nominal"])


# ---- the solvers: each (problem, budget, seed, trace, start) -> None --------------------
def run_camopt(cfg, problem: Problem, solver_cls, seed: int, trace: Trace) -> tuple[int, NDArray]:
    """camopt's shipped config, one repeat (seed child ``seed``); its nfev and result."""
    original = problem.evaluate

    def recording(X: NDArray):
        ev = original(X)
        trace.record(np.atleast_2d(X), np.asarray(ev.f, dtype=float),
                     np.asarray(ev.violation, dtype=float))
        return ev
    problem.evaluate = recording  # type: ignore[method-assign]
    try:
        child = np.random.SeedSequence(cfg.run.seed).spawn(seed + 1)[seed]
        rec = run_repeat(problem, solver_cls, cfg, child, seed, 1)
    finally:
        del problem.evaluate
    return rec.nfev, rec.x


def run_scipy_de(problem: Problem, budget: int, start: Start, seed: int, trace: Trace) -> None:
    """scipy's defaults (best1bin, popsize 15, dithered mutation (0.5, 1), recombination
    0.7, the L-BFGS-B polish), integer variables declared (``integrality``), the first
    population camopt's draws; ``tol=0``: its default (0.01) compares the population's
    spread with its mean, which the infeasible designs' 1e9 floor makes tiny (it stopped
    the robust fast switch after 186 evaluations), so it runs to the budget and its
    polish, after the last generation, is cut by the budget."""
    from scipy.optimize import differential_evolution

    evaluate = traced(problem, trace, snap_integers=True)
    pop = 15 * problem.n_var

    def func(x: NDArray) -> NDArray | float:
        x = np.asarray(x)
        values = scalar(evaluate, x.T)
        return values if x.ndim == 2 else float(values[0])
    differential_evolution(func, list(zip(problem.lower, problem.upper)),
                           maxiter=max(budget // pop - 1, 1), init=start.population(pop), tol=0,
                           integrality=problem.integer if problem.integer.any() else None,
                           vectorized=True, updating="deferred", rng=seed)


def run_pycma(problem: Problem, budget: int, start: Start, seed: int, trace: Trace) -> None:
    """pycma's BIPOP-CMA-ES (``cma.fmin2(..., restarts=9, bipop=True)``, its documented
    setting for multimodal functions) from camopt's start, sigma0 0.3 of each range (as
    camopt's ``cmaes``), bounds by its own BoundTransform, a generation per call."""
    import cma

    evaluate = traced(problem, trace, snap_integers=True)
    lo, span = problem.lower, problem.upper - problem.lower
    opts = {"bounds": [0, 1], "seed": seed + 1, "verbose": -9, "maxfevals": budget}
    cma.fmin2(None, start.x0, 0.3, opts, restarts=9, bipop=True,
              parallel_objective=lambda U: list(scalar(evaluate, lo + np.array(U) * span)))


def _pymoo(problem: Problem, budget: int, seed: int, trace: Trace, algorithm) -> None:
    from pymoo.core.problem import Problem as PymooProblem
    from pymoo.optimize import minimize

    evaluate = traced(problem, trace, snap_integers=True)

    class Wrapped(PymooProblem):
        def __init__(self) -> None:
            super().__init__(n_var=problem.n_var, n_obj=1, n_ieq_constr=problem.n_constr,
                             xl=problem.lower, xu=problem.upper)

        def _evaluate(self, X, out, *args, **kwargs):
            f, g, _, _ = evaluate(X)
            out["F"] = np.where(np.isfinite(f), f, 1e30)[:, None]
            out["G"] = np.where(np.isfinite(g), g, 1e30)

    minimize(Wrapped(), algorithm, ("n_eval", budget), seed=seed, verbose=False)


def run_pymoo_de(problem: Problem, budget: int, start: Start, seed: int, trace: Trace) -> None:
    """pymoo's DE as its documentation's example sets it (100, DE/rand/1/bin, CR 0.3,
    dithered F), the first population camopt's draws."""
    from pymoo.algorithms.soo.nonconvex.de import DE

    _pymoo(problem, budget, seed, trace, DE(pop_size=100, sampling=start.population(100),
                                            variant="DE/rand/1/bin", CR=0.3,
                                            dither="vector", jitter=False))


def run_pymoo_ga(problem: Problem, budget: int, start: Start, seed: int, trace: Trace) -> None:
    """pymoo's GA, its defaults (100, SBX, polynomial mutation, duplicates eliminated),
    the first population camopt's draws."""
    from pymoo.algorithms.soo.nonconvex.ga import GA

    _pymoo(problem, budget, seed, trace, GA(pop_size=100, sampling=start.population(100)))


def _scalar_prediction(value: object) -> float:
    """``float`` of a one-element prediction, as numpy before 2.x converted it."""
    return float(np.asarray(value).reshape(-1)[0])


def run_nevergrad(problem: Problem, budget: int, start: Start, seed: int, trace: Trace) -> None:
    """nevergrad's NGOpt (its recommended optimiser) from camopt's start, 50 designs per
    batch.

    nevergrad 1.0.12 (the newest) minimises its metamodel through ``float(prediction)`` of a
    one-element array (``nevergrad.optimization.metamodel``), a TypeError since numpy 2.x
    (its issue #1612): in low dimensions NGOpt picks a metamodel and stopped at 100
    evaluations. The module's ``float`` is replaced by one that reads the single element,
    which is what nevergrad means there, so the peer runs as its authors intended."""
    import nevergrad as ng
    from nevergrad.optimization import metamodel

    metamodel.float = _scalar_prediction  # type: ignore[attr-defined]

    evaluate = traced(problem, trace, snap_integers=True)
    param = ng.p.Array(init=start.x0).set_bounds(0.0, 1.0)
    param.random_state = np.random.RandomState(seed)
    opt = ng.optimizers.NGOpt(parametrization=param, budget=budget, num_workers=50)
    lo, span = problem.lower, problem.upper - problem.lower
    while trace.nfev < budget:
        cands = [opt.ask() for _ in range(50)]
        values = scalar(evaluate, lo + np.array([c.value for c in cands]) * span)
        for c, v in zip(cands, values):
            opt.tell(c, float(v))


PEERS: dict[str, tuple[str, Callable[..., None]]] = {
    "scipy DE": ("scipy", run_scipy_de),
    "pycma BIPOP": ("cma", run_pycma),
    "pymoo DE": ("pymoo", run_pymoo_de),
    "pymoo GA": ("pymoo", run_pymoo_ga),
    "nevergrad NGOpt": ("nevergrad", run_nevergrad),
}

PEER_KEY = 0x50454552  # "PEER": the spawn-key word of a peer's robust draws


def compare(objective: str, seeds: int, full: bool = False,
            only: list[str] | None = None, extra: tuple[str, ...] = ()) -> None:
    """One objective: camopt and every installed peer (``only``: those named), seeds
    interleaved; print the table. ``extra``: overrides of the config after the row's own
    (``--set solver.generations=250``), shown in the table's title."""
    from camopt.core.capabilities import Stochastic

    path, reduced = OBJECTIVES[objective]
    settings = [*([] if full else reduced), *extra]
    cfg = load(CONFIGS / path, ["run.repeats=1", *settings])
    problem, solver_cls = prepare(cfg)
    warm_up(problem)
    robust = isinstance(problem, Stochastic)
    chosen = {name: v for name, v in PEERS.items() if only is None or name in only}
    available = {name: fn for name, (module, fn) in chosen.items()
                 if importlib.util.find_spec(module) is not None}
    missing = [name for name in chosen if name not in available]
    traces: dict[str, list[Trace]] = {"camopt": [], **{name: [] for name in available}}
    crashed: list[str] = []
    for seed in range(seeds):
        trace = Trace()
        budget, x = run_camopt(cfg, problem, solver_cls, seed, trace)
        trace.total = time.process_time() - trace.start
        if robust:
            trace.fresh = score_fresh(problem, x)
        traces["camopt"].append(trace)
        start = start_of(problem, cfg, seed)
        for name, fn in available.items():
            if robust:  # one set of draws for the whole solve (a peer knows no generations)
                problem.reseed(np.random.SeedSequence(cfg.run.seed,  # type: ignore[attr-defined]
                                                      spawn_key=(seed, PEER_KEY)))
                problem.new_generation()  # type: ignore[attr-defined]
            trace = Trace(budget=budget)
            try:
                fn(problem, budget, start, seed, trace)
            except Spent:
                pass
            except Exception as exc:  # a peer's own bug: keep what it reached, say so
                crashed.append(f"{name} (seed {seed}: {type(exc).__name__}: {exc}; "
                               f"stopped at {trace.nfev} evaluations)")
            trace.total = time.process_time() - trace.start
            if robust:
                trace.fresh = score_fresh(problem, trace.best_x)
            traces[name].append(trace)
    best = {name: median_quality([t.quality for t in ts]) for name, ts in traces.items()}
    peers = {k: v for k, v in best.items() if k != "camopt"}
    best_peer = min(peers, key=lambda k: peers[k]) if peers else None
    quality = peers[best_peer] if best_peer else (np.inf, np.inf)
    polish = " + polish" if getattr(cfg.solver, "polish", None) else ""
    judged = "chosen design on fresh draws, " if robust else ""
    shown = " ".join(["full", *extra] if full else settings)
    print(f"{objective} ({cfg.solver.name}{polish}; {shown}"
          f"; {seeds} seeds, budget = camopt's evaluations, median "
          f"{statistics.median(t.nfev for t in traces['camopt']):.0f}; {judged}"
          f"{time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime())}):")
    print(f"| solver | median best | feasible seeds | median nfev | "
          f"median CPU s to {show(quality)} | median CPU s |")
    print("|---|---|---|---|---|---|")
    for name, ts in traces.items():
        cpu = statistics.median(t.cpu_to(quality) for t in ts)
        print(f"| {name} | {show(best[name])} | {sum(t.quality[0] == 0 for t in ts)}/{len(ts)} | "
              f"{statistics.median(t.nfev for t in ts):.0f} | "
              f"{'-' if not np.isfinite(cpu) else format(cpu, '.2f')} | "
              f"{statistics.median(t.total for t in ts):.2f} |")
    for name, ts in traces.items():
        print(f"{name} per seed: " + ", ".join(
            f"{show(t.quality)} ({t.cpu_to(quality):.2f} s)" for t in ts))
    if missing:
        print(f"not installed: {', '.join(missing)}")
    for line in crashed:
        print(f"raised: {line}")
    if best_peer is not None:
        ahead = at_least(best["camopt"], quality)
        ours = statistics.median(t.cpu_to(quality) for t in traces["camopt"])
        theirs = statistics.median(t.cpu_to(quality) for t in traces[best_peer])
        reached = sum(at_least(t.quality, quality) for t in traces["camopt"])
        peer_reached = sum(at_least(t.quality, quality) for t in traces[best_peer])
        print(f"camopt {'at least as good as' if ahead else 'BEHIND'} the best peer "
              f"({best_peer}); its median quality reached in {reached}/{seeds} seeds by "
              f"camopt, {peer_reached}/{seeds} by {best_peer}; CPU to it: camopt "
              f"{ours:.2f} s, {best_peer} {theirs:.2f} s\n", flush=True)


def main(argv: list[str] | None = None) -> None:
    import warnings

    # pycma's notes on injected and rescaled solutions are its own business, not a result
    warnings.filterwarnings("ignore", module=r"cma(\..*)?")
    args = list(sys.argv[1:] if argv is None else argv)
    full = "--full" in args
    args = [a for a in args if a != "--full"]
    only = None
    if "--peers" in args:  # --peers 'scipy DE,pycma BIPOP': those peers alone
        i = args.index("--peers")
        only = args[i + 1].split(",")
        del args[i:i + 2]
    extra: list[str] = []
    while "--set" in args:  # --set solver.generations=250: the config changed so
        i = args.index("--set")
        extra.append(args[i + 1])
        del args[i:i + 2]
    seeds = int(args.pop(0)) if args and args[0].isdigit() else SEEDS
    for objective in args or list(OBJECTIVES):
        compare(objective, max(seeds, MIN_SEEDS.get(objective, 0)), full, only, tuple(extra))


if __name__ == "__main__":
    main()
