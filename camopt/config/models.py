"""Pydantic models of a case file: ``[case]``, ``[solver]`` and ``[run]``.

Units: a field whose name ends in ``_mm``, ``_deg``, ``_kg``, ``_gpa`` ... is in
that unit; everything else is SI or unitless. Cases convert to SI when they
build their Problem.
"""

from __future__ import annotations

from typing import Annotated, Literal

from pydantic import BaseModel, ConfigDict, Field, model_validator

Positive = Annotated[float, Field(gt=0)]


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


class SolverOptions(Strict):
    """Base of every solver's options; ``name`` selects the solver."""

    name: str


class CaseConfig(Strict):
    """Base of every case's parameters; ``kind`` selects the case."""

    kind: str


class FastSwitchConfig(CaseConfig):
    """Fast acting switch, Clauss & Papalambros (1982): Nomenclature parameters."""

    kind: Literal["fast_switch"] = "fast_switch"
    link2_length_mm: Positive = Field(200.0, description="L, total length of link 2")
    half_piston_mm: Positive = Field(50.0, description="p4, one-half piston length")
    m2_kg: Positive = Field(0.5, description="M2, mass of part 2")
    m3_kg: Positive = Field(0.75, description="M3, mass of part 3")
    m4_kg: Positive = Field(0.5, description="M4, mass of part 4 (piston)")
    spring_diameter_mm: Positive = Field(20.0, description="D, spring coil diameter")
    wire_diameter_mm: Positive = Field(2.0, description="d, spring wire diameter")
    wire_strength_a_mpa: Positive = Field(1880.0, description="A, wire strength coefficient")
    wire_strength_exponent: float = Field(0.186, ge=0, lt=1, description="m, strength exponent")
    wire_strength_d_unit: Literal["m", "mm"] = Field(
        "m",
        description="unit of d inside A*d**-m; 'm' reproduces Table 1, 'mm' is Shigley's "
        "(see docs/assumptions.md)",
    )
    shear_modulus_gpa: Positive = Field(
        207.0, description="G as printed (207 GPa reproduces Table 1; steel is about 79 GPa)"
    )
    max_initial_angle_deg: float = Field(
        30.0, gt=0, le=90, description="W, largest initial angle of part 2 (arcing)"
    )
    max_joint_load_n: Positive = Field(1500.0, description="F_rated, joint strength")
    min_coils: int = Field(3, ge=1, description="practical least number of coils")
    max_coils: int = Field(42, ge=1, description="largest coil count searched")
    branch: Literal["I", "II", "both"] = Field(
        "both", description="sign of sf - sud allowed: I (sf >= sud), II (sf <= sud) or both"
    )
    reduced_form: Literal["corrected", "printed"] = Field(
        "corrected",
        description="7-variable statement: 'printed' as in the paper (has errors), or "
        "'corrected' (loop equations solved exactly, right arcsine branch)",
    )
    sf_bounds_mm: Bounds = Field(Bounds(lower=1, upper=400), description="x3 search bounds")
    sud_bounds_mm: Bounds = Field(Bounds(lower=1, upper=400), description="x4 search bounds")
    s0_bounds_mm: Bounds = Field(Bounds(lower=1, upper=400), description="x5 search bounds")
    r3_bounds_mm: Bounds = Field(Bounds(lower=10, upper=600), description="x6 search bounds")
    r2_bounds_mm: Bounds = Field(Bounds(lower=1, upper=200), description="x7 search bounds")

    @model_validator(mode="after")
    def _coils_ordered(self) -> FastSwitchConfig:
        if self.min_coils >= self.max_coils:
            raise ValueError(f"min_coils {self.min_coils} must be below max_coils {self.max_coils}")
        return self


CASE_CONFIGS: dict[str, type[CaseConfig]] = {
    "fast_switch": FastSwitchConfig,
}


def _toml_value(value: object) -> str:
    import tomli_w

    return tomli_w.dumps({"v": value}).split("=", 1)[1].strip()


def _section(title: str, model: BaseModel) -> list[str]:
    lines = [f"[{title}]"]
    for name, info in type(model).model_fields.items():
        value = getattr(model, name)
        if isinstance(value, Bounds):
            value = value.as_list()
        if info.description:
            lines.append(f"# {info.description}")
        if value is None:
            lines.append(f"# {name} =   (unset)")
        else:
            lines.append(f"{name} = {_toml_value(value)}")
    return lines


def template(kind: str, solver: SolverOptions) -> str:
    """A commented case file for ``kind`` with every default written out."""
    case = CASE_CONFIGS[kind]()
    lines = [f"# camopt case file for '{kind}'. Units are in the field names; others are SI.", ""]
    lines += _section("case", case) + [""]
    lines += _section("solver", solver) + [""]
    lines += _section("run", RunSection(name=kind))
    return "\n".join(lines) + "\n"
