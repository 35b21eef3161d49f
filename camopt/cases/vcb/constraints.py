"""The VCB problem's constraints as one table: each constraint's name, when a config asks
for it and its normalised value g (<= 0 met), read from the quantities of one evaluation
(:class:`Terms`). :class:`~camopt.cases.vcb.problem.VcbProblem` takes the rows its config
asks for, in this order (the archive's ``constraints``)."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from functools import cached_property

import numpy as np

from camopt.cases.vcb.band import MotionBand
from camopt.cases.vcb.config import VcbConfig
from camopt.cases.vcb.dynamics import ClosingMotion
from camopt.cases.vcb.model import ForceBalance, Kinematics, VcbModel, unassembled
from camopt.mechanics import Floats, cam, fourbar, hertz
from camopt.units import DEG, GPA, MM, MPA


@dataclass
class Terms:
    """What the constraints read for n designs: the config, model, kinematics, force
    balance, linkage (n, 5), the exact largest follower swing ``phi_top`` (deg, (n,)), the
    peak contact shear ``tau_max`` (Pa), and where the dynamics ran the nominal closing
    ``motion`` and its ``band``. Quantities only some constraints read are computed on
    first use."""

    config: VcbConfig
    model: VcbModel
    kin: Kinematics
    bal: ForceBalance
    link: Floats
    phi_top: Floats
    tau_max: Floats
    motion: ClosingMotion | None
    band: MotionBand | None
    setting: Floats | None = None
    """The longest nut travel the factory setting needs under any of the form's sets (m,
    (n,); +inf: none reaches the velocity), where the run sets its breakers
    (:meth:`VcbProblem.as_set`)."""
    setting_velocity: Floats | None = None
    """The velocity each breaker is set to (m/s, (n,)), with :attr:`setting`."""

    @property
    def travel(self) -> Floats:
        """Rod travel opened to closed (m), (n,)."""
        return self.kin.s1[:, -1]

    @property
    def spread(self) -> MotionBand:
        """The band (the dynamic constraints exist only where the motion was computed)."""
        assert self.band is not None
        return self.band

    @property
    def velocity_limits(self) -> tuple[float, float]:
        assert self.config.closing_velocity_m_s is not None
        return self.config.closing_velocity_m_s

    @cached_property
    def cam_torque_min(self) -> Floats:
        """Least torque the cam passes to the roller over the part of the stroke it
        reaches (N m), (n,)."""
        assert self.motion is not None
        return self.motion.cam_torque_min

    @cached_property
    def lift_off_ratio(self) -> Floats:
        """:attr:`cam_torque_min` as a share of the closing springs' mean driving torque
        over the stroke (driving work / stroke angle), (n,): 0 is the lift-off limit."""
        return self.cam_torque_min * self.model.theta_c[-1] / self.bal.driving

    @cached_property
    def pickup_tau(self) -> Floats:
        """Largest shear stress beneath the cam-roller contact at the pick-up impact (Pa),
        (n,): the band's greatest impact loss stored elastically in the Hertz line contact
        of the profile's radius where the cam meets the roller (theta_c = 0) and the roller
        (:func:`camopt.mechanics.hertz.line_impact_force`), Eq 31 at that force. The
        contact is the only compliance counted (shafts and arms are softer and spread the
        impact): an upper estimate of the peak load, not a contact simulation."""
        c, m, f = self.config, self.model, self.kin.follower
        first = cam.Follower(f.theta_c[:, :1], f.xi, f.angle[:, :1], f.dphi[:, :1],
                             f.ddphi[:, :1], f.cos_a[:, :1], f.sin_a[:, :1])
        rho = cam.curvature_radius(m.l2, m.l6, first, m.rf)[:, 0]
        e_eq = hertz.equivalent_modulus(c.cam_modulus_gpa * GPA, c.poisson,
                                        c.cam_modulus_gpa * GPA, c.poisson)
        length = c.contact_length_mm * MM
        force = hertz.line_impact_force(self.spread.high["pickup_loss"], rho, m.rf, length,
                                        e_eq)
        return hertz.line_contact(force, rho, m.rf, length, e_eq)[2]

    @cached_property
    def psi_max(self) -> Floats:
        """Largest pressure angle along the stroke (deg), (n,)."""
        m = self.model
        return np.max(np.abs(cam.pressure_angle(m.l2, m.l6, self.kin.follower)), axis=1) / DEG


@dataclass(frozen=True)
class Constraint:
    """One row of the table: ``name``, whether a config asks for it, and g (n,)."""

    name: str
    applies: Callable[[VcbConfig], bool]
    g: Callable[[Terms], Floats]


def _latch(q: Terms) -> Floats:
    """Continuous across the limit: the kinetic energy left (share of the driving work)
    when the cam latches, the share of the stroke it misses when it stalls; the worst
    parameter set of the band."""
    c, band, driving = q.config, q.spread, q.bal.driving
    return np.where(band.latched, c.latch_energy_min_j - band.kinetic_low,
                    c.latch_energy_min_j + driving * (1 - band.reach_low)) / driving


def _setting(q: Terms) -> Floats:
    """The factory setting's constraint: the longest nut travel any of the form's sets
    needs within the nut's reach, and the set breaker's velocity under every set (as
    computed for the verdict) within :data:`SETTING_MISS` of the setting (a stall or kink
    the secant's extrapolation missed)."""
    assert q.setting is not None and q.setting_velocity is not None
    reach = np.abs(q.setting) / (q.config.preload_setting_range_mm * MM) - 1
    band = q.spread  # every set of the form, each at its own travel
    with np.errstate(invalid="ignore"):
        off = np.maximum(np.abs(band.velocity_low / q.setting_velocity - 1),
                         np.abs(band.velocity_high / q.setting_velocity - 1))
        miss = off / SETTING_MISS - 1
    return np.maximum(reach, np.where(np.isnan(miss), np.inf, miss))


SETTING_MISS = 0.01
"""How far a set breaker's velocity may lie from its setting (share): beyond, the setting
failed (the secant's step leaves < 1e-3 m/s where the velocity is smooth in the nut's
travel)."""


def _always(_: VcbConfig) -> bool:
    return True


CONSTRAINTS = (
    Constraint("phi_max_low", _always, lambda q: 1 - q.phi_top / q.config.phi_max_deg[0]),
    Constraint("phi_max_high", _always, lambda q: q.phi_top / q.config.phi_max_deg[1] - 1),
    Constraint("monotonic", _always, lambda q: -np.min(q.kin.dphi, axis=1)),
    Constraint("assembly", _always, lambda q: unassembled(q.kin.cos4, q.kin.ds1)),
    # normalised by the travel itself, as the other limits are by their bound (a scale of
    # the tolerance made far-off designs' violations dwarf the others)
    Constraint("rod_travel", _always,
               lambda q: (np.abs(q.travel / MM - q.config.rod_travel_mm)
                          - q.config.rod_travel_tolerance_mm) / q.config.rod_travel_mm),
    Constraint("grashof", lambda c: c.step == "fourbar",  # Eq 43
               lambda q: -fourbar.grashof_margin(q.link[:, 0], q.model.l2, q.link[:, 1],
                                                 q.link[:, 2]) / q.model.l2),
    Constraint("shear_yield", lambda c: c.stress_constraint,  # Eq 31
               lambda q: q.tau_max / (q.config.shear_yield_mpa * MPA) - 1),
    # the whole band of closing velocities inside the requirement
    Constraint("closing_velocity_low", lambda c: c.closing_velocity_m_s is not None,
               lambda q: 1 - q.spread.velocity_low / q.velocity_limits[0]),
    Constraint("closing_velocity_high", lambda c: c.closing_velocity_m_s is not None,
               lambda q: q.spread.velocity_high / q.velocity_limits[1] - 1),
    Constraint("latch", lambda c: c.require_latch, _latch),
    # what the prop and stop must absorb: the band's greatest energy left at the latch
    Constraint("latch_energy_high", lambda c: c.require_latch,
               lambda q: q.spread.kinetic_high / q.config.latch_energy_max_j - 1),
    # the cam's blow on the resting roller at the pick-up, in every set of the band, within
    # the contact's shear yield (Eq 31 at the impact's peak force)
    Constraint("pickup_impact", lambda c: c.require_latch,
               lambda q: q.pickup_tau / (q.config.shear_yield_mpa * MPA) - 1),
    # the cam must start in every set of the band, with the assumed margin on the
    # springs' torque against the friction at the release (a latch needs a release)
    Constraint("release_torque", lambda c: c.require_latch,
               lambda q: 1 - q.spread.release_ratio_low / q.config.release_torque_margin_min),
    # the least torque the cam passes on, as a share of the mean driving torque, at least
    # lift_off_fraction_min (positive g: the follower comes near to lifting off)
    Constraint("lift_off", lambda c: c.forbid_lift_off,
               lambda q: q.config.lift_off_fraction_min - q.lift_off_ratio),
    # the factory setting within the nut's reach
    Constraint("preload_setting", lambda c: c.velocity_setting_bounds_m_s is not None,
               _setting),
    Constraint("pressure_angle", lambda c: c.pressure_angle_max_deg is not None,
               lambda q: q.psi_max / (q.config.pressure_angle_max_deg or np.inf) - 1),
)
"""Every VCB constraint, in the archive's order."""
