"""Pydantic models of a case file: ``[case]``, ``[solver]`` and ``[run]``.

Units: a field whose name ends in ``_mm``, ``_deg``, ``_kg``, ``_gpa`` ... is in
that unit; everything else is SI or unitless. Cases convert to SI when they
build their Problem. Each case's own config model lives beside the case
(``camopt/cases/<kind>/config.py``) and subclasses :class:`CaseConfig`.

tomli_w is imported where a case file is written (``camopt init``), not when one is read.
"""

from __future__ import annotations

import math
import re
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Annotated, Any, ClassVar, Literal

from pydantic import (
    BaseModel,
    BeforeValidator,
    ConfigDict,
    Field,
    ValidationInfo,
    field_validator,
    model_validator,
)

# Every float of a case file is finite (``allow_inf_nan=False`` on :class:`Strict`) and at
# most MAX_MAGNITUDE in size: no length, mass, rate or modulus of a mechanism in the units
# the field names carry (mm, kg, N, MPa, GPa ...) comes near 1e12, while values like 1e308
# overflow the physics (squares, exponentials) into inf and NaN.
MAX_MAGNITUDE = 1e12

Positive = Annotated[float, Field(gt=0)]


def _as_tuple(value: Any) -> Any:
    """A TOML array (a list) as the tuple a fixed-length field holds; strict mode refuses
    a list for a tuple, and the numbers inside are still checked strictly."""
    return tuple(value) if isinstance(value, list) else value


AsTuple = BeforeValidator(_as_tuple)
"""Metadata of every tuple field: ``Annotated[tuple[float, float], AsTuple]``."""
Pair = Annotated[tuple[float, float], AsTuple]

PLAUSIBILITY_KEY = "check_plausibility"


@dataclass(frozen=True)
class Plausible:
    """Physical range of a field for its mechanism, checked after validation: a value
    outside it is bad input (a length in metres typed into an mm field, say) unless the
    case file sets ``run.check_plausibility = false``. Use as ``Annotated`` metadata:
    ``Annotated[Positive, Plausible(1, 5000)]``."""

    lower: float
    upper: float


def _too_large(value: Any) -> float | None:
    """The first float in ``value`` (nested lists, tuples, dicts) above MAX_MAGNITUDE."""
    if isinstance(value, float):
        return value if math.isfinite(value) and abs(value) > MAX_MAGNITUDE else None
    if isinstance(value, (list, tuple)):
        items: Any = value
    elif isinstance(value, dict):
        items = value.values()
    else:
        return None
    for item in items:
        found = _too_large(item)
        if found is not None:
            return found
    return None


class Strict(BaseModel):
    """Base of every config model: unknown keys are errors; every float is finite and at
    most MAX_MAGNITUDE in size; fields with :class:`Plausible` metadata are in range."""

    # strict: a number is a number (``population = "10"``, ``repeats = true`` and
    # ``generations = 2.0`` are refused naming the field, not converted); an integer is
    # still a float. defer_build: a model's validator is built when first used, so a
    # command that reads one case kind does not build every case's and solver's (~0.1 s
    # CPU at start-up)
    model_config = ConfigDict(extra="forbid", frozen=True, allow_inf_nan=False, strict=True,
                              defer_build=True)

    @field_validator("*", mode="after")
    @classmethod
    def _physical(cls, value: Any, info: ValidationInfo) -> Any:
        big = _too_large(value)
        if big is not None:
            raise ValueError(f"{big:g} is beyond {MAX_MAGNITUDE:g} in size: no quantity of a "
                             "mechanism in this field's unit is that large")
        if (info.context or {}).get(PLAUSIBILITY_KEY) is False or info.field_name is None:
            return value
        # one number, or each number of a pair (closing_velocity_m_s = [0.7, 1.1])
        numbers = [value] if isinstance(value, (int, float)) else list(
            value) if isinstance(value, (tuple, list)) else []
        numbers = [v for v in numbers if isinstance(v, (int, float))
                   and not isinstance(v, bool)]
        for meta in cls.model_fields[info.field_name].metadata:
            bad = [v for v in numbers if isinstance(meta, Plausible)
                   and not meta.lower <= v <= meta.upper]
            if bad and isinstance(meta, Plausible):
                unit = _unit(info.field_name)
                raise ValueError(
                    f"{bad[0]:g} is outside the physical range [{meta.lower:g}, "
                    f"{meta.upper:g}]{unit} of this mechanism (a value in another unit?); "
                    f"set run.{PLAUSIBILITY_KEY} = false to accept it")
        return value


# a field name's unit suffix and the unit it names, longest suffixes first
UNIT_SUFFIXES = (
    ("_kn_per_mm3", "kN/mm^3"), ("_n_per_mm", "N/mm"), ("_sqrt_mpa", "sqrt(MPa)"),
    ("_kg_m2", "kg m^2"), ("_m_s", "m/s"), ("_mm", "mm"), ("_deg", "deg"), ("_rad", "rad"),
    ("_kg", "kg"), ("_gpa", "GPa"), ("_mpa", "MPa"), ("_nm", "N m"), ("_n", "N"),
    ("_ms", "ms"), ("_s", "s"), ("_j", "J"), ("_pct", "%"), ("_m", "m"),
)


def unit_of(name: str) -> str:
    """The unit a field's name carries ('mm' for ``l1_mm``, 'N/mm' for ``k_n_per_mm``);
    '' for a name without a unit suffix (SI or unitless)."""
    return next((unit for suffix, unit in UNIT_SUFFIXES if name.endswith(suffix)), "")


def _unit(name: str) -> str:
    """' mm' for ``l1_mm``, '' for a field without a unit suffix."""
    unit = unit_of(name)
    return f" {unit}" if unit else ""


class Bounds(Strict):
    """A closed interval ``[lower, upper]`` with ``lower < upper``."""

    lower: float
    upper: float

    @model_validator(mode="before")
    @classmethod
    def _from_pair(cls, value: object) -> object:
        if isinstance(value, (list, tuple)):
            if len(value) != 2:
                raise ValueError("bounds must be a pair [lower, upper]")
            return {"lower": value[0], "upper": value[1]}
        return value

    @model_validator(mode="after")
    def _ordered(self) -> Bounds:
        if not self.lower < self.upper:
            raise ValueError(f"lower bound {self.lower} must be below upper bound {self.upper}")
        return self

    def as_list(self) -> list[float]:
        return [self.lower, self.upper]


MAX_REPEATS = 10_000
# Size and budget caps of solver options (each option's description repeats its reason).
# Memory: a population's evaluation holds several arrays of n_pop x samples floats (VCB:
# 141 samples, EMB: ~400), so 10,000 designs stay within ~1 GB; the papers use 100.
MAX_POPULATION = 10_000
# Time: 100,000 iterations of a 100-design population is 10^7 evaluations per repeat,
# hours on one core for the slower cases; the papers use 300-500.
MAX_ITERATIONS = 100_000
# Local starts and their scipy iterations (one start is one scipy solve).
MAX_STARTS = 10_000
MAX_LOCAL_ITERATIONS = 1_000_000
MAX_NAME_BYTES = 100
# a run name becomes a file name: word characters (any script), '.', '_', '-', '+'; not
# starting with '.' (hidden files, '..'); no separators, NUL, spaces or markup brackets
_SAFE_NAME = re.compile(r"[^\W_][\w.+-]*|_[\w.+-]*")


def safe_name(name: str) -> str:
    """``name`` when it is safe as a file name (see ``_SAFE_NAME``); ValueError otherwise."""
    if not _SAFE_NAME.fullmatch(name):
        raise ValueError("must be a file name: letters, digits, '.', '_', '-', '+', not "
                         "starting with '.' (no '/', spaces or other characters)")
    if len(name.encode()) > MAX_NAME_BYTES:
        raise ValueError(f"longer than {MAX_NAME_BYTES} bytes (the archive's file name adds "
                         "a timestamp and must stay within the 255-byte limit)")
    return name


class RunSection(Strict):
    """``[run]``: naming, seeding and repeats of a run."""

    name: str = Field("run", description="name of the run; the archive is runs/<name>-<time>.h5 "
                      "(letters, digits, '.', '_', '-', '+'; at most 100 bytes)")
    seed: int = Field(0, ge=0, lt=2**128, description="root seed; repeats get "
                      "SeedSequence(seed).spawn(n) (below 2^128: SeedSequence's own entropy)")
    repeats: int = Field(1, ge=1, le=MAX_REPEATS, description="independent repeats of the "
                         f"solver (at most {MAX_REPEATS}: each is a group in the archive)")
    target: float | None = Field(
        None, description="objective at or below which a feasible repeat counts as a success"
    )
    min_success_rate: float | None = Field(
        None, ge=0, le=1, description="sweep --check fails below this success rate"
    )
    max_evaluations: int | None = Field(
        None, ge=1, description="stop a repeat once its solver has used this many evaluations "
        "(besides the solver's own budget)")
    max_seconds: float | None = Field(
        None, gt=0, description="stop a repeat after this many seconds of wall time "
        "(besides the solver's own budget; not reproducible across machines)")
    check_plausibility: bool = Field(
        True, description="reject case values outside the physical ranges of the case's "
        "config model (false: accept them)")
    next_config: str | None = Field(
        None, description="a case file (path relative to this one) that requires what this "
        "run's search leaves out: show's next: line names it when the best design fails a "
        "requirement (not inherited through extends)")

    @field_validator("name")
    @classmethod
    def _safe_name(cls, name: str) -> str:
        return safe_name(name)



MAX_ROBUST_SAMPLES = 1_000
MAX_CHECK_SAMPLES = 1_000_000


class RobustSection(Strict):
    """``[robust]``: optimise for yield under manufacturing tolerances (docs/tolerance.md,
    "Robust design"). Every candidate is evaluated at ``samples`` perturbed copies (common
    random numbers: one set per generation, the same for every candidate) and counts as
    feasible when its estimated yield reaches ``yield_target``."""

    vary: dict[str, str] = Field(
        default_factory=dict, description="tolerances { NAME = \"±X%\" or \"±X\" }, NAME a "
        "design variable or case.FIELD as camopt tolerance's --vary (empty: the case's "
        "tolerance class, case.tolerance_class)")
    samples: int = Field(16, ge=2, le=MAX_ROBUST_SAMPLES, description="perturbed copies per "
                         f"candidate and generation (at most {MAX_ROBUST_SAMPLES}: memory)")
    yield_target: float = Field(0.95, gt=0, le=1, description="required share of parts "
                                "meeting every constraint: a repeat's result is feasible when "
                                "the lower bound of its yield's Clopper-Pearson interval on "
                                "check_samples fresh draws reaches it")
    search_yield: float | None = Field(
        None, gt=0, le=1, description="share of a generation's draws a candidate must pass "
        "during the search (unset: yield_target); above it, a margin against lucky draws")
    objective: Literal["nominal", "mean", "quantile", "margin"] = Field(
        "nominal", description="what is minimised: the nominal design's objective, its mean "
        "over the samples, or its quantile (below); margin: the yield column itself, the "
        "worst normalised constraint at the yield target's order statistic (the most robust "
        "design; the case's objective is reported, not optimised)")
    quantile: float = Field(0.9, gt=0, lt=1, description="the objective's quantile when "
                            "objective = \"quantile\"")
    distribution: Literal["uniform", "normal"] = Field(
        "uniform", description="uniform on nominal ± X, or normal with sigma = X/3")
    draws: Literal["generation", "repeat"] = Field(
        "generation", description="common random numbers: a new set of samples draws every "
        "generation (a design that passed one set by luck meets another), or one set for "
        "the whole repeat (a sample-average approximation: the search sees one deterministic "
        "function; the finalists' fresh draws judge what it fitted to its set)")
    screen: bool = Field(True, description="sample only candidates whose nominal design "
                         "meets every constraint (the others keep their nominal violation)")
    finalists: int = Field(8, ge=0, le=MAX_ROBUST_SAMPLES, description="designs that met "
                           "the target on their generation's draws checked again on fresh "
                           "draws at the end of a repeat, with the solver's best")
    check_samples: int = Field(4000, ge=100, le=MAX_CHECK_SAMPLES, description="fresh "
                               "draws of that selection and of the final check of the best")
    confidence: float = Field(0.95, gt=0, lt=1, description="level of the final yield's "
                              "Clopper-Pearson interval")
    race: int = Field(0, ge=0, le=MAX_CHECK_SAMPLES, description="racing: a candidate's "
                      "draws are evaluated in stages (this many, as many again, then "
                      "doubling), and a candidate stops once it has failed more draws than "
                      "its order statistic allows (it can no longer meet the search's or "
                      "the selection's target on these draws); 0 (default): every draw at once. "
                      "Speed: feasibility is the same, an infeasible candidate's margins "
                      "come from fewer draws")
    chunk_rows: int | None = Field(None, ge=1, le=10_000_000, description="rows "
                                   "(candidates x samples) per vectorised call (unset: "
                                   "camopt.core.batch's default): memory and speed, never results")
    centre_generations: int = Field(0, ge=0, le=MAX_ITERATIONS, description="yield "
                                    "centring after the search: generations of a local "
                                    "CMA-ES that moves the repeat's result to where the "
                                    "most of centre_samples fixed draws pass (smoothed); "
                                    "kept only if more of the selection's fresh draws pass "
                                    "(docs/tolerance.md, \"Yield centring\"); 0: none")
    centre_samples: int = Field(256, ge=2, le=MAX_ROBUST_SAMPLES, description="fixed draws "
                                "of the yield centring")
    centre_step: float = Field(0.002, gt=0, le=1, description="the centring's initial step, "
                               "a fraction of each variable's range")

    @model_validator(mode="after")
    def _centring_maximises_the_yield(self) -> RobustSection:
        # the centring trades the case's objective for yield (on the tests' two-part window
        # it moved a design meeting its target to +21 % objective): only where the
        # objective is the yield margin itself does that leave the result's meaning
        if self.centre_generations and self.objective != "margin":
            raise ValueError("centre_generations needs objective = \"margin\": the "
                             "centring maximises the yield, not the objective")
        return self


class SolverOptions(Strict):
    """Base of every solver's options; ``name`` selects the solver."""

    name: str


FieldRole = Literal["hardware", "identified", "requirement", "solver setting",
                    "measured data"]
ROLES: dict[str, str] = {
    "hardware": "describes the breaker as built or drawn (geometry, springs, materials, "
    "loads, the reference design): change it with the hardware",
    "identified": "fitted to measurements, not read off a drawing: re-identify it after a "
    "geometry change (camopt calibrate on travel curves, or an identification case)",
    "requirement": "what a design must meet (a constraint or a reported limit), from the "
    "specification, a standard or an assumption",
    "solver setting": "how camopt models, searches and reports (search bounds, grids, "
    "penalties, seeds): no property of the breaker",
    "measured data": "a measurement an identification fits (a datum and its reading error)",
}
"""What each field role means (``docs/cases``, ``camopt init``)."""


class CaseConfig(Strict):
    """Base of every case's parameters; ``kind`` selects the case. A case may mark each
    field with its role (``field_roles``: field name -> :data:`FieldRole`); ``docs/cases``
    and ``camopt init`` show it."""

    field_roles: ClassVar[Mapping[str, FieldRole]] = {}

    kind: str
    tolerance_class: str | None = Field(
        None, description="manufacturing tolerance class the parts are made to, used by "
        "camopt tolerance and robust design (the case's classes and their sources: "
        "docs/tolerance.md; unset: the case's default class)")


def toml_comment(text: object) -> str:
    """User text (a file name, a label) for a TOML comment: printable characters as they
    are, every other one as its Python escape (``\\n``, ``\\x1b``, ``\\u2028``). A
    comment ends at a line break, so a newline in a name written raw would start a live
    line (``run = {repeats = 777}``) in the file; TOML forbids other control characters in
    comments too."""
    text = str(text)
    return "".join(c if c.isprintable() else repr(c)[1:-1] for c in text)


def toml_string(text: str) -> str:
    """``text`` as a TOML basic string (quotes, backslashes and control characters
    escaped: tomli_w), on one line."""
    import tomli_w

    return tomli_w.dumps({"v": text}).split("=", 1)[1].strip()


def _toml_value(value: object) -> str:
    """One TOML value on one line (tables inline, so every field stays a single line)."""
    import tomli_w

    if isinstance(value, BaseModel):
        value = value.model_dump(mode="json", exclude_none=True)
    if isinstance(value, dict):
        return "{ " + ", ".join(f"{k} = {_toml_value(v)}" for k, v in value.items()) + " }"
    if isinstance(value, (list, tuple)):
        return "[" + ", ".join(_toml_value(v) for v in value) + "]"
    return tomli_w.dumps({"v": value}).split("=", 1)[1].strip()


def _section(title: str, model: BaseModel) -> list[str]:
    lines = [f"[{title}]"]
    for name, info in type(model).model_fields.items():
        value = getattr(model, name)
        if isinstance(value, Bounds):
            value = value.as_list()
        if isinstance(value, dict) and not value:
            lines += [f"# {info.description}", f"# {name} = {{ }}"] if info.description else []
            continue
        if info.description:
            unit = unit_of(name)
            role = role_of(type(model), name)
            lines.append(f"# {info.description}" + (f" [{unit}]" if unit else "")
                         + (f" ({role})" if role else ""))
        if value is None:
            lines.append(f"# {name} =   (unset)")
        else:
            lines.append(f"{name} = {_toml_value(value)}")
    return lines


def role_of(model: type[BaseModel], name: str) -> str | None:
    """The role of a case field (``CaseConfig.field_roles``), None where it has none."""
    roles: Mapping[str, str] = getattr(model, "field_roles", {})
    return roles.get(name)


def template(case_model: type[CaseConfig], solver: SolverOptions) -> str:
    """A commented case file for a case config model with every default written out."""
    case = case_model.model_validate({})
    kind = case.kind
    lines = [f"# camopt case file for '{kind}'. Units are in the field names; others are SI.", ""]
    if case_model.field_roles:
        lines += ["# Each [case] field's role is in parentheses at the end of its comment:"]
        lines += [f"#   ({role}): {meaning}" for role, meaning in ROLES.items()
                  if role in set(case_model.field_roles.values())]
        lines += [""]
    lines += _section("case", case) + [""]
    lines += _section("solver", solver) + [""]
    lines += _section("run", RunSection(name=kind))
    return "\n".join(lines) + "\n"
