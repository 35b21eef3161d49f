"""Fitting a model to measured data: robust least squares, profile-likelihood intervals
and the rules that judge the fit, for any model that offers
:class:`~camopt.core.capabilities.Fittable` (the VCB's calibration on travel curves is one).

Notes
-----
The fit, in the model's fitted coordinates q (a parameter, or the log of a positive one,
inside search bounds), minimises the robust cost

    cost(q) = 0.5 sum_i rho(r_i(q)^2),   rho(z) = 2 C^2 (sqrt(1 + z / C^2) - 1)

(scipy ``least_squares``'s soft-l1 with ``f_scale`` C = :data:`ROBUST_SCALE`) of the
residuals r_i in units of the data's noise: data further than ~C noise levels from the
model (an analyser's spikes) count linearly, not quadratically.

Intervals are **profile likelihood** (not a posterior): each coordinate in turn is fixed
at values stepped away from the optimum and every other coordinate re-fitted; the 95 %
interval is where the cost has risen by chi2(1, 0.95) / 2 = 1.92 times the reduced
chi-square s^2 = 2 cost / (N - n) (at least 1: a model that misfits gets wider intervals,
not narrower). A profile that stays under the threshold up to a search bound leaves the
interval open there (the bound is its end).

The decision rules (each pinned by ``tests/core/test_fitting.py``):

- identified (:func:`identified`): a closed interval within ``accuracy`` of the value;
- at a search bound (:func:`near_bound`);
- kept (:func:`keep`): RMS misfit at most :data:`KEEP_RATIO` times the best model's or
  the noise; a nested model's added term kept only on a likelihood-ratio gain
  (:func:`likelihood_ratio`, :data:`CHI2_99_1DOF`);
- explains the data (:meth:`ResidualTest.passes`): residual RMS at most
  :data:`RMS_RATIO_LIMIT` noise levels and a Durbin-Watson statistic not below 2 by more
  than :data:`STRUCTURE_Z_LIMIT` standard errors;
- determined combinations of a Jacobian (:func:`identifiability`).

``scipy.optimize`` is imported inside :func:`least_squares_fit` only: cases import this
module when their Problem is built, and a command that evaluates nothing must not load it.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

import numpy as np

from camopt.core.capabilities import Fittable
from camopt.mechanics import Floats

CHI2_95_1DOF = 3.841458820694124
"""chi-square quantile, 1 degree of freedom, 0.95 (scipy.stats.chi2.ppf(0.95, 1))."""
CHI2_99_1DOF = 6.634896601021214
"""chi-square quantile, 1 degree of freedom, 0.99 (scipy.stats.chi2.ppf(0.99, 1))."""
ROBUST_SCALE = 3.0
"""soft-l1 loss scale in noise levels: quadratic within, linear beyond."""
IDENTIFIED_WITHIN = 0.05
"""A positive parameter counts as identified when its 95 % interval is closed inside the
search bounds and lies within +-5 % of its value (the accuracy a designer asks of a
calibrated value: the truth, inside the interval, is then within 5 %); a model states the
absolute accuracy of its other coordinates (:attr:`Fittable.accuracy`)."""
KEEP_RATIO = 1.5
"""A model is kept when its RMS misfit is at most this many times the best model's or the
data's noise, whichever is larger (1.5: a model that fits about as well as the best, or to
within the noise, is as credible)."""
RMS_RATIO_LIMIT = 1.5
"""A model explains the data only if the RMS of its residuals, in units of each data set's
noise (winsorised at :data:`WINSOR` noise levels: a few analyser spikes do not count), is
at most this: the keep rule's noise floor. 1.5 rather than 1.1: a noise estimate from the
median of second differences is exact for Gaussian noise but up to ~1.4 times low for
heavier-tailed noise (Laplace), and the structure test catches a smooth misfit below it."""
STRUCTURE_Z_LIMIT = 3.0
"""... and only if its residuals show no serial structure: the Durbin-Watson statistic d
(pooled over the data sets) is not below 2 by more than this many of its standard errors
under white noise, 2 / sqrt(N) (one-sided, p ~ 0.0013: with a dozen models and curves a
correct model is rarely flagged by chance)."""
WINSOR = 5.0
"""Residuals beyond this many noise levels count as this many in the residual test."""
NEAR_BOUND_FACTOR = 1.5
"""A positive parameter is at its search bound when its fitted value is within this
factor of it or a tenth of its search range's log, whichever is less (an efficiency's
0.2..1 gives 1.17); other coordinates within their :attr:`Fittable.bound_room`."""
DETERMINED = 0.01
"""A combination of parameters is determined by the data when its singular value is at
least this fraction of the largest (:func:`identifiability`)."""
MAX_PROFILE_STEPS = 10
"""Re-fits per profile and direction before it is taken as open."""


INTERVALS = ("profile likelihood, 95 % (chi2(1) / 2 = 1.92 times the reduced chi-square "
             "rise of the robust cost)")
"""The profile-likelihood intervals, as reports state them."""
LINEARISED = ("linearised, 95 % (+-1.96 standard deviations of (J^T J)^-1 s^2 in the fitted "
              "coordinates): a form not kept is not profiled")
"""The linearised intervals of a model not kept, as reports state them."""
KEEP_RULE = (f"kept: RMS misfit at most {KEEP_RATIO:g} x the best form's or the curves' "
             "noise, whichever is larger")
""":func:`keep`, as reports state it."""
EXPLAINS_RULE = (f"explains: kept, residual RMS at most {RMS_RATIO_LIMIT:g} x the noise "
                 f"and Durbin-Watson not below 2 by more than {STRUCTURE_Z_LIMIT:g} "
                 "standard errors")
""":meth:`ResidualTest.passes` of a kept model, as reports state it."""


@dataclass(frozen=True)
class Optimum:
    """A model's best fit: fitted coordinates ``q`` (n,), its robust cost, the linearised
    covariance of q ((J^T J)^-1 s^2, (n, n)), the reduced chi-square s^2 (at least 1) and
    the RMS misfit (the model's :meth:`~camopt.core.capabilities.Fittable.rms`)."""

    q: Floats
    cost: float
    cov: Floats
    s2: float
    rms: float


@dataclass(frozen=True)
class ParameterEstimate:
    """A fitted parameter (its unit): value, 95 % interval (low, high; a search bound where
    the profile does not cross the threshold), whether the data identify it
    (:func:`identified`) and whether it lies at a search bound (:func:`near_bound`)."""

    name: str
    unit: str
    value: float
    low: float
    high: float
    identified: bool
    at_bound: bool = False


@dataclass(frozen=True)
class Estimates:
    """:func:`estimate`'s result: the parameters, their correlation matrix at the optimum
    (n, n) and the band: every coordinate vector met inside the intervals, the optimum
    first (k, n), in fitted coordinates."""

    parameters: tuple[ParameterEstimate, ...]
    correlation: Floats
    members: Floats


def robust_cost(R: Floats) -> Floats:
    """soft-l1 cost of residual rows ``R`` (k, N), (k,): 0.5 C^2 sum 2 (sqrt(1 + (r/C)^2)
    - 1), scipy ``least_squares``'s with ``f_scale`` C = :data:`ROBUST_SCALE`."""
    z = (R / ROBUST_SCALE) ** 2
    cost: Floats = 0.5 * ROBUST_SCALE**2 * np.sum(2 * (np.sqrt(1 + z) - 1), axis=1)
    return cost


def jacobian(model: Fittable, q: Floats) -> Floats:
    """The residuals' Jacobian at ``q`` (n,), (N, n), by forward differences of step
    1e-6 max(1, |q_j|): one evaluation of n + 1 rows."""
    h = 1e-6 * np.maximum(1.0, np.abs(q))
    R = model.residuals(np.vstack([q, q + np.diag(h)]))
    J: Floats = ((R[1:] - R[0]) / h[:, None]).T
    return J


def with_jacobian(model: Fittable, Q: Floats, free: Floats) -> tuple[Floats, Floats]:
    """Residuals (k, N) at the rows of ``Q`` (k, n) and their Jacobians' transposes
    (k, n, N) by forward differences (step 1e-6 max(1, |q|)), zero in the columns
    ``free`` (k, n) marks fixed: one evaluation of k (n + 1) rows."""
    k, n = Q.shape
    h = 1e-6 * np.maximum(1.0, np.abs(Q))
    rows = np.concatenate([Q[:, None, :], Q[:, None, :] + np.eye(n)[None] * h[:, :, None]],
                          axis=1)
    Rall = model.residuals(rows.reshape(k * (n + 1), n)).reshape(k, n + 1, -1)
    J = (Rall[:, 1:] - Rall[:, :1]) / h[:, :, None]
    return Rall[:, 0], J * free[:, :, None]


def fit_many(model: Fittable, Q0: Floats, fixed: Floats | None = None, tol: float = 1e-9,
             atol: float = 0.0, max_iter: int = 60) -> tuple[Floats, Floats]:
    """Robust least squares from each start of ``Q0`` (B, n) at once; ``fixed`` (B,) the
    coordinate each row keeps at its start (-1: none). Returns the fits (B, n) and their
    costs (B,) (0.5 sum rho, as scipy's ``least_squares``).

    Levenberg-Marquardt with Marquardt's scaling on iteratively reweighted least squares
    (soft-l1: weights w = 1 / sqrt(1 + (r / C)^2), C = :data:`ROBUST_SCALE`): the step
    solves (J^T W J + lambda diag(J^T W J)) dq = -J^T W r, J by forward differences; a
    step is kept when it lowers the robust cost (lambda / 3), else lambda x 4; a row stops
    when a kept step lowers its cost by less than ``tol`` relative or ``atol``, or lambda
    exceeds 1e10, or after ``max_iter`` steps.

    Each step is one vectorised evaluation of the trials and their forward steps,
    k (n + 1) rows for the k rows still running: the Jacobian at a trial is ready when the
    trial is kept, and the last one still holds when it is not. The profiles' re-fits so
    run side by side for little more than the price of one (a vectorised model's cost
    grows slowly with the rows)."""
    lower, upper = model.lower, model.upper
    Q = np.clip(np.atleast_2d(np.asarray(Q0, dtype=float)), lower, upper)
    B, n = Q.shape
    free = np.ones((B, n), dtype=bool)
    if fixed is not None:
        rows = np.flatnonzero(np.asarray(fixed) >= 0)
        free[rows, np.asarray(fixed)[rows]] = False
    R, J = with_jacobian(model, Q, free)
    cost = robust_cost(R)
    lam = np.full(B, 1e-3)
    active = np.ones(B, dtype=bool)
    eye = np.eye(n)
    for _ in range(max_iter):
        idx = np.flatnonzero(active)
        if len(idx) == 0:
            break
        q, r, Jk = Q[idx], R[idx], J[idx]
        w = 1.0 / np.sqrt(1.0 + (r / ROBUST_SCALE) ** 2)
        g = np.einsum("knm,km->kn", Jk, w * r)
        # a coordinate on a bound that the descent would push out of it sits this step
        # out (an active set: clipping its step instead stalls the others)
        held = ((q <= lower + 1e-12) & (g > 0)) | ((q >= upper - 1e-12) & (g < 0))
        Jk = Jk * ~held[:, :, None]
        g = np.where(held, 0.0, g)
        H = np.einsum("knm,kjm,km->knj", Jk, Jk, w)
        diag = np.einsum("knn->kn", H)
        scale = np.maximum(diag, 1e-12 * diag.max(axis=1, keepdims=True) + 1e-300)
        A = H + (lam[idx][:, None] * scale)[:, :, None] * eye
        # pinv: a coordinate the data do not see (a zero column) takes no step
        step = -(np.linalg.pinv(A) @ g[:, :, None])[:, :, 0]
        trial = np.clip(q + step, lower, upper)
        Rt, Jt = with_jacobian(model, trial, free[idx])
        ct = robust_cost(Rt)
        better = ct < cost[idx]
        gain = cost[idx] - ct
        good = idx[better]
        Q[good], R[good], J[good], cost[good] = (trial[better], Rt[better], Jt[better],
                                                 ct[better])
        lam[good] /= 3.0
        lam[idx[~better]] *= 4.0
        moved = np.max(np.abs(trial - q), axis=1)
        done = (better & ((gain <= np.maximum(tol * ct, atol)) | (moved < 1e-9))) | (
            lam[idx] > 1e10)
        active[idx[done]] = False
    return Q, cost


def least_squares_fit(model: Fittable, q0: Floats) -> tuple[Floats, float]:
    """The fit from ``q0``: scipy's ``least_squares`` (trust region reflective, soft-l1,
    tight tolerances: the optimum every profile is measured from; its trust region follows
    the narrow valleys of a single curve better than :func:`fit_many`'s
    Levenberg-Marquardt). Returns q and the cost."""
    from scipy.optimize import least_squares  # lazy: module docstring

    def fun(z: Floats) -> Floats:
        r: Floats = model.residuals(z)[0]
        return r

    def jac(z: Floats) -> Floats:
        return jacobian(model, z)

    z0 = np.clip(q0, model.lower + 1e-9, model.upper - 1e-9)
    sol = least_squares(fun, z0, jac=jac, bounds=(model.lower, model.upper),
                        loss="soft_l1", f_scale=ROBUST_SCALE, x_scale=1.0, max_nfev=100,
                        ftol=1e-8, xtol=1e-8)
    return sol.x, float(sol.cost)


def optimum(model: Fittable, start: Floats) -> Optimum:
    """The best fit from two starts: ``start`` and the first fit's end with every log
    coordinate moved by 0.05 (the cost surface of a delay and an angle has shallow
    valleys), the better kept; its linearised covariance (J^T J)^+ s^2 with the reduced
    chi-square s^2 = max(2 cost / (N - n), 1), and the RMS misfit."""
    q, cost = least_squares_fit(model, start)
    q2, cost2 = least_squares_fit(model, q + 0.05 * model.log)
    if cost2 < cost:
        q, cost = q2, cost2
    J = jacobian(model, q)
    dof = max(len(J) - len(q), 1)
    s2 = max(2 * cost / dof, 1.0)
    return Optimum(q, cost, np.linalg.pinv(J.T @ J) * s2, s2, model.rms(q))


def near_bound(q: float, lower: float, upper: float, log: bool, room: float) -> bool:
    """Whether a fitted coordinate ``q`` is at or near its search bounds: the log of a
    positive parameter (``log``) within min(ln :data:`NEAR_BOUND_FACTOR`, a tenth of its
    log range), another coordinate within ``room`` (its unit). A parameter there is not
    measured by the data but held by the search: often a model standing in for physics
    it lacks."""
    room = min(np.log(NEAR_BOUND_FACTOR), 0.1 * (upper - lower)) if log else room
    return bool(q - lower <= room or upper - q <= room)


def identified(value: float, low: float, high: float, closed: bool, log: bool,
               accuracy: float) -> bool:
    """Whether the data identify a parameter: its interval [low, high] is ``closed`` (both
    ends found inside the search bounds) and reaches at most ``accuracy`` from ``value``:
    relative (max(value - low, high - value) <= accuracy |value|) for a positive
    parameter fitted in its log (``log``), absolute (in its unit) otherwise."""
    reach = max(value - low, high - value)
    return bool(closed and (reach <= accuracy * abs(value) if log else reach <= accuracy))


def keep(rms: Sequence[float], noise: float) -> list[bool]:
    """Which models are kept by their RMS misfits ``rms``: at most :data:`KEEP_RATIO`
    times the larger of the best model's and ``noise`` (the data's RMS noise level, the
    same unit)."""
    if not rms:
        return []
    limit = KEEP_RATIO * max(min(rms), noise)
    return [r <= limit for r in rms]


def likelihood_ratio(base: Optimum, nested: Optimum) -> float:
    """The likelihood ratio of a model that adds one term to ``base``:
    2 (cost_base - cost) / s^2 (s^2 the richer model's reduced chi-square). Its term is
    worth keeping when this is at least :data:`CHI2_99_1DOF` = 6.63: a term the data do
    not need fits them as well as the base (the ratio ~0) and would only widen the
    predictions."""
    return 2 * (base.cost - nested.cost) / nested.s2


@dataclass(frozen=True)
class ResidualTest:
    """A fit's residuals against the data's noise (:func:`residual_test`): ``noise`` the
    data's RMS noise level (each data set's own), ``rms_ratio`` the residuals' RMS in noise
    levels (winsorised), ``durbin_watson`` d = sum (e_i - e_i-1)^2 / sum e_i^2 of the
    normalised residuals within each data set, pooled (2 for white residuals, toward 0
    for a smooth misfit), ``structure_z`` = (2 - d) sqrt(N) / 2 its distance below 2 in
    standard errors, and the number of samples N."""

    noise: float
    rms_ratio: float
    durbin_watson: float
    structure_z: float
    samples: int

    def passes(self) -> bool:
        """Residuals at the noise (:data:`RMS_RATIO_LIMIT`) and without structure
        (:data:`STRUCTURE_Z_LIMIT`)."""
        return self.rms_ratio <= RMS_RATIO_LIMIT and self.structure_z <= STRUCTURE_Z_LIMIT


def residual_test(residuals: Sequence[Floats], sigma: Sequence[float]) -> ResidualTest:
    """The test of a fit's residuals (one array per data set) against each set's noise
    ``sigma`` (same unit): :class:`ResidualTest`. Normalised by the noise and winsorised
    at :data:`WINSOR`; the Durbin-Watson sums run within each set (no difference across
    two sets) and are pooled."""
    e = [np.clip(np.asarray(r) / s, -WINSOR, WINSOR) for r, s in zip(residuals, sigma)]
    n = sum(len(x) for x in e)
    squares = sum(float(np.sum(x * x)) for x in e)
    steps = sum(float(np.sum(np.diff(x) ** 2)) for x in e)
    counts = np.array([len(x) for x in e])
    noise = float(np.sqrt(np.sum(counts * np.square(sigma)) / max(n, 1)))
    d = steps / squares if squares > 0 else 2.0
    return ResidualTest(noise, float(np.sqrt(squares / max(n, 1))), d,
                        (2.0 - d) * np.sqrt(n) / 2.0, n)


def delta_sd(values: Callable[[Floats], Floats], opt: Optimum) -> Floats:
    """The linearised (delta-method) standard deviation sqrt(g^T C g) of predictions at
    the optimum ``opt``: ``values`` maps rows of fitted coordinates (k, n) to predictions
    (k, m); g by forward differences of step 1e-6 max(1, |q_j|), C the optimum's
    covariance. (m,); NaN where a prediction is."""
    h = 1e-6 * np.maximum(1.0, np.abs(opt.q))
    Y = values(np.vstack([opt.q, opt.q + np.diag(h)]))
    with np.errstate(invalid="ignore"):
        G = (Y[1:] - Y[:1]) / h[:, None]
        sd: Floats = np.sqrt(np.einsum("in,ij,jn->n", G, opt.cov, G))
    return sd


@dataclass
class _Profile:
    """The state of one coordinate's profile in one direction (:func:`profiles`): its
    coordinate ``j``, direction, the optimum's value of it (``origin``) and the room to
    the search bound, the step ``d`` from the optimum now tried, the furthest inside
    (``near``, its cost rise) and the nearest outside (``far``: distance, rise), the last
    re-fitted vector inside, those inside, and the end (None: open to a bound)."""

    j: int
    sign: float
    origin: float
    room: float
    d: float
    last: Floats
    near: float = 0.0
    near_rise: float = 0.0
    far: tuple[float, float] | None = None
    inside: list[Floats] = field(default_factory=list)
    done: bool = False
    end: float | None = None
    steps: int = 0


def _valley(cov: Floats, j: int) -> Floats:
    """How the linearised conditional optimum moves per unit of coordinate j (n,):
    column j of the covariance over its variance. A coordinate the data do not see
    (a zero column of the Jacobian: zero variance in the pseudo-inverse) moves alone:
    the others have nothing to trade against it (0 / 0 there was NaN, and a
    RuntimeWarning)."""
    if cov[j, j] > 0:
        moved: Floats = cov[:, j] / cov[j, j]
        return moved
    alone: Floats = np.eye(len(cov))[j]
    return alone


def _advance(p: _Profile, trial: Floats, r: float, rise: float) -> None:
    """One re-fit of profile ``p`` at its step ``p.d``, the cost risen by ``r``: the next
    step (doubling while inside, bisecting once outside) or the end."""
    p.steps += 1
    if r <= rise:
        p.inside.append(trial)
        p.last, p.near, p.near_rise = trial, p.d, max(r, 0.0)
        if p.far is None and p.d >= p.room:
            p.done, p.end = True, None  # open up to the search bound
            return
        p.d = min(2 * p.d, p.room) if p.far is None else 0.5 * (p.near + p.far[0])
    else:
        p.far = (p.d, r)
        if r <= 4 * rise or p.far[0] - p.near < 1e-4:
            _finish(p, rise)
            return
        p.d = 0.5 * (p.near + p.far[0])


def _finish(p: _Profile, rise: float) -> None:
    """The end of profile ``p``: None without a point outside, else the crossing in the
    bracket (near, far) on a parabola rise ~ a (distance)^2 through its two ends."""
    p.done = True
    if p.far is None:
        p.end = None
        return
    a = (p.far[1] - p.near_rise) / max(p.far[0] ** 2 - p.near**2, 1e-300)
    at = np.sqrt(p.near**2 + (rise - p.near_rise) / a) if a > 0 else p.far[0]
    p.end = float(p.origin + p.sign * float(np.clip(at, p.near, p.far[0])))


def profiles(model: Fittable, q: Floats, cost: float, cov: Floats, rise: float
             ) -> dict[tuple[int, float], _Profile]:
    """Every coordinate's profile from the optimum ``q`` (cost ``cost``) in both
    directions, side by side (:func:`fit_many` re-fits them together): coordinate j fixed
    at 1.5, 3, 6, ... linearised standard deviations (``cov``) from the optimum, the
    others re-fitted, until the cost rises by more than ``rise``; a rise of more than
    4 ``rise`` (a cliff: the profile is not a parabola there) is bisected until the
    bracket holds at most that, and the crossing is placed in the bracket as on a
    parabola through the optimum. A profile's end is None where it reaches the search
    bound, or :data:`MAX_PROFILE_STEPS` re-fits, under the threshold."""
    lower, upper = model.lower, model.upper
    out = {}
    for j in range(len(q)):
        for sign in (-1.0, 1.0):
            bound = upper[j] if sign > 0 else lower[j]
            room = abs(bound - q[j])
            # a coordinate the data do not see (no variance) starts at its bound
            first = 1.5 * float(np.sqrt(cov[j, j])) if cov[j, j] > 0 else room
            out[(j, sign)] = _Profile(j, sign, float(q[j]), room, min(first, room), q)
    for _ in range(MAX_PROFILE_STEPS):
        live = [p for p in out.values() if not p.done]
        if not live:
            break
        # start from the better of the last inside point moved along j alone and the
        # linearised conditional optimum (the valley's direction near the optimum)
        starts = []
        for p in live:
            x = q[p.j] + p.sign * p.d
            two = np.vstack([p.last, q + _valley(cov, p.j) * (x - q[p.j])])
            two = np.clip(two, lower + 1e-9, upper - 1e-9)
            two[:, p.j] = x
            starts.append(two)
        S = np.vstack(starts)
        c2 = robust_cost(model.residuals(S)).reshape(len(live), 2)
        S0 = S.reshape(len(live), 2, -1)[np.arange(len(live)), np.argmin(c2, axis=1)]
        # a re-fit needs its cost to a small part of the threshold, not to round-off
        trials, costs = fit_many(model, S0, np.array([p.j for p in live]),
                                 atol=0.005 * rise, max_iter=50)
        for p, trial, c in zip(live, trials, costs):
            _advance(p, trial, float(c - cost), rise)
    for p in out.values():
        if not p.done:
            _finish(p, rise)
    return out


def _out(q: float, log: bool) -> float:
    return float(np.exp(q)) if log else float(q)


def estimate(model: Fittable, opt: Optimum, names: Sequence[tuple[str, str]],
             profiled: bool = True) -> Estimates:
    """The parameters (``names``: (name, unit) per fitted coordinate) at the optimum
    ``opt`` with their 95 % intervals. ``profiled``: profile likelihood (module
    docstring), the threshold a cost rise of chi2(1, 0.95) / 2 s^2; else linearised,
    q +- 1.96 sd of the covariance in the fitted coordinates (the log of a positive
    parameter), each end's band member the linearised conditional optimum there, and
    nothing identified (a model the data reject: its values calibrate nothing, and a
    misfitting model's profiles wander far for little)."""
    q, cov = opt.q, opt.cov
    lower, upper, log = model.lower, model.upper, model.log
    sd = np.sqrt(np.maximum(np.diag(cov), 1e-12))
    corr = cov / np.outer(sd, sd)
    rise = 0.5 * CHI2_95_1DOF * opt.s2
    ends: dict[tuple[int, float], float | None] = {}
    members = [q]
    if profiled:
        for key, prof in profiles(model, q, opt.cost, cov, rise).items():
            ends[key] = prof.end
            members += prof.inside
    else:
        for j in range(len(q)):
            for sign in (-1.0, 1.0):
                x = q[j] + sign * np.sqrt(CHI2_95_1DOF) * sd[j]
                inside = bool(lower[j] <= x <= upper[j])
                ends[(j, sign)] = x if inside else None
                members.append(np.clip(q + _valley(cov, j) * (x - q[j]), lower, upper))
    ests = []
    for j, (name, unit) in enumerate(names):
        lo_q, hi_q = ends[(j, -1.0)], ends[(j, 1.0)]
        low = _out(lo_q if lo_q is not None else lower[j], log[j])
        high = _out(hi_q if hi_q is not None else upper[j], log[j])
        value = _out(q[j], log[j])
        closed = profiled and lo_q is not None and hi_q is not None
        ests.append(ParameterEstimate(
            name, unit, value, low, high,
            identified(value, low, high, closed, bool(log[j]), float(model.accuracy[j])),
            near_bound(q[j], lower[j], upper[j], bool(log[j]), float(model.bound_room[j]))))
    return Estimates(tuple(ests), corr, np.array(members))


@dataclass(frozen=True)
class Identifiability:
    """What data determine about a model's parameters at its fit, from the Jacobian J of
    the residuals with respect to the log parameters (m, p): its ``singular_values``
    (descending) and condition number, the parameters' ``correlations`` (p, p, from
    (J^T J)^-1) and the ``determined`` combinations: the right singular vectors whose
    singular value is at least :data:`DETERMINED` of the largest, each a product of the
    parameters' powers (log-linear) with its singular value; the rest (``undetermined``)
    move the fit by less than that."""

    names: tuple[str, ...]
    singular_values: Floats
    correlations: Floats
    determined: tuple[dict[str, float], ...]
    undetermined: tuple[dict[str, float], ...]

    def to_json(self) -> dict[str, object]:
        s = self.singular_values
        return {"parameters": list(self.names), "singular_values": s.tolist(),
                "condition": float(s[0] / s[-1]) if s[-1] > 0 else float("inf"),
                "correlations": {a: {b: float(self.correlations[i, j])
                                     for j, b in enumerate(self.names)}
                                 for i, a in enumerate(self.names)},
                "determined": list(self.determined), "undetermined": list(self.undetermined)}


def identifiability(jac: Floats, names: Sequence[str]) -> Identifiability:
    """:class:`Identifiability` from the Jacobian ``jac`` (m, p) of the residuals with
    respect to the log parameters ``names`` (p,)."""
    _, s, vt = np.linalg.svd(jac, full_matrices=False)
    cov = np.linalg.pinv(jac.T @ jac)
    sd = np.sqrt(np.abs(np.diag(cov)))
    with np.errstate(divide="ignore", invalid="ignore"):
        corr = cov / np.outer(sd, sd)

    def combination(i: int) -> dict[str, float]:
        v = vt[i] * np.sign(vt[i][np.argmax(np.abs(vt[i]))])  # largest exponent positive
        return {"singular_value": float(s[i]),
                **{f"exponent_{n}": float(c) for n, c in zip(names, v)}}

    determined = s >= DETERMINED * s[0]
    return Identifiability(tuple(names), s, corr,
                           tuple(combination(int(i)) for i in np.flatnonzero(determined)),
                           tuple(combination(int(i)) for i in np.flatnonzero(~determined)))


def central_jacobian(fun: Callable[[Floats], Floats], q: Floats, step: float = 1e-6
                     ) -> Floats:
    """d fun / d q at ``q`` (p,), (m, p), by central differences of ``step`` in every
    coordinate: ``fun`` maps rows (k, p) to residual rows (k, m), all 2 p rows in one
    call."""
    n = len(q)
    r = fun(q[None, :] + step * np.vstack([np.eye(n), -np.eye(n)]))
    J: Floats = ((r[:n] - r[n:]) / (2 * step)).T
    return J
