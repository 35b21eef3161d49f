"""Calibration of the VCB closing dynamics on measured travel curves: the model the
fitting (:mod:`camopt.core.fitting`) runs on, and what the fits mean for the VCB.

Each curve belongs to a design (the case's reference cam and springs unless the curve
names others) and is timed from the close command; the model's closing starts at the
release of the closing springs, a latch delay later. For every model form of
:data:`camopt.cases.vcb.forms.FORMS` (the one seam the identification on the ADAMS data
uses too: the parameters a form fits, their search bounds on curves and the closing it
simulates for designs and parameter rows) the fit is

    min over (p, d)  sum_curves sum_samples  rho( ((s_model(t_i - d_c; p) - s_i) / sigma_c)^2 )

the robust least squares of :mod:`camopt.core.fitting` (soft-l1: an analyser's spikes
count linearly) in the log of each positive parameter, with one latch delay d_c shared by
every curve without a measured one (a nuisance parameter: the same breaker's coil and
latch), sigma_c each curve's noise (its second differences,
:func:`camopt.cases.vcb.curves.noise_level`). Samples before the motion are fitted too:
the model holds the rod at rest until the cam meets the roller, so they fix the delay
plus the free rotation's time; the curve's zero is the median of those samples.

Intervals are the fitting module's profile likelihood (linearised for a form not kept).
Samples along a travel curve are not quite independent (the model's misfit is smooth),
so these intervals are the ones white noise would give; ``docs/calibration.md`` says so.
Predictions (closing velocity over the case's window, touch time) for designs get the
wider of their envelope over every re-fitted parameter vector met on the profiles
within the threshold and the linearised interval.

A form is **kept** by :func:`camopt.core.fitting.keep` on its RMS misfit (the
identification's rule, ``form_keep_ratio`` times the best form's largest residual or
``form_keep_pct``, with the RMS misfit for the largest residual and the noise for the
absolute floor), a form adding one term to another by :func:`nested_keep`, and where some
form explains the curves, only if its residuals pass the test too.
"""

from __future__ import annotations

import warnings
from collections.abc import Sequence
from dataclasses import dataclass, field, replace

import numpy as np

from camopt.cases.vcb.calibration_model import (
    Design,
    KinematicsMemo,
    sample_travel,
    travel,
    velocity,
)
from camopt.cases.vcb.config import VcbConfig
from camopt.cases.vcb.curves import (
    AnalyserQuantities,
    TravelCurve,
    VelocityPoints,
    analyse,
)
from camopt.cases.vcb.forms import CURVE_FORMS, ModelForm
from camopt.core.capabilities import Fittable
from camopt.core.fitting import (
    CHI2_95_1DOF,
    CHI2_99_1DOF,
    IDENTIFIED_WITHIN,
    Optimum,
    ParameterEstimate,
    ResidualTest,
    delta_sd,
    estimate,
    keep,
    likelihood_ratio,
    optimum,
    residual_test,
)
from camopt.mechanics import Floats
from camopt.units import MM, MS

IDENTIFIED_DELAY_MS = 0.25
"""The latch delay counts as identified when its closed 95 % interval lies within this
(ms) of its value (the positive parameters: within
:data:`~camopt.core.fitting.IDENTIFIED_WITHIN`)."""
NEAR_BOUND_DELAY_MS = 0.1
"""The latch delay is at its search bound within this (ms)."""
MAX_DELAY_S = 0.1
"""Upper search bound of a fitted latch delay (s)."""
FINE_STEP_S = 1e-5
"""The fitted model's curve is read by the analyser's rules at this step (100 kHz)."""
MIN_WINDOW_SAMPLES = 10
"""A measured curve with fewer samples between the contact velocity's calculation points
reads its closing time and contact velocity from the fit (resampled)."""


@dataclass(frozen=True)
class CurveCase:
    """A measured curve with its design and latch delay (s; None: fitted)."""

    curve: TravelCurve
    design: Design
    latch_delay: float | None = None


@dataclass(frozen=True)
class Prediction:
    """A design's predicted closing (the case's closing velocity, m/s, and its touch time
    from the release, s) at the fit and its low/high over the profiles."""

    design: str
    closing_velocity: float
    closing_velocity_low: float
    closing_velocity_high: float
    touch_time: float
    touch_time_low: float
    touch_time_high: float


@dataclass(frozen=True)
class CurveFit:
    """One curve's fit: its source, the samples' time (s) and measured and fitted travel
    (m), the RMS misfit (m), the analyser's quantities of both curves and the curve's
    noise level (m)."""

    source: str
    design: str
    latch_delay: float
    time: Floats
    measured: Floats
    fitted: Floats
    rms: float
    measured_quantities: AnalyserQuantities
    fitted_quantities: AnalyserQuantities
    noise: float = 0.0


@dataclass(frozen=True)
class FormFit:
    """The calibration of one model form: RMS misfit over every sample (m), the
    parameters (the form's, then the fitted latch delay in ms, if any), their correlation
    matrix at the optimum (linearised: (J^T J)^-1 s^2), the curves, the predictions,
    ``band``: the form's parameter rows met on the profiles inside the intervals, the fit
    first, whether the form is ``kept`` (:func:`~camopt.core.fitting.keep`), how its
    ``intervals`` were found (``profile``: profile likelihood; ``linearised``: a form not
    kept), the test of its residuals against the curves' noise
    (:func:`~camopt.core.fitting.residual_test`) and whether it ``explains`` the curves
    (kept, and its residuals pass: :meth:`~camopt.core.fitting.ResidualTest.passes`),
    and why a form with more physics is not kept (``kept_note``: :func:`nested_keep`)."""

    form: str
    description: str
    rms: float
    parameters: tuple[ParameterEstimate, ...]
    correlation: Floats
    curves: tuple[CurveFit, ...]
    predictions: tuple[Prediction, ...]
    band: Floats = field(repr=False)
    kept: bool = True
    intervals: str = "profile"
    residuals: ResidualTest | None = None
    explains: bool = False
    kept_note: str = ""


class Calibration(Fittable):
    """One model form and the curves: the :class:`~camopt.core.capabilities.Fittable` the
    fitting runs on (module docstring) and the form's report from its fit. ``steps`` the
    form's grid (the case's ``dynamics_steps``)."""

    def __init__(self, config: VcbConfig, form: ModelForm, curves: Sequence[CurveCase],
                 points: VelocityPoints | None = None) -> None:
        self.config, self.form, self.curves = config, form, tuple(curves)
        self.model = KinematicsMemo(config)
        self.steps = config.dynamics_steps
        self.points = points or VelocityPoints.last_third(config.contact_gap_mm * MM)
        self.designs = [c.design for c in self.curves]
        self.parameters = form.curve_parameters()
        self.n_form = len(self.parameters)
        # one latch delay for every curve without its own (the same breaker's coil and latch)
        self.free_delay = [i for i, c in enumerate(self.curves) if c.latch_delay is None]
        lo = [np.log(p.lower) if p.log else p.lower for p in self.parameters]
        hi = [np.log(p.upper) if p.log else p.upper for p in self.parameters]
        shared = 1 if self.free_delay else 0
        self.lower = np.r_[lo, np.zeros(shared)]
        self.upper = np.r_[hi, np.full(shared, MAX_DELAY_S / MS)]
        self.log = np.array([p.log for p in self.parameters] + [False] * shared)
        self.accuracy = np.where(self.log, IDENTIFIED_WITHIN, IDENTIFIED_DELAY_MS)
        self.bound_room = np.full(len(self.log), NEAR_BOUND_DELAY_MS)
        self.sigma = np.array([max(c.curve.noise, 1e-3 * MM) for c in self.curves])
        self.n_samples = sum(len(c.curve.time) for c in self.curves)

    # ---- parameter vectors: q (fitted coordinates) <-> form values and delays --------
    def values(self, Q: Floats) -> tuple[Floats, Floats]:
        """Form parameters (k, P) in their units and every curve's delay (k, n) s."""
        Q = np.atleast_2d(Q)
        v = np.where(self.log, np.exp(np.minimum(Q, 700)), Q)
        delays = np.tile([c.latch_delay or 0.0 for c in self.curves], (len(Q), 1))
        if self.free_delay:
            delays[:, self.free_delay] = v[:, self.n_form:self.n_form + 1] * MS
        return v[:, :self.n_form], delays

    def simulate(self, Q: Floats) -> list[Floats]:
        """Simulated travel (m) at each curve's sample times, per curve (k, m_c)."""
        P, delays = self.values(Q)
        time, rod = travel(self.form, self.model, self.designs, P, self.steps)
        k = len(P)
        out = []
        for i, c in enumerate(self.curves):  # curves: a handful, each vectorised over k
            query = c.curve.time[None, :] - delays[:, i : i + 1]
            out.append(sample_travel(time[:, i], rod[:, i], np.broadcast_to(
                query, (k, len(c.curve.time)))))
        return out

    def residuals(self, Q: Floats) -> Floats:
        """Normalised residuals (k, N): (model - measured) / sigma, every curve."""
        sims = self.simulate(Q)
        return np.concatenate([(s - c.curve.travel) / sig for s, c, sig
                               in zip(sims, self.curves, self.sigma)], axis=1)

    def rms(self, q: Floats) -> float:
        """RMS misfit (m) at ``q`` over every sample of every curve."""
        R = self.residuals(q)[0]
        sig = np.concatenate([np.full(len(c.curve.time), s)
                              for c, s in zip(self.curves, self.sigma)])
        return float(np.sqrt(np.mean((R * sig) ** 2)))

    def start(self) -> Floats:
        """The form's case values and, for each fitted delay, the delay that puts the
        model's first motion on the curve's (from a quick look at the curves)."""
        p0 = self.form.start(self.config)
        q = np.array([np.log(v) if p.log else v for v, p in zip(p0, self.parameters)])
        time, rod = travel(self.form, self.model, self.designs, p0[None, :], self.steps)
        delays = []
        for i in self.free_delay:
            c = self.curves[i].curve
            moved = np.argmax(c.travel > 0.1 * np.max(c.travel))
            t_model = time[0, i][np.argmax(rod[0, i] > 0.1 * np.max(c.travel))]
            delays.append(np.clip((c.time[moved] - t_model) / MS, 0.01, MAX_DELAY_S / MS - 0.01))
        return np.r_[q, np.mean(delays)] if delays else q

    def optimum(self) -> Optimum:
        """The best fit from the form's case values (:func:`camopt.core.fitting.optimum`)."""
        return optimum(self, self.start())

    def fit(self, opt: Optimum | None = None, profiled: bool = True) -> FormFit:
        """The fit (``opt``, else :meth:`optimum`), its intervals
        (:func:`camopt.core.fitting.estimate`: profile likelihood, or linearised for a form
        the curves reject) and the report of this form."""
        o = opt or self.optimum()
        est = estimate(self, o, self.names(), profiled)
        P_band, _ = self.values(est.members)
        return FormFit(self.form.name, self.form.summary, o.rms, est.parameters,
                       est.correlation, self._curve_fits(o.q), (), P_band,
                       intervals="profile" if profiled else "linearised")

    def names(self) -> list[tuple[str, str]]:
        """(name, unit) of every fitted coordinate: the form's, then the latch delay."""
        return [(p.name, p.unit) for p in self.parameters] + (
            [("latch_delay_ms", "ms")] if self.free_delay else [])

    def _curve_fits(self, q: Floats) -> tuple[CurveFit, ...]:
        """Each curve's fit at ``q``: the model at the samples' times, and the analyser's
        quantities of the measured curve and of the model sampled every
        :data:`FINE_STEP_S` (the fit's own reading, at any sampling rate of the curve).
        A measured curve with fewer than :data:`MIN_WINDOW_SAMPLES` samples between the
        velocity's calculation points reads its contact velocity and closing time from
        the fit (resampled, said in its notes): linear interpolation between samples
        5 ms apart reads a 1.73 m/s closing at 1.37."""
        sims = self.simulate(q)
        P, delays = self.values(q)
        gap = self.config.contact_gap_mm * MM
        out = []
        for i, (c, s) in enumerate(zip(self.curves, sims)):
            t, meas = c.curve.time, c.curve.travel
            fine_t = np.arange(t[0], t[-1] + FINE_STEP_S / 2, FINE_STEP_S)
            time, rod = travel(self.form, self.model, [self.designs[i]], P, self.steps)
            fine = sample_travel(time[:, 0], rod[:, 0], (fine_t - delays[0, i])[None, :])[0]
            fitted = analyse(fine_t, fine, gap, self.points, rebounds=False)
            measured = analyse(t, meas, gap, self.points)
            inside = int(np.sum((meas >= self.points.low) & (meas <= self.points.high)))
            if inside < MIN_WINDOW_SAMPLES:
                measured = replace(measured, closing_time=fitted.closing_time,
                                   contact_velocity=fitted.contact_velocity,
                                   notes=(*measured.notes,
                                          f"closing time and contact velocity resampled from "
                                          f"the fit: {inside} sample(s) between the velocity's "
                                          f"calculation points, fewer than "
                                          f"{MIN_WINDOW_SAMPLES}"))
            out.append(CurveFit(
                c.curve.source, c.design.label, float(delays[0, i]), t, meas, s[0],
                float(np.sqrt(np.mean((s[0] - meas) ** 2))), measured, fitted,
                float(self.sigma[i])))
        return tuple(out)

    def predict(self, fit: FormFit, designs: Sequence[Design], best: Floats,
                opt: Optimum | None = None) -> tuple[Prediction, ...]:
        """Closing velocity and touch time of ``designs`` at the fitted form parameters
        ``best`` (P,): low and high the wider of their envelope over the fit's band and,
        given the optimum ``opt``, the linearised 95 % interval +-1.96 sqrt(g^T C g)
        (g the prediction's gradient in the fitted coordinates by forward differences, C
        the optimum's covariance: :func:`camopt.core.fitting.delta_sd`). The envelope
        alone is the profiles' extremes along each parameter's axis; a prediction that
        moves with several parameters at once lies off those axes, and the envelope alone
        covered a third design's true velocity in too few noisy curves (the coverage
        study of tests/cases/test_vcb_calibrate.py)."""
        P = np.vstack([best, fit.band])
        v, t = velocity(self.form, self.model, designs, P, self.steps)
        sd_v = sd_t = np.zeros(len(designs))
        if opt is not None:
            n = len(designs)

            def both(Q: Floats) -> Floats:
                vq, tq = velocity(self.form, self.model, designs, self.values(Q)[0],
                                  self.steps)
                return np.hstack([vq, tq])

            sd = delta_sd(both, opt)
            sd_v, sd_t = sd[:n], sd[n:]
        z = np.sqrt(CHI2_95_1DOF)
        with np.errstate(invalid="ignore"), warnings.catch_warnings():
            warnings.simplefilter("ignore", RuntimeWarning)  # all-NaN: never touches
            return tuple(Prediction(
                d.label, float(v[0, i]),
                float(np.nanmin(np.r_[v[:, i], v[0, i] - z * sd_v[i]])),
                float(np.nanmax(np.r_[v[:, i], v[0, i] + z * sd_v[i]])), float(t[0, i]),
                float(np.nanmin(np.r_[t[:, i], t[0, i] - z * sd_t[i]])),
                float(np.nanmax(np.r_[t[:, i], t[0, i] + z * sd_t[i]])))
                for i, d in enumerate(designs))


def nested_keep(forms: Sequence[ModelForm], optima: Sequence[Optimum], kept: Sequence[bool]
                ) -> list[tuple[bool, str]]:
    """The keep rule for a form that adds one term to a ``base`` form fitted beside it:
    kept only where the term improves the fit beyond chance, the likelihood ratio
    2 (cost_base - cost) / s^2 at least chi2(1, 0.99) = 6.63 (s^2 the form's reduced
    chi-square, at least 1). A term the curves do not need fits them as well as the base
    (its parameter at its lower bound, the ratio ~0) and is kept out: its extra freedom
    would only widen the predictions. Returns (kept, why not) per form."""
    names = [f.name for f in forms]
    out = []
    for form, opt, k in zip(forms, optima, kept):
        if form.base is None or form.base not in names or not k:
            out.append((k, ""))
            continue
        ratio = likelihood_ratio(optima[names.index(form.base)], opt)
        out.append((True, "") if ratio >= CHI2_99_1DOF else (
            False, f"not kept: its {form.extra.replace('_', ' ')} does not improve on "
            f"{form.base} (likelihood ratio {ratio:.2f} < {CHI2_99_1DOF:.2f})"))
    return out


def calibrate(config: VcbConfig, curves: Sequence[CurveCase],
              forms: Sequence[ModelForm] = CURVE_FORMS, predict: Sequence[Design] = (),
              points: VelocityPoints | None = None) -> tuple[FormFit, ...]:
    """Fit every form (default :data:`~camopt.cases.vcb.forms.CURVE_FORMS`) to the curves
    jointly, mark the forms kept (:func:`~camopt.core.fitting.keep`, :func:`nested_keep`;
    where some form explains the curves, a form whose residuals fail the test is not
    kept), find the
    intervals (profile likelihood for the kept forms, linearised for the others:
    :meth:`Calibration.fit`) and predict ``predict``'s designs (the curves' designs if
    empty)."""
    cals = [Calibration(config, form, curves, points) for form in forms]
    optima = [c.optimum() for c in cals]
    sigma = np.array([max(c.curve.noise, 1e-3 * MM) for c in curves])
    counts = np.array([len(c.curve.time) for c in curves])
    noise = float(np.sqrt(np.sum(counts * sigma**2) / np.sum(counts)))
    decided = nested_keep(forms, optima, keep([o.rms for o in optima], noise))
    tests = [residual_test([s[0] - c.curve.travel for s, c in zip(cal.simulate(o.q), curves)],
                           list(cal.sigma)) for cal, o in zip(cals, optima)]
    explaining = [f.name for f, (k, _), t in zip(forms, decided, tests) if k and t.passes()]
    if explaining:  # forms that explain the curves outrank forms that merely fit as well
        decided = [(k, why) if not k or t.passes() else (
            False, f"not kept: its residuals are not the noise (RMS {t.rms_ratio:.2f} x, "
            f"Durbin-Watson {t.durbin_watson:.2f}) where {', '.join(explaining)} explain "
            "the curves") for (k, why), t in zip(decided, tests)]
    out = []
    for cal, opt, (k, why), test in zip(cals, optima, decided, tests):
        fit = cal.fit(opt, profiled=k)
        best = np.array([p.value for p in fit.parameters[:cal.n_form]])
        designs = list(predict) or _unique(cal.designs)
        out.append(replace(fit, predictions=cal.predict(fit, designs, best, opt), kept=k,
                           residuals=test, explains=k and test.passes(), kept_note=why))
    return tuple(out)


def _unique(designs: Sequence[Design]) -> list[Design]:
    """One design per label, in order."""
    seen: dict[str, Design] = {}
    for d in designs:
        seen.setdefault(d.label, d)
    return list(seen.values())
