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
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

PASS_TOL = 1e-9
"""Round-off allowance relative to the limit: a design exactly at its limit (an active
constraint, solved to machine precision) passes."""


def _fmt(value: float) -> str:
    return f"{value:.6g}"


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
        scale = max([1.0, *(abs(b) for b in (self.lower, self.upper) if math.isfinite(b))])
        with np.errstate(invalid="ignore"):
            return m >= -PASS_TOL * scale


@dataclass(frozen=True)
class Check:
    """A requirement evaluated for one design: ``value`` None when the design does not
    report the quantity (then ``passed`` is None and the check does not count)."""

    requirement: Requirement
    value: float | None
    margin: float | None
    passed: bool | None

    def as_dict(self) -> dict[str, Any]:
        """The JSON form: name, limit, value, margin, pass (and unit, source, quantity)."""
        r = self.requirement
        return {"name": r.name, "limit": r.limit, "value": self.value, "margin": self.margin,
                "pass": self.passed, "unit": r.unit, "source": r.source,
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


def check(requirements: Sequence[Requirement], values: Mapping[str, Any]) -> list[Check]:
    """Each requirement evaluated on one design's ``{quantity: value}``."""
    out = []
    for r in requirements:
        raw = values.get(r.quantity)
        if raw is None or isinstance(raw, (list, tuple, str)):
            out.append(Check(r, None, None, None))
            continue
        v = float(raw)
        margin = float(r.margin(v))
        out.append(Check(r, v, None if math.isnan(margin) else margin, bool(r.passes(v))))
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
        out.append({"name": r.name, "quantity": r.quantity, "limit": r.limit,
                    "lower": r.lower if math.isfinite(r.lower) else None,
                    "upper": r.upper if math.isfinite(r.upper) else None, "flag": r.flag,
                    "unit": r.unit, "yield": float(np.mean(r.passes(v))),
                    "margin_p5": pct[0], "margin_p50": pct[1]})
    return out
