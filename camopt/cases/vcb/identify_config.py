"""``[case]`` of the VCB identifications: the fit of the parameters the paper leaves out to
the results it reports (``vcb_identify``), and of the dynamics' parameters to the vendor
design's ADAMS data (``vcb_identify_dynamics``). Each is the design case's ``[case]`` with
the data it fits and the ranges it searches."""

from __future__ import annotations

from collections.abc import Mapping
from typing import ClassVar, Literal

from pydantic import Field

from camopt.cases.vcb.config import VCB_ROLES, CamDesign, ModelFormName, VcbConfig, roles_of
from camopt.config.models import Bounds, FieldRole, Positive


class VcbIdentifyConfig(VcbConfig):
    """Fit the VCB parameters the paper leaves out to the results it reports."""

    field_roles: ClassVar[Mapping[str, FieldRole]] = {
        **VCB_ROLES, **roles_of("measured data", """vendor_surplus_target_j
            optimum_surplus_target_j paper_optimum"""),
        **roles_of("solver setting", """rod_offset_bounds_deg opening_arm_bounds
            free_contact_bounds_n""")}
    kind: Literal["vcb_identify"] = "vcb_identify"  # type: ignore[assignment]
    vendor_surplus_target_j: float = Field(
        1.75, description="Table 6 vendor objective 1.75e3, read as N mm")
    optimum_surplus_target_j: float = Field(0.0, description="Table 6 optimum: 1.74e-7")
    paper_optimum: CamDesign = Field(
        CamDesign(a1=0.238432, a2=0.000226, a3=-0.011492, kc1_n_per_mm=9.315336,
                  kc2_n_per_mm=7.788183), description="Table 6 DE-gr design")
    rod_offset_bounds_deg: Bounds = Field(Bounds(lower=-15, upper=15),
                                          description="unknown (search range)")
    opening_arm_bounds: Bounds = Field(
        Bounds(lower=0.1, upper=1.85), description="r7/r6; above 1.86 the opening spring "
        "would be compressed in the opened state (search range)")
    free_contact_bounds_n: Bounds = Field(
        Bounds(lower=0, upper=1000), description="self-closing force of three interrupters; "
        "it helps closing, so not negative (search range)")


class VcbDynamicsIdentifyConfig(VcbConfig):
    """Fit the dynamics' parameters the paper leaves out to the vendor design's seven ADAMS data
    (Sec 3.2, Table 4)."""

    field_roles: ClassVar[Mapping[str, FieldRole]] = {
        **VCB_ROLES, **roles_of("measured data", """departure_time_target_ms
            open_time_target_ms opening_velocity_target_m_s cam_contact_time_target_ms
            touch_time_target_ms closing_velocity_target_m_s closed_by_ms
            velocity_reading_pct time_reading_ms"""),
        **roles_of("solver setting", """cam_inertia_bounds_kg_m2 rod_mass_bounds_kg
            contacts_mass_bounds_kg release_offset_bounds_deg cam_friction_bounds_nm
            efficiency_bounds model_form form_keep_ratio form_keep_pct band_samples
            band_seed""")}
    kind: Literal["vcb_identify_dynamics"] = "vcb_identify_dynamics"  # type: ignore[assignment]
    # the ADAMS data of the vendor design (Sec 3.2 and Table 4), times from the release
    departure_time_target_ms: Positive = Field(
        3.2, description="Sec 3.2: the contacts separate 3.2 ms after the hook lets go")
    open_time_target_ms: Positive = Field(
        7.0, description="Sec 3.2: the opening is complete at 7 ms")
    opening_velocity_target_m_s: Positive = Field(
        2.5, description="Sec 3.2: average opening velocity of the vendor design")
    cam_contact_time_target_ms: Positive = Field(
        13.1, description="Sec 3.2: the freely turning cam meets the roller at 13.1 ms")
    touch_time_target_ms: Positive = Field(
        27.8, description="Sec 3.2 and Table 4: the contacts collide at 27.8 ms")
    closing_velocity_target_m_s: Positive = Field(
        1.71, description="Sec 3.2: average closing velocity of the vendor design")
    closed_by_ms: Positive = Field(
        45.0, description="Sec 3.2 and Table 4: closed when the simulation ends at 45 ms "
        "(an upper bound on release_to_latch_ms, not an event)")
    velocity_reading_pct: Positive = Field(
        2.0, description="reading error of the reported velocities (band; assumed)")
    time_reading_ms: Positive = Field(
        0.5, description="reading error of the reported times (band; assumed)")
    cam_inertia_bounds_kg_m2: Bounds = Field(Bounds(lower=5e-4, upper=0.05),
                                             description="search range (physical)")
    rod_mass_bounds_kg: Bounds = Field(Bounds(lower=0.1, upper=30.0), description="search range")
    contacts_mass_bounds_kg: Bounds = Field(Bounds(lower=0.1, upper=15.0),
                                            description="search range")
    release_offset_bounds_deg: Bounds = Field(Bounds(lower=0.5, upper=23.0),
                                              description="search range (physical)")
    cam_friction_bounds_nm: Bounds = Field(Bounds(lower=0.0, upper=50.0),
                                           description="search range")
    efficiency_bounds: Bounds = Field(Bounds(lower=0.3, upper=1.0),
                                      description="search range of a fitted efficiency")
    model_form: ModelFormName = Field(
        "efficiency_coulomb", description="the losses the search fits (camopt/cases/vcb/"
        "forms.py); every form is fitted and reported after the run (camopt option)")
    form_keep_ratio: float = Field(
        1.5, ge=1.0, description="a form is kept (in every band) when its largest residual "
        "is at most this many times the best form's ... (assumed; docs/assumptions.md)")
    form_keep_pct: Positive = Field(
        10.0, description="... or at most this (%), whichever is larger (assumed)")
    band_samples: int = Field(2000, ge=10, le=100_000, description="draws per kept form "
                              "for the band of parameter sets (camopt option)")
    band_seed: int = Field(0, ge=0, description="seed of the band's draws (camopt option)")
