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

**One feasibility rule, at the printed resolution**: a requirement is judged at the
resolution its value is printed with, :data:`RESOLUTION_DIGITS` significant digits of its
scale (:attr:`Requirement.tol_scale`: by default the limit's magnitude, at least 1 in the
unit; 100 for a percentage). A quantity meets its limit when it lies beyond it by less than
half that resolution (:attr:`Requirement.resolution`): 0.00005 mm on an 18 ± 0.2 mm rod
travel, 0.0005 MPa on a 1194 MPa stress, 0.000005 m/s on a 1.1 m/s velocity, far below
anything a workshop or an analyser measures; a count (:attr:`Requirement.count`) is
judged exactly. So a value printed at that resolution meets its printed limit exactly when
it passes: never a FAIL whose printed value meets its limit, never a margin in ``e-``
notation (:func:`value_text`, :func:`margin_text`). The run's own constraints are
normalised and held to :data:`~camopt.core.problem.FEASIBILITY_TOL` (1e-9 of their
scale, round-off), which is stricter: a design the run calls feasible meets every
requirement that mirrors one of its constraints. The expected yield judges every draw by
the same rule (:func:`all_pass`). A quantity the design does not reach (NaN: a stroke
never finished) is "n/a" and fails.

**At limit**: a passing requirement whose margin is smaller than half the 5-95 % spread of
its quantity under the case's default tolerances (the run's expected-yield estimate), or,
without that spread, smaller than :data:`AT_LIMIT_SHARE` of its allowed band (a two-sided
limit) or of its scale (a one-sided one), is flagged "at limit": met at nominal, not by
parts made to tolerance. A count is never at its limit (``0 <= 0`` is met exactly); a flag
is when fewer than :data:`AT_LIMIT_YIELD` of the draws keep it.

**Vocabulary** (every command, page and JSON): ``PASS at nominal`` (the nominal design
meets every requirement) always with the expected yield beside it, and green only when
the yield's 95 % interval lies at or above the case's yield target and no requirement is
at its limit (:func:`grade`); else amber; ``FAIL`` in red.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from camopt.core.documents import CheckDoc, RequirementSpread
from camopt.mechanics import Bools, Floats

RESOLUTION_DIGITS = 6
"""Significant digits of a requirement's scale it is judged and printed at (module
docstring): the resolution of the tables' values."""
DEFAULT_YIELD_TARGET = 0.95
"""The yield target of a case without a ``[robust]`` table (``robust.yield_target``'s
default): below it a design that passes at nominal is amber, not green."""
AT_LIMIT_SHARE = 0.01
"""Without a tolerance spread, a margin below 1 % of the allowed band (or of the scale of a
one-sided limit) counts as at the limit: nothing a workshop can hold is that fine."""
AT_LIMIT_YIELD = 0.95
"""A flag (latches, meets the full model) is at its limit when fewer than this share of the
tolerance draws keep it."""


def _fmt(value: float) -> str:
    return f"{value:.6g}"


def positional(value: float, decimals: int) -> str:
    """``value`` with ``decimals`` decimals, never in ``e`` notation, trailing zeros
    dropped (``1.10000`` -> ``1.1``, ``-0.0`` -> ``0``)."""
    text = f"{value:.{max(0, decimals)}f}"
    if "." in text:
        text = text.rstrip("0").rstrip(".")
    return "0" if text in ("-0", "") else text


def _decimals(step: float) -> int:
    return max(0, -math.floor(math.log10(step)))


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
    count: bool = False
    """The quantity is a whole number (parameter sets that fail, coils): judged exactly,
    never "at limit"."""

    @property
    def resolution(self) -> float:
        """The step the requirement is judged and printed at, in ``unit``: one unit of the
        :data:`RESOLUTION_DIGITS`-th significant digit of :attr:`tol_scale` (1 for a
        count)."""
        if self.count:
            return 1.0
        return 10.0 ** (math.floor(math.log10(self.tol_scale)) - (RESOLUTION_DIGITS - 1))

    @property
    def tol_scale(self) -> float:
        """The scale the resolution is relative to (see :attr:`scale`)."""
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

    def margin(self, value: Floats | float) -> Floats:
        """Distance inside the limit in ``unit`` (negative: outside; NaN: not evaluated),
        same shape as ``value``. A flag's margin is 1 for yes, -1 for no."""
        v = np.asarray(value, dtype=float)
        if self.flag:
            return np.where(np.isnan(v), np.nan, np.where(v >= 0.5, 1.0, -1.0))
        with np.errstate(invalid="ignore"):
            m = np.minimum(v - self.lower, self.upper - v)
        # an infinite value (a stress at a cusp, a stroke never finished) fails its bound
        return np.where(np.isinf(v) & ~np.isnan(m), -np.inf, m)

    def passes(self, value: Floats | float) -> Bools:
        """Bool array: the value meets the requirement (NaN fails)."""
        m = self.margin(value)
        with np.errstate(invalid="ignore"):
            return m >= -0.5 * self.resolution

    def at_limit(self, margin: float, spread: float | None = None,
                 sampled_yield: float | None = None) -> bool:
        """Whether a passing ``margin`` is too small to survive manufacture (module
        docstring): below ``spread`` (half the 5-95 % spread of the quantity under the
        default tolerances) when given, else below :data:`AT_LIMIT_SHARE` of the band or
        scale. A flag is at its limit when ``sampled_yield`` is below
        :data:`AT_LIMIT_YIELD`."""
        if self.flag:
            return sampled_yield is not None and sampled_yield < AT_LIMIT_YIELD
        if self.count:
            return False
        if spread is not None and math.isfinite(spread) and spread > 0:
            return margin < spread
        return margin < AT_LIMIT_SHARE * (self.band or self.tol_scale)


def value_text(r: Requirement, value: float) -> str:
    """``value`` as the verdict prints it, without unit: at the requirement's resolution
    (so it meets the printed limit exactly when it passes), or, for a small value well
    inside its limit, to 3 significant digits (``0.0000181``); never in ``e`` notation;
    ``inf``, ``n/a`` for NaN."""
    if math.isnan(value):
        return "n/a"
    if math.isinf(value):
        return "inf" if value > 0 else "-inf"
    if r.count:
        return positional(value, 0)
    res = r.resolution
    text = positional(round(value / res) * res, _decimals(res))
    inside = float(r.margin(value)) > res
    if value and inside and abs(value) < 100 * res:  # '0.00002' says less than '0.0000181'
        return positional(float(f"{value:.3g}"), 2 - math.floor(math.log10(abs(value))))
    return text


def margin_text(r: Requirement, margin: float) -> str:
    """A margin to 3 significant digits, never in ``e`` notation and never rounded to 0
    unless it is below half the requirement's resolution (a pass at its limit): a failing
    margin shows its excess (``-0.0000061``)."""
    if math.isnan(margin):
        return "n/a"
    if math.isinf(margin):
        return "inf" if margin > 0 else "-inf"
    if abs(margin) < 0.5 * r.resolution:
        return "0"
    if r.count:
        return positional(margin, 0)
    digits = 2 - math.floor(math.log10(abs(margin)))
    return positional(float(f"{margin:.3g}"), digits)


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

    def as_dict(self) -> CheckDoc:
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
                 or math.isnan(self.value) else f"{value_text(r, self.value)}{unit}")
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


def sentence(checks: Sequence[Check], nominal: bool = True) -> str:
    """The verdict in words: ``PASS at nominal: meets all 6 requirements`` (``PASS`` when
    not ``nominal``: a sweep's success rates), ``PASS at nominal: meets all 6
    requirements, 2 at their limit (...)`` or ``FAIL: does not latch; closing velocity
    1.31 m/s, required 0.9 ± 0.2 m/s``."""
    failed = [c for c in checks if c.passed is False]
    evaluated = sum(c.passed is not None for c in checks)
    if not evaluated:
        return "FAIL: no requirement could be evaluated"
    if not failed:
        head = "PASS at nominal" if nominal else "PASS"
        n = f"meets {'all ' if evaluated > 1 else ''}{evaluated} requirement" + (
            "s" if evaluated > 1 else "")
        close = [c.requirement.name for c in checks if c.at_limit]
        if close:
            return (f"{head}: {n}, {len(close)} at {'their' if len(close) > 1 else 'its'} "
                    f"limit ({'; '.join(close)})")
        return f"{head}: {n}"
    return "FAIL: " + "; ".join(c.words for c in failed)


def short_sentence(checks: Sequence[Check]) -> str:
    """The verdict in one short line, the requirements named only: ``FAIL: 3 of 14
    requirements (cam latches at the end of the stroke, ...)`` or ``PASS at nominal:
    meets all 6 requirements``."""
    failed = [c.requirement.name for c in checks if c.passed is False]
    evaluated = sum(c.passed is not None for c in checks)
    if not evaluated or not failed:
        return sentence(checks).split(" (", 1)[0]
    return f"FAIL: {len(failed)} of {evaluated} requirements ({'; '.join(failed)})"


GRADES = ("pass", "pass at nominal", "fail")
"""The verdict's grades (JSON ``verdict_grade``): ``pass`` (green: meets every requirement
at nominal, none at its limit, expected yield at or above the yield target), ``pass at
nominal`` (amber: meets them at nominal, but at a limit, below the target or with no
yield estimate) and ``fail`` (red)."""
GRADE_STYLES = {"pass": "green", "pass at nominal": "yellow", "fail": "red"}
"""The grades' colours on a terminal (amber is rich's ``yellow``)."""


def grade(verdict: str | None, at_limit: bool, expected: float | None,
          target: float | None) -> str | None:
    """The verdict's grade (:data:`GRADES`) from the nominal ``verdict`` ("pass"/"fail"),
    whether a requirement is at its limit, the ``expected`` yield (None: not estimated) and
    the yield ``target``; None when not judged."""
    if verdict is None:
        return None
    if verdict != "pass":
        return "fail"
    if at_limit or expected is None or target is None or expected < target:
        return "pass at nominal"
    return "pass"


def yields(requirements: Sequence[Requirement], samples: Mapping[str, Floats],
           ) -> list[RequirementSpread]:
    """Per requirement, its finite limits (``lower``/``upper``, None when unbounded), the
    share of ``samples`` (``{quantity: (n,)}``) that passes and the margin's percentiles;
    requirements whose quantity is not sampled are left out."""
    out: list[RequirementSpread] = []
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


def all_pass(requirements: Sequence[Requirement], samples: Mapping[str, Floats]) -> Bools:
    """(n,) bool: each sample meets every requirement whose quantity ``samples`` holds (an
    all-true column when none is sampled)."""
    n = len(next(iter(samples.values()))) if samples else 0
    ok = np.ones(n, dtype=bool)
    for r in requirements:
        if r.quantity in samples:
            ok &= r.passes(np.asarray(samples[r.quantity], dtype=float))
    return ok
