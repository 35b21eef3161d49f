"""Pydantic models of a case file: ``[case]``, ``[solver]`` and ``[run]``.

Units: a field whose name ends in ``_mm``, ``_deg``, ``_kg``, ``_gpa`` ... is in
that unit; everything else is SI or unitless. Cases convert to SI when they
build their Problem. Each case's own config model lives beside the case
(``camopt/cases/<kind>/config.py``) and subclasses :class:`CaseConfig`.
"""

from __future__ import annotations

from typing import Annotated

from pydantic import BaseModel, ConfigDict, Field, model_validator

Positive = Annotated[float, Field(gt=0)]
Pair = tuple[float, float]


class Strict(BaseModel):
    """Base of every config model: unknown keys are errors."""

    model_config = ConfigDict(extra="forbid", frozen=True)


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


class RunSection(Strict):
    """``[run]``: naming, seeding and repeats of a run."""

    name: str = Field("run", description="name of the run; the archive is runs/<name>-<time>.h5")
    seed: int = Field(0, ge=0, description="root seed; repeats get SeedSequence(seed).spawn(n)")
    repeats: int = Field(1, ge=1, description="independent repeats of the solver")
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


class SolverOptions(Strict):
    """Base of every solver's options; ``name`` selects the solver."""

    name: str


class CaseConfig(Strict):
    """Base of every case's parameters; ``kind`` selects the case."""

    kind: str


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
            lines.append(f"# {info.description}")
        if value is None:
            lines.append(f"# {name} =   (unset)")
        else:
            lines.append(f"{name} = {_toml_value(value)}")
    return lines


def template(case_model: type[CaseConfig], solver: SolverOptions) -> str:
    """A commented case file for a case config model with every default written out."""
    case = case_model()
    kind = case.kind
    lines = [f"# camopt case file for '{kind}'. Units are in the field names; others are SI.", ""]
    lines += _section("case", case) + [""]
    lines += _section("solver", solver) + [""]
    lines += _section("run", RunSection(name=kind))
    return "\n".join(lines) + "\n"
