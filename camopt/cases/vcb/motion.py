"""The VCB closing and opening models' inputs and results: the dynamic parameters the
paper omits (:class:`MotionParameters`), the closing's events and curves, the opening's
events, and the switch to the compiled kernel (:func:`compiled`). The models themselves:
:mod:`camopt.cases.vcb.dynamics`."""

from __future__ import annotations

import os
from collections.abc import Callable
from dataclasses import dataclass, field, fields, replace
from functools import cached_property
from types import ModuleType

import numpy as np
from numpy.typing import NDArray


@dataclass(frozen=True)
class MotionParameters:
    """The dynamic parameters the paper omits (SI). Each is a float or an (n,) array, one
    per design or per parameter set.

    ``cam_kg_m2`` cam, shaft, spring crank and the closing springs' share, about O;
    ``follower_kg_m2`` follower BD, roller and the four-bar's input about B;
    ``rod_kg`` output link, arm and insulated rods as a mass moving with the rod travel s1;
    ``contacts_kg`` the three moving contacts, carried by the rod until they touch;
    ``release_offset_rad`` the charged spring crank's angle past its dead centre when the
    closing latch lets go; ``friction_nm`` a Coulomb friction torque referred to the cam
    shaft, against the cam's rotation while it drives the roller (N m);
    ``release_friction_nm`` the same in the free rotation from the release (None: the
    driven closing's ``friction_nm``; 0 for a model form with friction only in the
    driven closing); ``efficiency`` the share of the springs' work that drives (Eq 26's
    eps; None: the case's ``efficiency``; 1 for a form with Coulomb friction alone).
    ``spring_kg`` the closing springs' own mass moving with their free ends, effective
    (a uniform coil with one end fixed: a third of its mass), an inertia
    ``spring_kg`` (dL/dtheta)^2 on the cam from the release on; ``rod_damping_n_s_per_m``
    a viscous force on the rod (a dashpot or buffer), c ds1/dt against its motion (0:
    the rigid, Coulomb-only model; either non-zero runs the numpy path, not the kernel).
    The model forms (:mod:`camopt.cases.vcb.forms`) map their fitted vectors to these."""

    cam_kg_m2: NDArray | float
    follower_kg_m2: NDArray | float
    rod_kg: NDArray | float
    contacts_kg: NDArray | float
    release_offset_rad: NDArray | float
    friction_nm: NDArray | float = 0.0
    release_friction_nm: NDArray | float | None = None
    efficiency: NDArray | float | None = None
    spring_kg: NDArray | float = 0.0
    rod_damping_n_s_per_m: NDArray | float = 0.0

    def columns(self, n: int, efficiency: float) -> ParameterColumns:
        """The same parameters as (n, 1) columns (what the motions broadcast against);
        ``efficiency`` fills an unset ``efficiency`` (the case's eps)."""
        def col(v: NDArray | float) -> NDArray:
            return per_row(v, n)[:, None]
        resolved = replace(
            self, efficiency=efficiency if self.efficiency is None else self.efficiency,
            release_friction_nm=(self.friction_nm if self.release_friction_nm is None
                                 else self.release_friction_nm))
        return ParameterColumns(**{f.name: col(getattr(resolved, f.name))
                                   for f in fields(self)})

    def repeat(self, n: int) -> MotionParameters:
        """Each of k parameter sets repeated for n designs in a row: (k n,) arrays ordered
        set-major (set 0 for every design, then set 1, ...); unset fields stay unset, and
        a plain number (one value for every set) stays one."""
        changes = {}
        for name in _FIELDS:
            v = getattr(self, name)
            if v is not None and np.ndim(v) > 0:
                changes[name] = np.ravel(np.asarray(v, dtype=float)).repeat(n)
        return replace(self, **changes)


_FIELDS = tuple(f.name for f in fields(MotionParameters))


@dataclass(frozen=True)
class ParameterColumns:
    """:class:`MotionParameters` as (n, 1) columns, one row per design (SI), every field
    resolved."""

    cam_kg_m2: NDArray
    follower_kg_m2: NDArray
    rod_kg: NDArray
    contacts_kg: NDArray
    release_offset_rad: NDArray
    friction_nm: NDArray
    release_friction_nm: NDArray
    efficiency: NDArray
    spring_kg: NDArray
    rod_damping_n_s_per_m: NDArray


@dataclass(frozen=True)
class ClosingEvents:
    """The closing's events per design (n,), time from the release of the closing springs:
    ``cam_contact_time`` (s), ``touch_time`` (s), ``touch_velocity`` (m/s),
    ``closing_velocity_avg`` (m/s, over the last third of the contact stroke, Sec 2.1),
    ``closing_time`` (s, to theta_end; inf if stalled), ``final_kinetic`` (J, at
    theta_end), ``touch_loss`` (J), ``latched``, ``reach``, the fraction of theta_end
    the cam turns before its kinetic energy first reaches zero (1 if latched; 0 if it
    stops before the roller; below 0 if it never starts: minus how far it is from
    starting, :func:`~camopt.cases.vcb.rotation.start_shortfall`),
    ``release_torque_ratio``, eps T_s / T_f at the release crank angle (the cam starts iff
    it exceeds 1; inf without friction in the free rotation), and ``pickup_loss`` (J),
    the kinetic energy the plastic impact of the cam on the resting roller takes (1/2 J*
    omega^2 of the relative motion, what the contact stores at its peak; 0 if the cam
    never gets there). What a band member contributes
    (:func:`closing_events`)."""

    cam_contact_time: NDArray
    touch_time: NDArray
    touch_velocity: NDArray
    closing_velocity_avg: NDArray
    closing_time: NDArray
    final_kinetic: NDArray
    touch_loss: NDArray
    latched: NDArray
    reach: NDArray
    release_torque_ratio: NDArray
    pickup_loss: NDArray



@dataclass(frozen=True)
class ClosingCurves:
    """The closing's curves, arrays (n, m) on the graded cam-angle grid. ``theta_c`` cam
    angle from the cam meeting the roller (rad, (m,)); ``time`` (s, inf after a stall);
    ``omega`` cam speed (rad/s); ``rod`` and ``rod_velocity`` rod travel s1 (m) and its
    velocity (m/s); ``contact`` and ``contact_velocity`` the movable contact's travel and
    velocity (it stops at touch); ``cam_torque`` the torque the cam passes to the roller,
    eps T_s - T_f - J_cam omega domega/dtheta (N m, negative: the follower would lift
    off)."""

    theta_c: NDArray
    time: NDArray
    omega: NDArray
    rod: NDArray
    rod_velocity: NDArray
    contact: NDArray
    contact_velocity: NDArray
    cam_torque: NDArray


@dataclass(frozen=True)
class ClosingMotion(ClosingEvents):
    """The closing of each design: its :class:`ClosingEvents`, ``cam_torque_min`` (n,),
    the least torque the cam passes to the roller over the nodes it reaches (N m; inf if
    it reaches none), and the :class:`ClosingCurves`, computed on first use by
    ``curves`` (the search reads the events and the least torque alone: the compiled
    kernel gives them without the curves)."""

    cam_torque_min: NDArray
    curves: Callable[[], ClosingCurves] = field(repr=False, compare=False)

    @cached_property
    def _curves(self) -> ClosingCurves:
        return self.curves()

    @property
    def theta_c(self) -> NDArray:
        return self._curves.theta_c

    @property
    def time(self) -> NDArray:
        return self._curves.time

    @property
    def omega(self) -> NDArray:
        return self._curves.omega

    @property
    def rod(self) -> NDArray:
        return self._curves.rod

    @property
    def rod_velocity(self) -> NDArray:
        return self._curves.rod_velocity

    @property
    def contact(self) -> NDArray:
        return self._curves.contact

    @property
    def contact_velocity(self) -> NDArray:
        return self._curves.contact_velocity

    @property
    def cam_torque(self) -> NDArray:
        return self._curves.cam_torque


def per_row(v: NDArray | float, n: int) -> NDArray:
    """A number, or one value per row, as an (n,) array (a number repeated; n values kept;
    any other size refused as numpy's broadcast refuses it)."""
    a = np.ravel(np.asarray(v, dtype=float))
    if a.size == n:
        return a
    return np.full(n, a[0]) if a.size == 1 else np.broadcast_to(a, (n,))


def least_torque(curves: ClosingCurves) -> NDArray:
    """:attr:`ClosingMotion.cam_torque_min` from the curves: the least cam torque over the
    nodes with a finite time (before a stall), (n,)."""
    return np.min(np.where(np.isfinite(curves.time), curves.cam_torque, np.inf), axis=1)


@dataclass(frozen=True)
class OpeningMotion:
    """The opening of each design from the closed state at rest, (n,): contact separation
    (``departure_time``, s: the rod is back at the contact gap), the end of the opening
    (``open_time``, s: the rod at s1 = 0) and the average opening velocity over 3/4 of the
    contact stroke from departure (``opening_velocity_avg``, m/s, Sec 2.1)."""

    departure_time: NDArray
    open_time: NDArray
    opening_velocity_avg: NDArray


def compiled() -> ModuleType | None:
    """:mod:`camopt.cases.vcb.kernel` where numba is installed and ``CAMOPT_NUMBA`` is not
    ``0`` (imported here, at the first evaluation, never by a command that evaluates no
    VCB); else None: the numpy path, the reference, with no error."""
    if os.environ.get("CAMOPT_NUMBA", "1") == "0":
        return None
    try:
        from camopt.cases.vcb import kernel
    except ImportError:  # numba not installed
        return None
    return kernel

