"""Case registry: one :class:`CaseSpec` per mechanism, registered like a solver.

Built-in cases are the sub-packages of :mod:`camopt.cases`, found by listing them (so a
source checkout without installed metadata works, and no list names them); each
registers its spec when imported. Packages outside camopt add cases through the
``camopt.cases`` entry-point group, whose entry points name a ``CaseSpec`` (or a module
that registers one). Nothing else in camopt names a case kind: the CLI, archive, plots
and export ask the registry.

A look-up by kind (:func:`get_case`, :func:`case_configs`) imports only the package the
kind's entry point names (pyproject.toml declares every built-in case there), not every
case: a command that reads one case file or archive starts without the others' models
(:mod:`camopt.core.plugins`). Listing (:func:`cases`) imports them all.
"""

from __future__ import annotations

import importlib
from collections.abc import Callable, Collection, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from types import SimpleNamespace
from typing import TYPE_CHECKING, Any, Protocol

from camopt.core.plugins import OnDemand, entry_points, look_up
from camopt.core.requirements import Requirement
from camopt.errors import ConfigError, did_you_mean, from_interrupt

if TYPE_CHECKING:
    from importlib.metadata import EntryPoint

    from matplotlib.figure import Figure

    from camopt.config.models import CaseConfig
    from camopt.core.calibration import Calibrated, CalibrationRequest
    from camopt.core.problem import Problem
    from camopt.core.runview import RunView
    from camopt.mechanics.cam_outline import CamOutline

ENTRY_POINT_GROUP = "camopt.cases"


class RequirementsOf(Protocol):
    """A case's requirements for a run's ``[case]`` (as a dict) whose designs report the
    quantities ``names`` (``camopt/cases/<kind>/requirements.py``)."""

    def __call__(self, case: Mapping[str, Any], names: Collection[str]
                 ) -> tuple[Requirement, ...]: ...


class ArchiveLoader(Protocol):
    """Loads another run's archive named by a case-file key (``case.cam_archive``); a
    missing or damaged archive is a ConfigError against that key."""

    def __call__(self, key: str, path: str, /) -> RunView: ...

    def locate(self, key: str, path: str, /) -> Path:
        """Another input file named by a case-file key (``case.reference_cam_points``),
        found as the archives are: in the working folder, else beside the case file; a
        missing one is a ConfigError against that key."""


@dataclass(frozen=True)
class ProfileCurve:
    """A planar curve of a case's analysis exported for CAD: a file ``name`` and the
    analysis curves of its x and y coordinates in mm (several curves are joined in order)."""

    name: str
    x: tuple[str, ...]
    y: tuple[str, ...]


@dataclass(frozen=True)
class ProfileCircle:
    """A circle drawn with a case's profiles in CAD export (base circle, roller): a layer
    ``name``, the ``[case]`` field holding its radius in mm, and the analysis curves whose
    first point is its centre in mm (``None``: the cam's centre, the origin)."""

    name: str
    radius: str
    centre: tuple[str, str] | None = None


@dataclass(frozen=True)
class ToleranceClass:
    """A named set of manufacturing tolerances a case's parts can be ordered to
    (docs/tolerance.md, "Tolerance classes"): ``{design variable or "case.FIELD": "±X%"
    or "±X"}``, the standard or practice it follows, and its cost relative to the case's
    default class (1: the default; a spring maker's grading of springs by force, a ground
    instead of a machined profile cost more). The cost is documented, not computed: it
    ranks classes for ``camopt tolerance --allocate``."""

    tolerances: Mapping[str, str]
    source: str
    relative_cost: float = 1.0


@dataclass(frozen=True)
class OverlayCurve:
    """An analysis curve drawn for several runs on one axes (``camopt plot A.h5 B.h5``):
    a figure ``name`` and ``title``, the analysis curves of x and y and their labels."""

    name: str
    title: str
    x: str
    y: str
    xlabel: str
    ylabel: str


@dataclass(frozen=True)
class Adjustment:
    """A parameter the factory sets on each unit at assembly (a spring's preload nut, a
    pushrod's length) until a measured quantity reads its target: ``name`` for people;
    ``metric``, the travel each design needs (signed, in ``unit``; +inf: none reaches
    the target), as the case's evaluation reports it; ``reach``, the case field with how
    far it may move either way; ``target``, what it is set to, in words. ``camopt
    tolerance`` reports its distribution over the draws and the share out of reach."""

    name: str
    metric: str
    reach: str
    unit: str
    target: str


@dataclass(frozen=True)
class CaseSpec:
    """Everything camopt needs to know about one mechanism.

    ``problem`` is the Problem class, or ``"module:Class"`` (:func:`problem_at`) imported
    when ``spec.problem`` is first read (building a problem, listing solvers): a command
    that reads a case file or archive without building its problem (``init``, ``show``)
    does not import the case's model (start-up time). ``figures`` is ``"module:function"``,
    imported only when figures are drawn (matplotlib is slow to import); the function
    takes a :class:`~camopt.core.runview.RunView` and returns ``{name: Figure}``.
    ``paper`` holds the paper's reported values, used to mark figures only, never by a
    model. ``resolve`` fills config values that come from other run
    archives (VCB step 2's cam) before a run.
    """

    kind: str
    config: type[CaseConfig]
    problem: type[Problem]
    default_solver: str
    summary: str = ""
    paper_source: str = ""
    figures: str | None = None
    profiles: tuple[ProfileCurve, ...] = ()
    circles: tuple[ProfileCircle, ...] = ()
    overlays: tuple[OverlayCurve, ...] = ()
    """Curves ``camopt plot A.h5 B.h5`` draws for both runs on the same axes (the
    ``profiles`` are overlaid too)."""
    outline: str | None = None
    """``"module:function"`` giving a run's closed cam outline for the workshop,
    ``function(run, step_rad | None) -> CamOutline | None`` (imported when exported)."""
    paper: Mapping[str, Any] = field(default_factory=dict)
    resolve: Callable[[CaseConfig, ArchiveLoader], CaseConfig] | None = None
    tolerances: Mapping[str, str] = field(default_factory=dict)
    """Realistic manufacturing tolerances of the case's default class
    (``default_tolerance_class``), ``camopt tolerance``'s default ``--vary``:
    ``{design variable or "case.FIELD": "±X%" or "±X"}`` (docs/tolerance.md); those
    that do not apply to a run (not its variables, not a field its case varies) are
    skipped."""
    default_tolerance_class: str = "standard"
    """The name of the class ``tolerances`` describes (``case.tolerance_class`` unset)."""
    tolerance_classes: Mapping[str, ToleranceClass] = field(default_factory=dict)
    """Other classes the parts can be ordered to, by name (``case.tolerance_class`` or
    ``camopt tolerance --class``); each lists every input it tolerances."""
    profile_tolerance: str | None = None
    """The tolerance key (``"case.FIELD"`` or a design variable) whose ``±X`` in the run's
    tolerance class is the cam profile's radial tolerance in mm, noted on the DXF and
    bounding its chord error (``camopt export --chord-error-mm``); None: not stated."""
    equivalence: float | None = None
    """``compare``'s practical-equivalence threshold in the objective's unit: medians of
    two runs closer than this are one result whatever the p-value; None: 0.1 % of the
    larger median (:data:`camopt.core.stats.EQUIVALENCE_RTOL`)."""
    requirements: RequirementsOf | None = None
    """What a design must meet whatever the run optimised (:mod:`camopt.core.requirements`);
    ``show``, ``report``, ``compare`` and ``tolerance`` evaluate them."""
    reference: str = ""
    """The one name of the design the optimum is shown beside: ``"vendor, Sec 2.3"``
    (shown as ``reference: vendor, Sec 2.3``)."""
    reference_values: Mapping[str, Any] = field(default_factory=dict)
    """The reference design's values by the run's names when the case does not report
    them as ``initial_``/``original_`` metrics (a paper's optimum)."""
    adjustments: tuple[Adjustment, ...] = ()
    """What the factory sets on each unit at assembly, where a run models it."""
    calibration: str | None = None
    """``"module:function"`` that calibrates the case on measured curves (``camopt
    calibrate``, :mod:`camopt.core.calibration`: it returns a ``Calibrated``); None: the
    case has none."""
    variable_names: Callable[[Any], tuple[str, ...]] | None = None
    """The design variables' names for a validated config of this kind, without building
    its Problem: ``show`` and ``runs`` check an archive's names with it and import no case
    model (tests/cases/test_registry.py compares it with the Problem's); None: the
    Problem is built to ask."""

    def names_of(self, config: CaseConfig) -> tuple[str, ...]:
        """The design variables' names for ``config`` (:attr:`variable_names`, else the
        Problem's)."""
        if self.variable_names is not None:
            return tuple(self.variable_names(config))
        return tuple(self.build(config).names)

    def stored_names(self, case: Mapping[str, Any]) -> tuple[str, ...] | None:
        """The names :attr:`variable_names` gives for a run's stored ``[case]`` table (a
        dict: the config as validated when the run was written), its fields read as
        attributes without validating it again (no config model imported); None when the
        case has no :attr:`variable_names` or the table cannot answer (a field it lacks,
        a value of another kind: an archive of another version)."""
        if self.variable_names is None:
            return None
        try:
            return tuple(self.variable_names(SimpleNamespace(**case)))
        except Exception as exc:
            if from_interrupt(exc):
                raise
            return None

    def class_names(self) -> tuple[str, ...]:
        """Every tolerance class of the case, cheapest (loosest) first; the default class
        costs 1."""
        cost = {self.default_tolerance_class: 1.0,
                **{n: c.relative_cost for n, c in self.tolerance_classes.items()}}
        return tuple(sorted(cost, key=lambda n: cost[n]))

    def class_cost(self, name: str) -> float:
        """A class's documented cost relative to the default class."""
        return 1.0 if name == self.default_tolerance_class else \
            self.tolerance_classes[name].relative_cost

    def tolerances_of(self, name: str | None, source: str = "<case>",
                      key: str = "case.tolerance_class") -> Mapping[str, str]:
        """The tolerances of class ``name`` (None: the default class); an unknown name is
        a ConfigError against ``key`` listing the case's classes."""
        if name is None or name == self.default_tolerance_class:
            return self.tolerances
        if name not in self.tolerance_classes:
            raise ConfigError(source, key, f"{name!r}: not a tolerance class of case "
                              f"'{self.kind}' (classes: {', '.join(self.class_names())})")
        return self.tolerance_classes[name].tolerances

    def profile_tolerance_mm(self, run: RunView) -> float | None:
        """The cam profile's radial tolerance (mm, the ``±X`` of :attr:`profile_tolerance`
        in the run's ``case.tolerance_class``); None when the case states none or its
        class gives it as a percentage."""
        if self.profile_tolerance is None:
            return None
        text = self.tolerances_of(run.case.get("tolerance_class"), run.path).get(
            self.profile_tolerance, "")
        value = text.strip().removeprefix("±").removeprefix("+-")
        try:
            return None if value.endswith("%") else abs(float(value))
        except ValueError:
            return None

    def build(self, config: CaseConfig) -> Problem:
        """The case's Problem for a validated config of this kind."""
        return self.problem(config)  # type: ignore[call-arg]

    def calibrate(self, config: CaseConfig, request: CalibrationRequest
                  ) -> Calibrated:
        """Calibrate the case on measured curves (the fits, the verdict and the case's
        parts of the report); a case without a calibration is a ConfigError naming its
        kind."""
        if self.calibration is None:
            raise ConfigError("case", "kind", f"{self.kind!r} has no calibration on "
                              "measured curves")
        module, _, name = self.calibration.partition(":")
        return getattr(importlib.import_module(module), name)(config, request)

    def draw(self, run: RunView) -> dict[str, Figure]:
        """The case's figures of a loaded run (empty when the case draws none)."""
        if self.figures is None:
            return {}
        module, _, name = self.figures.partition(":")
        return getattr(importlib.import_module(module), name)(run)

    def cam_outline(self, run: RunView, step: float | None = None) -> CamOutline | None:
        """The run's closed cam outline (None when the case draws none or the archive
        lacks the law); ``step`` its sampling in rad (None: the case's grid)."""
        if self.outline is None:
            return None
        module, _, name = self.outline.partition(":")
        return getattr(importlib.import_module(module), name)(run, step)


class _Imported:
    """A :class:`CaseSpec` field stored as given (a class or ``"module:Class"``), read as
    the class, imported on the first read and kept: :attr:`CaseSpec.problem`, and
    :attr:`CaseSpec.config` (a config read first when a config of that kind is loaded,
    so a case's package can register kinds whose configs a run of another kind never
    imports). A config imported late is checked then, as :func:`register_case` checks
    one given as a class."""

    def __init__(self, field: str) -> None:
        self.field, self.slot = field, f"_{field}"

    def __get__(self, spec: CaseSpec | None, owner: Any = None) -> Any:
        if spec is None:  # the dataclass sees no default (and the class no attribute)
            raise AttributeError(self.field)
        value = spec.__dict__[self.slot]
        if isinstance(value, str):
            module, _, name = value.partition(":")
            value = getattr(importlib.import_module(module), name)
            if self.field == "config":
                _check_kind(spec.kind, value)
            spec.__dict__[self.slot] = value
        return value

    def __set__(self, spec: CaseSpec, value: Any) -> None:
        spec.__dict__[self.slot] = value


# after @dataclass: no default
CaseSpec.problem = _Imported("problem")  # type: ignore[assignment]
CaseSpec.config = _Imported("config")  # type: ignore[assignment]


def problem_at(ref: str) -> type[Problem]:
    """A case's Problem class named ``"module:Class"``, for :class:`CaseSpec`'s ``problem``:
    imported when the spec's ``problem`` is first read (its package need not import the
    model to register the case)."""
    return ref  # type: ignore[return-value]  # read through _Imported as the class


def config_at(ref: str) -> type[CaseConfig]:
    """A case's config model named ``"module:Class"``, for :class:`CaseSpec`'s ``config``:
    imported when the spec's ``config`` is first read (a config of that kind loaded, the
    kinds listed)."""
    return ref  # type: ignore[return-value]  # read through _Imported as the class


def _check_kind(kind: str, config: type[CaseConfig]) -> None:
    if config.model_fields["kind"].default != kind:
        raise ConfigError("camopt", "case", f"case '{kind}': its config model's kind "
                          f"default is {config.model_fields['kind'].default!r}")


_REGISTRY: dict[str, CaseSpec] = {}
_loaded = False


def register_case(spec: CaseSpec) -> CaseSpec:
    """Register ``spec`` under its kind; a different spec under a taken kind raises."""
    existing = _REGISTRY.get(spec.kind)
    if existing is not None and existing is not spec:
        raise ConfigError("camopt", "case", f"case kind '{spec.kind}' is registered twice")
    if not isinstance(spec.__dict__["_config"], str):  # else checked when imported
        _check_kind(spec.kind, spec.config)
    _REGISTRY[spec.kind] = spec
    return spec


def _load_entry_point(ep: EntryPoint) -> None:
    try:
        obj = ep.load()
    except Exception as exc:  # a broken plugin must not break camopt
        raise ConfigError("camopt", f"case plugin {ep.name}",
                          f"failed to load ({ep.value}): {exc}") from exc
    if isinstance(obj, CaseSpec):
        register_case(obj)


def _load() -> None:
    global _loaded
    if _loaded:
        return
    _loaded = True
    import pkgutil  # listing only: a look-up by name imports one module

    package = importlib.import_module("camopt.cases")
    for module in pkgutil.iter_modules(package.__path__, "camopt.cases."):
        if module.ispkg:  # one package per built-in case
            importlib.import_module(module.name)
    for ep in entry_points(group=ENTRY_POINT_GROUP):
        _load_entry_point(ep)


def _find(kind: str) -> CaseSpec | None:
    """The spec of ``kind`` (None: unknown), importing the package its one entry point
    names when it is not registered yet, else every case (:func:`_load`)."""
    return look_up(_REGISTRY, kind, ENTRY_POINT_GROUP, _loaded, _load_entry_point, _load)


def cases() -> dict[str, CaseSpec]:
    """All registered cases by kind (every case package imported)."""
    _load()
    return dict(sorted(_REGISTRY.items()))


def get_case(kind: str) -> CaseSpec:
    """The spec of ``kind`` (only its package imported); an unknown kind lists the known
    ones."""
    spec = _find(kind)
    if spec is None:
        known = cases()
        raise ConfigError("case", "kind", f"unknown case kind {kind!r}"
                          f"{did_you_mean(kind, known)}; known: "
                          f"{', '.join(known)}")
    return spec


def case_configs() -> Mapping[str, type[CaseConfig]]:
    """Case kinds to their config models (what the loader validates ``[case]`` with); a
    kind looked up imports its package only, listing the kinds imports every case."""
    def config(kind: str) -> type[CaseConfig] | None:
        spec = _find(kind)
        return None if spec is None else spec.config

    return OnDemand(config, lambda: {kind: spec.config for kind, spec in cases().items()})


def run_requirements(run: RunView, violated: list[str] | None = None
                     ) -> tuple[Requirement, ...]:
    """The case's requirements of this run's designs, then every constraint of the run
    (``violated``: the constraints a failing design breaks, named in the words)."""
    from camopt.core.runview import design_values

    spec = get_case(run.kind)
    names = set(design_values(run))
    reqs = tuple(spec.requirements(run.case, names)) if spec.requirements else ()
    broken = ", ".join(violated or [])
    return (*reqs, Requirement(
        "every constraint of the run", "feasible", flag=True,
        source="the run's config ([case] and solver)",
        failing=f"violates the run's constraints{f' ({broken})' if broken else ''}"))
