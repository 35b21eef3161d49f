"""Opening and closing dynamics of the VCB mechanism, from the closed state as in ADAMS.

Kang, Huang & Yang (2023) simulate the vendor design in ADAMS (Sec 3.2, Table 4, Figs 23-25)
from the closed state: at t = 0 the hook lets go and the opening, contact and closing springs
release together; the contacts separate at 3.2 ms, the opening ends at 7 ms, the freely
turning cam meets the roller at 13.1 ms, the contacts collide at 27.8 ms and the simulation
ends, closed, at 45 ms; the average opening velocity is 2.5 m/s and the average closing
velocity 1.71 m/s (Sec 2.1: over the last third of the contact stroke; opening over 3/4
of it from departure). This module reproduces that sequence with one generalised
coordinate per phase:

* **closing spring release** (Sec 2.2 Step 8): the charged crank is held ``release_offset``
  past its dead centre (the crank pointing at the springs' fixed end G), where the springs'
  torque is small; the cam turns freely, inertia J_cam, until it meets the roller at
  theta_c = 0 (crank angle QOX + theta0). The time to get away from near the dead centre
  grows as the offset shrinks (logarithmically), which is what sets the 13.1 ms.
* **cam drives roller** (cam angle theta_c): kinetic energy 1/2 J(theta) omega^2 with

      J(theta) = J_cam + J_f phi'(theta)^2 + (m_rod + m_c) s1'(theta)^2   before the touch
      J(theta) = J_cam + J_f phi'(theta)^2 + m_rod s1'(theta)^2           after it

  J_f the follower and four-bar input about B (turning with the follower swing phi,
  Eq 6), m_rod the output link, arm and insulated rods as a mass at the rod, m_c the three
  moving contacts. The follower's share J_f phi'^2 shrinks along the stroke as phi'
  does (the cubic's rate falls from a1 toward 0), so the early motion is heavier than a
  constant lumped mass makes it. The work-energy equation gives omega(theta) without an
  ODE:

      1/2 J omega^2 = KE_0 + eps (E_cs(0) - E_cs(theta)) - V_r(s1(theta)) - impact losses

  E_cs the closing springs' energy, V_r the resistant potential (opening and contact
  springs, free-contact force: :class:`camopt.cases.vcb.model.Loads`), eps the paper's
  mechanical efficiency (Eq 26) as the friction loss on the driving springs' work. Events
  are plastic impacts (Carnot): the cam meets the roller at rest (generalised momentum
  kept, J_cam omega- = J(0) omega+), and the contacts stop on the fixed ones at s1 = gap
  (their kinetic energy 1/2 m_c v^2 is lost, omega continuous). A design whose kinetic
  energy reaches zero first stalls and never latches (closing time infinite).
* **opening** (follower angle phi from the closed to the opened state): the contact and
  opening springs drive the linkage back, eps of their work, with
  J(phi) = J_f + m_rod (ds1/dphi)^2; the contacts stay closed until the rod is back at the
  gap (separation), a plastic impact picks them up and the opening spring carries all to
  s1 = 0 (opening complete).

Time follows as t = integral d(coordinate) / rate on grids graded toward the states of rest.
The parameters are not printed in the paper; they are identified by least squares on every
ADAMS datum (``configs/vcb_identify_dynamics.toml``, :mod:`camopt.cases.vcb.identify`,
``docs/assumptions.md``). A scipy ODE integration of Lagrange's equation is the cross-check
in ``tests/cases/test_vcb_dynamics.py``. Own equations rather than a multibody library: the
mechanism is one degree of freedom in every phase, so the work-energy form is exact,
vectorises over a population and needs no time stepping (``docs/design.md``).

Modules: :mod:`~camopt.cases.vcb.motion` (parameters and results),
:mod:`~camopt.cases.vcb.locate` (grids and event location),
:mod:`~camopt.cases.vcb.rotation` (the free rotation), :mod:`~camopt.cases.vcb.closing`
(the driven closing in numpy, the reference), :mod:`~camopt.cases.vcb.opening`, and
:mod:`~camopt.cases.vcb.kernel` (the closing compiled); this one holds the entry points.
"""

from __future__ import annotations

import functools
from types import ModuleType

import numpy as np
from numpy.typing import NDArray

from camopt.cases.vcb.closing import (
    DAMPING_PASSES,
    ClosingState,
    closing_inputs,
    closing_state,
    curves_of,
    events_of,
    motion_of,
)
from camopt.cases.vcb.locate import (
    BISECTIONS,
    HERMITE_POINTS,
    _crossing,
    _cumulative_time,
    first_zero,
    graded_grid,
)
from camopt.cases.vcb.model import Loads, VcbModel
from camopt.cases.vcb.motion import (
    ClosingCurves,
    ClosingEvents,
    ClosingMotion,
    MotionParameters,
    OpeningMotion,
    ParameterColumns,
    compiled,
    least_torque,
    per_row,
)
from camopt.cases.vcb.opening import opening_motion
from camopt.cases.vcb.rotation import (
    free_rotation,
    free_steps,
    release_angle,
    release_torque_ratio,
    rotation_of,
    start_shortfall,
)

__all__ = [
    "BISECTIONS", "DAMPING_PASSES", "HERMITE_POINTS", "ClosingCurves", "ClosingEvents",
    "ClosingMotion", "ClosingState", "MotionParameters", "OpeningMotion", "ParameterColumns",
    "_crossing", "_cumulative_time", "closing_events", "closing_inputs", "closing_motion",
    "closing_state", "compiled", "compiled_events", "curves_of", "events_of", "first_zero",
    "free_rotation", "free_steps", "graded_grid", "least_torque", "motion_of", "opening_motion",
    "release_torque_ratio", "rotation_of",
]


def closing_motion(model: VcbModel, A: NDArray, kc: NDArray, link: NDArray,
                   rod_offset: NDArray | float, loads: Loads, params: MotionParameters,
                   steps: int, pre: NDArray | None = None) -> ClosingMotion:
    """Closing of n designs from the release of the closing springs: the events, the least
    cam torque and the curves. Through the compiled kernel where :func:`compiled` gives
    it (the events and the least torque; the curves from :func:`closing_state` when first
    read), else :func:`closing_state` read by :func:`motion_of`."""
    def state() -> ClosingState:
        return closing_state(model, A, kc, link, rod_offset, loads, params, steps, pre=pre)
    kernel = compiled()
    if kernel is None or _extra(params):
        return motion_of(state())
    events, low = _compiled(kernel, model, A, kc, link, rod_offset, loads,
                            params, steps, 1, pre, torque_min=True)
    return ClosingMotion(**vars(events), cam_torque_min=low,
                         curves=lambda: curves_of(state()))


def _extra(params: MotionParameters) -> bool:
    """Whether the parameters hold a term the kernel has not (the springs' own mass, a
    rod dashpot): those take the numpy path."""
    return any(bool(v) if isinstance(v, float | int) else bool(np.any(v))
               for v in (params.spring_kg, params.rod_damping_n_s_per_m))


def closing_events(model: VcbModel, A: NDArray, kc: NDArray, link: NDArray,
                   rod_offset: NDArray | float, loads: Loads, params: MotionParameters,
                   steps: int, sets: int = 1, pre: NDArray | None = None) -> ClosingEvents:
    """The events of :func:`closing_motion` alone for ``sets`` parameter sets per design:
    sets x n rows (``pre`` as :func:`closing_state`'s). Compiled
    (:mod:`camopt.cases.vcb.kernel`, the same arithmetic in one loop per row) where numba
    is installed and ``CAMOPT_NUMBA`` is not ``0``; else, and as the reference,
    :func:`closing_state` then :func:`events_of`."""
    kernel = compiled()
    if kernel is not None and not _extra(params):
        return compiled_events(kernel, model, A, kc, link, rod_offset, loads,
                               params, steps, sets, pre)
    return events_of(closing_state(model, A, kc, link, rod_offset, loads, params, steps,
                                   sets, pre))


def compiled_events(kernel: ModuleType, model: VcbModel, A: NDArray, kc: NDArray,
                    link: NDArray, rod_offset: NDArray | float, loads: Loads,
                    params: MotionParameters, steps: int, sets: int = 1,
                    pre: NDArray | None = None) -> ClosingEvents:
    """:func:`closing_events` through the compiled ``kernel``
    (:func:`camopt.cases.vcb.kernel.closing_rows`)."""
    return _compiled(kernel, model, A, kc, link, rod_offset, loads, params, steps, sets,
                     pre)[0]


def _compiled(kernel: ModuleType, model: VcbModel, A: NDArray, kc: NDArray, link: NDArray,
              rod_offset: NDArray | float, loads: Loads, params: MotionParameters,
              steps: int, sets: int, pre: NDArray | None, torque_min: bool = False
              ) -> tuple[ClosingEvents, NDArray]:
    """The events through ``kernel.closing_rows`` (the geometry once per design, the free
    rotation, the pick-up impact and the driven closing per row, in one call), and the
    least cam torque per row where ``torque_min`` (else nan). The inputs go in as they
    are: one value per design (``nd`` rows) or per row (``sets`` x nd), or one number."""
    nd = len(A)
    n = nd * sets
    theta, dtheta_du, u, weights = _grids(float(model.theta_c[-1]), steps)
    table = _table((params.cam_kg_m2, params.follower_kg_m2, params.rod_kg,
                    params.contacts_kg, params.friction_nm,
                    model.c.efficiency if params.efficiency is None else params.efficiency,
                    params.friction_nm if params.release_friction_nm is None
                    else params.release_friction_nm, params.release_offset_rad), n)
    loads_table = _table((loads.opening_k, loads.opening_arm, loads.opening_stretch_open,
                          loads.wipe_k, loads.wipe_preload, loads.free_contact), nd)
    pre_rows = _table(model.precompressions(pre), nd).T
    pre_rows = np.ascontiguousarray(pre_rows)
    kc = np.ascontiguousarray(kc, dtype=float)
    geometry = _geometry(kernel, model, steps, A, link, per_row(rod_offset, nd), kc, pre_rows,
                         loads_table, float(loads.gap))
    out = np.empty((12, n))
    kernel.closing_rows(theta, dtheta_du, 1.0 / steps, geometry, kc, pre_rows, loads_table,
                        float(loads.gap), table, model.release_crank, u, weights, torque_min,
                        out)
    shortfall = start_shortfall(release_angle(model, table[7]), out[10], float(theta[-1]))
    return ClosingEvents(
        cam_contact_time=out[0], touch_time=out[1], touch_velocity=out[2],
        closing_velocity_avg=out[3], closing_time=out[4], final_kinetic=out[5],
        touch_loss=out[6], latched=out[7] > 0, reach=out[8] - shortfall,
        release_torque_ratio=out[10],
        pickup_loss=out[11]), out[9]


_LAST: dict[tuple[object, ...], NDArray] = {}
"""The last geometry :func:`_geometry` computed, by its inputs, until it is read."""
KEPT_BYTES = 32 * 2**20
"""The largest geometry kept for the next call (a population of ~1,400 designs on 401
nodes; a robust search's row chunks are 512)."""


def _geometry(kernel: ModuleType, model: VcbModel, steps: int, A: NDArray, link: NDArray,
              rod_offset: NDArray, kc: NDArray, pre: NDArray, loads: NDArray, gap: float
              ) -> NDArray:
    """``kernel.closing_geometry`` of nd designs on the graded grid of ``steps``, (7, nd,
    m). The last result is kept by its inputs' bytes until it is read once: the nominal
    closing and its band evaluate the same designs one after the other, and the second
    reads the first's."""
    A = np.ascontiguousarray(A, dtype=float)
    link = np.ascontiguousarray(link, dtype=float)
    key = (model, steps, gap, A.shape, *(a.tobytes() for a in (A, link, rod_offset, kc, pre,
                                                                loads)))
    if key in _LAST:
        return _LAST.pop(key)  # read once: nothing held between evaluations
    theta, extension, spring_rate = model.graded_springs(steps)
    out = np.empty((7, len(A), theta.size))
    kernel.closing_geometry(theta, A, link, rod_offset, kc, pre, extension, spring_rate, loads,
                            gap, model.xi, model.l2, model.theta_bo, out)
    _LAST.clear()
    if out.nbytes <= KEPT_BYTES:
        _LAST[key] = out
    return out


def _table(values: tuple[NDArray | float, ...], n: int) -> NDArray:
    """Numbers, (n,) arrays or (n, 1) columns as the rows of a (len(values), n) table."""
    out = np.empty((len(values), n))
    for i, v in enumerate(values):
        out[i] = v if isinstance(v, float) else np.ravel(v)
    return out


@functools.lru_cache(maxsize=8)
def _grids(end: float, steps: int) -> tuple[NDArray, NDArray, NDArray, NDArray]:
    """The driven closing's graded grid and dtheta/du (:func:`graded_grid`), and the free
    rotation's u grid and Simpson weights (:func:`free_steps`, made even), per stroke and
    step count (read only)."""
    theta, dtheta_du = graded_grid(end, steps)
    free = free_steps(steps)
    free += free % 2
    u = np.linspace(0.0, 1.0, free + 1)
    weights = np.ones(free + 1)
    weights[1:-1:2], weights[2:-1:2] = 4.0, 2.0
    return theta, dtheta_du, u, weights
