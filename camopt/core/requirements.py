"""Requirements as data: what a design must meet to be acceptable, and the verdict on it.

A case declares its requirements in ``camopt/cases/<kind>/requirements.py`` (registered
through its :class:`~camopt.cases.registry.CaseSpec`): each names the quantity it reads
(a metric, a design variable or ``feasible``), its limit with the unit, and where the
limit comes from (paper equation, standard or config). They are evaluated for every
design shown (the optimum, the reference design) by ``show``, ``report`` and ``compare``,
and per sample by ``tolerance`` (yield per requirement), vectorised.

The requirements are not the run's constraints: a run may leave a requirement out of its
search (the paper's VCB problem does not ask the cam to latch) and then its optimum fails
the requirement; the verdict says so in words.

**One feasibility rule** (docs/design.md, "Feasibility"): a quantity meets its limit when it
lies beyond it by no more than :data:`~camopt.core.problem.FEASIBILITY_TOL` times its scale
(:attr:`Requirement.tol_scale`: the unit the run's normalised constraint divides by, by
default the limit's magnitude and at least 1). The run's constraints are normalised so that
their scale is 1 (``g <= FEASIBILITY_TOL``), and success (``sweep --check``) is built on the
same feasibility, so a requirement that mirrors a constraint passes exactly when the
constraint holds. A quantity the design does not reach (NaN: a stroke never finished) is
"n/a" and fails.

**At limit**: a passing requirement whose margin is smaller than half the 5-95 % spread of
its quantity under the case's default tolerances (the run's expected-yield estimate), or,
without that spread, smaller than :data:`AT_LIMIT_SHARE` of its allowed band (a two-sided
limit) or of its scale (a one-sided one), is flagged "at limit": met at nominal, not by
parts made to tolerance.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from camopt.core.problem import FEASIBILITY_TOL

PASS_TOL = FEASIBILITY_TOL
"""Round-off allowance relative to the requirement's scale: a design exactly at its limit
(an active constraint, solved to machine precision) passes; the run's constraints' rule."""
AT_LIMIT_SHARE = 0.01
"""Without a tolerance spread, a margin below 1 % of the allowed band (or of the scale of a
one-sided limit) counts as at the limit: nothing a workshop can hold is that fine."""
AT_LIMIT_YIELD = 0.95
"""A flag (latches, meets the full model) is at its limit when fewer than this share of the
tolerance draws keep it."""


def _fmt(value: float) -> str:
    return f"{value:.6g}"


def engineering(value: float) -> str:
    """A margin as an engineer reads it: 3 significant digits, positional between 1e-3 and
    1e6 (``825``, ``1250``, ``0.974``), else with an exponent (``3.98e-06``)."""
    if value == 0 or not math.isfinite(value) or not 1e-3 <= abs(value) < 1e6:
        return f"{value:.3g}"
    return f"{float(f'{value:.3g}'):g}" if abs(value) < 1e5 else f"{float(f'{value:.3g}'):.0f}"


@dataclass(frozen=True)
class Requirement:
    """One requirement: ``lower <= quantity <= upper`` in ``unit`` (``flag``: the quantity
    is 1 for yes, 0 for no, and must be yes). ``failing`` is what a failing design does,
    in words ("does not latch"); ``source`` the paper equation, standard or config key."""

    name: str
    quantity: str
    unit: str = ""
    lower: float = -math.inf
    upper: float = math.inf
    source: str = ""
    flag: bool = False
    failing: str = ""
    scale: float | None = None
    """The quantity's scale in ``unit`` (what the run's normalised constraint on it divides
    by: 100 for a percentage); None: the limit's magnitude, at least 1."""

    @property
    def tol_scale(self) -> float:
        """The scale :data:`PASS_TOL` is relative to (see :attr:`scale`)."""
        if self.scale is not None:
            return float(self.scale)
        return max([1.0, *(abs(b) for b in (self.lower, self.upper) if math.isfinite(b))])

    @property
    def band(self) -> float | None:
        """Width of a two-sided limit (``18 ± 0.2 mm``: 0.4 mm), else None."""
        if self.flag or not (math.isfinite(self.lower) and math.isfinite(self.upper)):
            return None
        return self.upper - self.lower

    @property
    def limit(self) -> str:
        """The limit as a person reads it: ``<= 1194 MPa``, ``18 ± 0.2 mm``, ``yes``."""
        if self.flag:
            return "yes"
        unit = f" {self.unit}" if self.unit else ""
        lo, hi = self.lower, self.upper
        if math.isfinite(lo) and math.isfinite(hi):
            mid, half = (lo + hi) / 2, (hi - lo) / 2
            if lo > 0 and half < abs(mid):  # a tolerance band about a nominal value
                return f"{_fmt(mid)} ± {_fmt(half)}{unit}"
            return f"{_fmt(lo)} to {_fmt(hi)}{unit}"
        if math.isfinite(hi):
            return f"<= {_fmt(hi)}{unit}"
        return f">= {_fmt(lo)}{unit}"

    def margin(self, value: NDArray | float) -> NDArray:
        """Distance inside the limit in ``unit`` (negative: outside; NaN: not evaluated),
        same shape as ``value``. A flag's margin is 1 for yes, -1 for no."""
        v = np.asarray(value, dtype=float)
        if self.flag:
            return np.where(np.isnan(v), np.nan, np.where(v >= 0.5, 1.0, -1.0))
        with np.errstate(invalid="ignore"):
            m = np.minimum(v - self.lower, self.upper - v)
        # an infinite value (a stress at a cusp, a stroke never finished) fails its bound
        return np.where(np.isinf(v) & ~np.isnan(m), -np.inf, m)

    def passes(self, value: NDArray | float) -> NDArray:
        """Bool array: the value meets the requirement (NaN fails)."""
        m = self.margin(value)
        with np.errstate(invalid="ignore"):
            return m >= -PASS_TOL * self.tol_scale

    def at_limit(self, margin: float, spread: float | None = None,
                 sampled_yield: float | None = None) -> bool:
        """Whether a passing ``margin`` is too small to survive manufacture (module
        docstring): below ``spread`` (half the 5-95 % spread of the quantity under the
        default tolerances) when given, else below :data:`AT_LIMIT_SHARE` of the band or
        scale. A flag is at its limit when ``sampled_yield`` is below
        :data:`AT_LIMIT_YIELD`."""
        if self.flag:
            return sampled_yield is not None and sampled_yield < AT_LIMIT_YIELD
        if spread is not None and math.isfinite(spread) and spread > 0:
            return margin < spread
        return margin < AT_LIMIT_SHARE * (self.band or self.tol_scale)


@dataclass(frozen=True)
class Check:
    """A requirement evaluated for one design: ``value`` None when the design does not
    report the quantity (then ``passed`` is None and the check does not count)."""

    requirement: Requirement
    value: float | None
    margin: float | None
    passed: bool | None
    at_limit: bool = False
    """Passes, with a margin too small for parts made to tolerance
    (:meth:`Requirement.at_limit`)."""

    @property
    def margin_share(self) -> float | None:
        """The margin as a share of a two-sided band (None for a one-sided limit or an
        unknown or unbounded margin)."""
        r = self.requirement
        return (self.margin / r.band if r.band and self.margin is not None
                and math.isfinite(self.margin) else None)

    def as_dict(self) -> dict[str, Any]:
        """The JSON form: name, limit, value, margin, pass, at_limit, margin_share
        (:attr:`margin_share`), unit, source, quantity."""
        r = self.requirement
        return {"name": r.name, "limit": r.limit, "value": self.value, "margin": self.margin,
                "pass": self.passed, "at_limit": self.at_limit,
                "margin_share": self.margin_share, "unit": r.unit, "source": r.source,
                "quantity": r.quantity}

    @property
    def words(self) -> str:
        """Why it fails, in words: ``does not latch`` or ``rod travel 18.3 mm outside
        18 ± 0.2 mm``."""
        r = self.requirement
        if r.flag:
            return r.failing or f"not {r.name}"
        unit = f" {r.unit}" if r.unit else ""
        value = ("n/a (the design does not reach it)" if self.value is None
                 or math.isnan(self.value) else f"{_fmt(self.value)}{unit}")
        text = f"{r.name} {value}, required {r.limit}"
        return f"{r.failing}: {text}" if r.failing else text


@dataclass(frozen=True)
class Spread:
    """A requirement's quantity under the default tolerances: half its 5-95 % spread (in
    the unit; None for a flag) and the share of draws meeting it."""

    half_spread: float | None
    sampled_yield: float


def check(requirements: Sequence[Requirement], values: Mapping[str, Any],
          spreads: Mapping[str, Spread] | None = None) -> list[Check]:
    """Each requirement evaluated on one design's ``{quantity: value}``; ``spreads`` (by
    requirement name) decide which passing ones are at their limit."""
    out = []
    for r in requirements:
        raw = values.get(r.quantity)
        if raw is None or isinstance(raw, (list, tuple, str)):
            out.append(Check(r, None, None, None))
            continue
        v = float(raw)
        margin = float(r.margin(v))
        passed = bool(r.passes(v))
        spread = (spreads or {}).get(r.name)
        limit = passed and r.at_limit(margin, spread.half_spread if spread else None,
                                      spread.sampled_yield if spread else None)
        out.append(Check(r, v, None if math.isnan(margin) else margin, passed, limit))
    return out


def verdict(checks: Sequence[Check]) -> str:
    """"pass" when every evaluated requirement passes (and at least one was), else
    "fail"."""
    evaluated = [c for c in checks if c.passed is not None]
    return "pass" if evaluated and all(c.passed for c in evaluated) else "fail"


def sentence(checks: Sequence[Check]) -> str:
    """The verdict in words: ``PASS: meets all 6 requirements`` or ``FAIL: does not latch;
    closing velocity 1.31 m/s, required 0.9 ± 0.2 m/s``."""
    failed = [c for c in checks if c.passed is False]
    evaluated = sum(c.passed is not None for c in checks)
    if not evaluated:
        return "FAIL: no requirement could be evaluated"
    if not failed:
        close = [c.requirement.name for c in checks if c.at_limit]
        if close:
            return (f"PASS at nominal: {len(close)} requirement{'s' if len(close) > 1 else ''}"
                    f" at {'their' if len(close) > 1 else 'its'} limit ({', '.join(close)})")
        return f"PASS: meets all {evaluated} requirements"
    return "FAIL: " + "; ".join(c.words for c in failed)


def yields(requirements: Sequence[Requirement], samples: Mapping[str, NDArray],
           ) -> list[dict[str, Any]]:
    """Per requirement, its finite limits (``lower``/``upper``, None when unbounded), the
    share of ``samples`` (``{quantity: (n,)}``) that passes and the margin's percentiles;
    requirements whose quantity is not sampled are left out."""
    out = []
    for r in requirements:
        if r.quantity not in samples:
            continue
        v = np.asarray(samples[r.quantity], dtype=float)
        m = r.margin(v)
        finite = m[np.isfinite(m)]
        pct = (np.percentile(finite, [5, 50]).tolist() if finite.size else [None, None])
        values = v[np.isfinite(v)]
        ends = np.percentile(values, [5, 95]) if values.size and not r.flag else None
        out.append({"name": r.name, "quantity": r.quantity, "limit": r.limit,
                    "lower": r.lower if math.isfinite(r.lower) else None,
                    "upper": r.upper if math.isfinite(r.upper) else None, "flag": r.flag,
                    "unit": r.unit, "yield": float(np.mean(r.passes(v))),
                    "margin_p5": pct[0], "margin_p50": pct[1],
                    "half_spread": None if ends is None else float(ends[1] - ends[0]) / 2})
    return out


def all_pass(requirements: Sequence[Requirement], samples: Mapping[str, NDArray]) -> NDArray:
    """(n,) bool: each sample meets every requirement whose quantity ``samples`` holds (an
    all-true column when none is sampled)."""
    n = len(next(iter(samples.values()))) if samples else 0
    ok = np.ones(n, dtype=bool)
    for r in requirements:
        if r.quantity in samples:
            ok &= r.passes(np.asarray(samples[r.quantity], dtype=float))
    return ok
