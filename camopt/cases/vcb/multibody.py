"""The VCB closing as a planar multibody model in Exudyn (docs/verify.md).

Bodies: the cam (about O, inertia J_cam), the follower BD with its roller (about B, J_f),
the output link LE with the arm EM (about E), the rod (a slider of mass m_rod on a vertical
guide, pinned to M through a horizontal slot: only M's height moves it) and the moving
contacts (a slider of mass m_c). Joints: revolute joints at O, B and E, the coupler DL a
massless distance constraint (or, with ``coupler_mass``, a bar with revolute joints at both
ends), the slot a prismatic joint. Forces: the two closing springs between G and the crank
point Q (their rates times the efficiency eps: the lumped model's friction on the springs'
work), a regularised Coulomb friction torque at O, and three unilateral compliant contacts:
the cam on the roller (penalty on the roller centre's penetration of the pitch curve, along
its normal), the contacts on their fixed counterparts at the gap, the rod's stop at the
opened position; the contact springs (preloaded) between the rod and the contacts, which
rest on a shoulder of the rod until they touch; the opening spring on the rod through its
lever ratio. Each contact's force is max(0, k g + c g'), g the penetration, c critical
damping (plastic impacts, as the lumped model's); the cam-roller pick-up's c may instead
follow from a restitution coefficient (beyond camopt's model, to see what it moves)."""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from numpy.typing import NDArray

from camopt.cases.vcb.mechanism import Mechanism
from camopt.cases.vcb.multibody_events import Events, Trace, events_of

exu: Any  # Exudyn's bundled stubs lack settings it has: the module is typed Any here
ii: Any
try:
    import exudyn as exu
    from exudyn import itemInterface as ii
except ImportError:  # the optional extra is not installed
    exu = ii = None

CONTACT_STIFFNESS = 1e9
"""Penalty stiffness of every contact (N/m): the cam on the roller, the moving on the fixed
contacts, the rod's stop, the contacts' shoulder on the rod. A steel line contact 10-20 mm
long is about this stiff; 1e9 keeps the cam's penetration below 5 um at 3 kN."""
STEP = 1e-5
"""Time step (s) of the implicit integrator (generalized-alpha, spectral radius 1: no
numerical damping): 7 steps per period (~70 us) of the stiffest oscillation, the cam's
inertia on the contact; halving it moves the judged quantities by < 0.03 %
(docs/verify.md)."""
BACK_TIME = 2e-3
"""How long (s) the cam may turn back (thrown back by an elastic pick-up) before the
simulation calls it stalled and stops."""
PRESSED_TIME = 2e-4
"""How long (s) the cam may turn back while the roller presses on it (an impact's few
periods of ~70 us) before it counts as stalled: the linkage driving the cam back."""
BACK_SPEED = 0.5
"""Cam speed (rad/s) below -BACK_SPEED counts as turning back (its friction reversed)."""
BACK_ANGLE = 1e-3
"""How far (rad) behind its release angle the cam may fall before it counts as stalled
(the release itself jitters by the solver's tolerance)."""
PITCH_POINTS = 4001
"""Points of the pitch curve polyline (the roller centre's path in the cam's frame)."""


def available() -> bool:
    """Whether the engine (the ``camopt[multibody]`` extra) is installed."""
    return exu is not None


def damping_ratio(restitution: float) -> float:
    """Damping ratio of a linear spring-damper contact that rebounds with ``restitution``
    (e = exp(-zeta pi / sqrt(1 - zeta^2))); 0 gives 1, critical damping, which with a
    force that cannot pull (max(0, ...)) does not rebound."""
    if restitution <= 0.0:
        return 1.0
    ln = math.log(restitution)
    return -ln / math.sqrt(math.pi**2 + ln * ln)


class _CamContact:
    """The cam-roller contact's geometry: the pitch curve in the cam's frame as a
    polyline, searched near the last contact point (the roller moves little per call)."""

    def __init__(self, mech: Mechanism) -> None:
        p = mech.pitch_curve(PITCH_POINTS)
        self.a, self.b = p[:-1], p[1:]
        seg = self.b - self.a
        self.length2 = np.einsum("ij,ij->i", seg, seg)
        self.seg = seg
        normal = np.stack([seg[:, 1], -seg[:, 0]], axis=1)
        # the outward normal: away from O
        mid = 0.5 * (self.a + self.b)
        normal *= np.sign(np.einsum("ij,ij->i", normal, mid))[:, None]
        self.normal = normal / np.sqrt(self.length2)[:, None]
        self.last = 0

    def penetration(self, d: NDArray) -> tuple[float, NDArray, NDArray]:
        """The roller centre ``d`` (cam frame)'s penetration of the pitch curve (m, > 0
        inside), the outward normal and the curve point there; penetration nan where d
        lies beyond either end of the curve (the cam's idle part: no contact)."""
        lo = max(self.last - 40, 0)
        hi = min(self.last + 40, len(self.a))
        for window in ((lo, hi), (0, len(self.a))):
            i0, i1 = window
            rel = d - self.a[i0:i1]
            t = np.einsum("ij,ij->i", rel, self.seg[i0:i1]) / self.length2[i0:i1]
            tc = np.clip(t, 0.0, 1.0)
            near = self.a[i0:i1] + tc[:, None] * self.seg[i0:i1]
            dist2 = np.einsum("ij,ij->i", d - near, d - near)
            i = int(np.argmin(dist2))
            if i0 < i + i0 < i1 - 1 or (i0, i1) == (0, len(self.a)):
                break
        k = i0 + i
        self.last = k
        if (k == 0 and t[i] < 0) or (k == len(self.a) - 1 and t[i] > 1):
            return math.nan, self.normal[k], near[i]
        n = self.normal[k]
        return float(np.dot(near[i] - d, n)), n, near[i]


def _rot(angle: float) -> NDArray:
    c, s = math.cos(angle), math.sin(angle)
    return np.array([[c, -s], [s, c]])


def simulate(mech: Mechanism, step: float = STEP, restitution: float = 0.0,
             stiffness: float = CONTACT_STIFFNESS, end_time: float = 0.2,
             contact_restitution: float = 0.0) -> Trace:
    """Simulate the closing from the release (the cam at rest at ``release_angle``, the
    linkage at rest against its stop) until the cam reaches the end of its travel, turns
    back, or ``end_time`` (s) passes; ``restitution`` of the cam-roller pick-up and
    ``contact_restitution`` of the moving contacts on the fixed ones (0: plastic)."""
    if exu is None:
        raise ImportError("exudyn")
    sc = exu.SystemContainer()
    mbs = sc.AddSystem()
    b = np.asarray(mech.pivot_b)
    d0 = mech.roller(mech.phi(np.asarray(0.0)))
    l0 = mech.coupler_point(d0)
    m0 = mech.rod_point(l0)
    e = mech.ground_e()
    tiny_inertia = 1e-7  # kg m^2: a body the lumped model gives no inertia (none of its
    # energy counts: 1e-7 against the cam's 5.8e-4 and the rod's ~1.6e-4 referred to it)
    ground = mbs.AddObject(ii.ObjectGround())
    ground_node = mbs.AddNode(ii.NodePointGround())
    ground_coord = mbs.AddMarker(ii.MarkerNodeCoordinate(nodeNumber=ground_node,
                                                         coordinate=0))

    def rigid(at: NDArray, mass: float, inertia: float, angle0: float = 0.0,
              ) -> tuple[int, int]:
        node = mbs.AddNode(ii.NodeRigidBody2D(referenceCoordinates=[at[0], at[1], 0.0],
                                              initialCoordinates=[0.0, 0.0, angle0]))
        body = mbs.AddObject(ii.ObjectRigidBody2D(mass=mass, inertia=inertia,
                                                  nodeNumber=node))
        return node, body

    def pin(body: int, local: NDArray, world: NDArray) -> None:
        m1 = mbs.AddMarker(ii.MarkerBodyPosition(bodyNumber=body,
                                                 localPosition=[local[0], local[1], 0.0]))
        m0g = mbs.AddMarker(ii.MarkerBodyPosition(bodyNumber=ground,
                                                  localPosition=[world[0], world[1], 0.0]))
        mbs.AddObject(ii.ObjectJointRevolute2D(markerNumbers=[m0g, m1]))

    # cam: its frame is the one at theta_c = 0; it starts at the release angle
    cam_node, cam = rigid(np.zeros(2), 1.0, mech.cam_inertia, mech.release_angle)
    pin(cam, np.zeros(2), np.zeros(2))
    fol_node, fol = rigid(b, 1.0, max(mech.follower_inertia, tiny_inertia))
    pin(fol, np.zeros(2), b)
    out_node, out = rigid(e, 1.0, tiny_inertia)
    pin(out, np.zeros(2), e)
    marker_d = mbs.AddMarker(ii.MarkerBodyPosition(bodyNumber=fol, localPosition=[
        *(d0 - b), 0.0]))
    marker_l = mbs.AddMarker(ii.MarkerBodyPosition(bodyNumber=out, localPosition=[
        *(l0 - e), 0.0]))
    if mech.coupler_mass > 0:  # a uniform bar D-L with revolute joints at both ends
        centre = 0.5 * (d0 + l0)
        _, bar = rigid(centre, mech.coupler_mass, mech.coupler_mass * mech.l3**2 / 12)
        for end, marker in ((d0, marker_d), (l0, marker_l)):
            mb = mbs.AddMarker(ii.MarkerBodyPosition(bodyNumber=bar, localPosition=[
                *(end - centre), 0.0]))
            mbs.AddObject(ii.ObjectJointRevolute2D(markerNumbers=[marker, mb]))
    else:
        mbs.AddObject(ii.ObjectConnectorDistance(markerNumbers=[marker_d, marker_l],
                                                 distance=mech.l3))
    # rod: a vertical slider at M's opened position, M in its horizontal slot
    rod_node, rod = rigid(m0, mech.rod_mass, tiny_inertia)
    for coordinate in (0, 2):
        mc = mbs.AddMarker(ii.MarkerNodeCoordinate(nodeNumber=rod_node, coordinate=coordinate))
        mbs.AddObject(ii.CoordinateConstraint(markerNumbers=[ground_coord, mc]))
    slot = mbs.AddMarker(ii.MarkerBodyRigid(bodyNumber=rod, localPosition=[0.0, 0.0, 0.0]))
    arm_end = mbs.AddMarker(ii.MarkerBodyRigid(bodyNumber=out, localPosition=[
        *(m0 - e), 0.0]))
    # Exudyn's prismatic 2D constraint is (p1 - p0) . normal, the normal given in marker
    # 1's frame: the rod's, which does not turn, so M and the rod share their height
    mbs.AddObject(ii.ObjectJointPrismatic2D(markerNumbers=[arm_end, slot],
                                            axisMarker0=[1.0, 0.0, 0.0],
                                            normalMarker1=[0.0, 1.0, 0.0],
                                            constrainRotation=False))
    # moving contacts: a vertical slider beside the rod
    con_node = mbs.AddNode(ii.NodePoint2D(referenceCoordinates=[m0[0], m0[1]]))
    mbs.AddObject(ii.ObjectMassPoint2D(mass=mech.contacts_mass, nodeNumber=con_node))
    mcx = mbs.AddMarker(ii.MarkerNodeCoordinate(nodeNumber=con_node, coordinate=0))
    mbs.AddObject(ii.CoordinateConstraint(markerNumbers=[ground_coord, mcx]))
    rod_y = mbs.AddMarker(ii.MarkerNodeCoordinate(nodeNumber=rod_node, coordinate=1))
    con_y = mbs.AddMarker(ii.MarkerNodeCoordinate(nodeNumber=con_node, coordinate=1))

    pickup_zeta = damping_ratio(restitution)  # the cam on the roller
    touch_zeta = damping_ratio(contact_restitution)  # the contacts; the rest plastic
    k = stiffness
    m_linkage = mech.rod_mass + mech.contacts_mass

    def unilateral(g: float, rate: float, mass: float, zeta: float = 1.0) -> float:
        """max(0, k g + c g') for penetration g > 0, else 0; c = 2 zeta sqrt(k mass)."""
        if not g > 0:
            return 0.0
        return max(0.0, k * g + 2 * zeta * math.sqrt(k * mass) * rate)

    # closing springs, G to Q: rates times eps, free length = opened length + compression
    g_point = np.asarray(mech.spring_g)
    q_local = mech.crank_l8 * np.array([math.cos(mech.crank_angle0),
                                        math.sin(mech.crank_angle0)])
    q_open = _rot(-mech.theta0) @ q_local
    length_open = float(np.hypot(*(g_point - q_open)))
    marker_q = mbs.AddMarker(ii.MarkerBodyPosition(bodyNumber=cam, localPosition=[
        *q_local, 0.0]))
    marker_g = mbs.AddMarker(ii.MarkerBodyPosition(bodyNumber=ground, localPosition=[
        *g_point, 0.0]))
    for rate, pre in zip(mech.spring_rates, mech.precompression):
        mbs.AddObject(ii.ObjectConnectorSpringDamper(
            markerNumbers=[marker_g, marker_q], stiffness=mech.efficiency * rate,
            referenceLength=length_open + pre))

    # rod: its stop at the opened position and the opening spring through its lever
    arm_k = mech.opening_arm * mech.opening_k

    def rod_force(mbs_: Any, t: float, item: int, s: float, v: float, *_: Any) -> float:
        force = arm_k * (mech.opening_stretch_open + mech.opening_arm * s)  # resists
        return force - unilateral(-s, -v, m_linkage)

    mbs.AddObject(ii.ObjectConnectorCoordinateSpringDamper(
        markerNumbers=[ground_coord, rod_y], springForceUserFunction=rod_force))

    # contact springs between the rod and the contacts; the contacts' shoulder on the rod
    def wipe_force(mbs_: Any, t: float, item: int, rel: float, v: float, *_: Any) -> float:
        # rel = contacts - rod travel: the springs are compressed by p - rel
        spring = -mech.wipe_k * (mech.wipe_preload - rel)  # pushes them apart
        return spring + unilateral(rel, v, mech.contacts_mass)

    mbs.AddObject(ii.ObjectConnectorCoordinateSpringDamper(
        markerNumbers=[rod_y, con_y], springForceUserFunction=wipe_force))

    # the fixed contacts at the gap; the free-contact force (vacuum) closes the contacts
    def fixed_force(mbs_: Any, t: float, item: int, c: float, v: float, *_: Any) -> float:
        return unilateral(c - mech.gap, v, mech.contacts_mass, touch_zeta) - mech.free_contact

    mbs.AddObject(ii.ObjectConnectorCoordinateSpringDamper(
        markerNumbers=[ground_coord, con_y], springForceUserFunction=fixed_force))

    # the cam on the roller, and the friction torque at O
    geometry = _CamContact(mech)
    d_local = d0 - b
    # the masses the pick-up meets along the contact normal: the cam's inertia on the
    # normal's arm about O, the linkage's (rod, contacts, follower) on the roller's swing
    # (l2 per rad of the follower: ds1/dphi = (ds1/dtheta) / phi'(0)); their reduced mass
    # sets the damping of the pick-up
    arm = abs(float(d0[0] * geometry.normal[0][1] - d0[1] * geometry.normal[0][0]))
    ds1_dphi = mech.rod_travel(1e-6) / 1e-6 / mech.law[1]
    m_linkage_roller = (m_linkage * (ds1_dphi / mech.l2) ** 2
                        + max(mech.follower_inertia, tiny_inertia) / mech.l2**2)
    m_pick = 1 / (arm**2 / mech.cam_inertia + 1 / m_linkage_roller)

    cache: dict[tuple[float, ...], tuple[float, NDArray, float]] = {}

    def roller_contact() -> tuple[float, NDArray, float]:
        """Normal force on the roller (N), its world direction and its torque on the cam
        (both loads ask at the same state: computed once)."""
        cam_q = mbs.GetNodeOutput(cam_node, exu.OutputVariableType.Coordinates)
        cam_v = mbs.GetNodeOutput(cam_node, exu.OutputVariableType.Coordinates_t)
        alpha = mbs.GetNodeOutput(fol_node, exu.OutputVariableType.Coordinates)[2]
        alpha_t = mbs.GetNodeOutput(fol_node, exu.OutputVariableType.Coordinates_t)[2]
        psi, omega = cam_q[2], cam_v[2]
        key = (psi, omega, alpha, alpha_t)
        if key in cache:
            return cache[key]
        if len(cache) > 64:
            cache.clear()
        arm = _rot(alpha) @ d_local
        d = b + arm
        v_d = alpha_t * np.array([-arm[1], arm[0]])
        back = _rot(-psi)
        g, n_cam, _ = geometry.penetration(back @ d)
        if not g > 0:
            cache[key] = (0.0, np.zeros(2), 0.0)
            return cache[key]
        n = _rot(psi) @ n_cam
        v_p = omega * np.array([-d[1], d[0]])  # the cam's point under the roller centre
        rate = float(np.dot(v_p - v_d, n))
        fn = unilateral(g, rate, m_pick, pickup_zeta)
        force = fn * n
        cache[key] = (fn, force, float(d[0] * force[1] - d[1] * force[0]))
        return cache[key]

    def roller_load(mbs_: Any, t: float, load: Any) -> list[float]:
        _, force, _ = roller_contact()
        return [float(force[0]), float(force[1]), 0.0]

    def cam_load(mbs_: Any, t: float, load: Any) -> list[float]:
        _, _, torque = roller_contact()
        psi = mbs.GetNodeOutput(cam_node, exu.OutputVariableType.Coordinates)[2]
        # Coulomb friction against the forward rotation of a closing; a cam an elastic
        # pick-up throws back (faster than BACK_SPEED: not the rest at the release,
        # where flipping it would chatter) is braked the other way; the simulation
        # stops should it keep turning back
        omega = mbs.GetNodeOutput(cam_node, exu.OutputVariableType.Coordinates_t)[2]
        friction = mech.release_friction if psi < 0 else mech.friction
        return [0.0, 0.0, -torque - (-friction if omega < -BACK_SPEED else friction)]

    mbs.AddLoad(ii.LoadForceVector(markerNumber=marker_d, loadVector=[0.0, 0.0, 0.0],
                                   loadVectorUserFunction=roller_load))
    cam_rigid = mbs.AddMarker(ii.MarkerBodyRigid(bodyNumber=cam, localPosition=[0.0, 0.0,
                                                                                 0.0]))
    mbs.AddLoad(ii.LoadTorqueVector(markerNumber=cam_rigid, loadVector=[0.0, 0.0, 0.0],
                                    loadVectorUserFunction=cam_load))

    rows: list[list[float]] = []
    moved = [False]  # whether the cam has turned forward (faster than BACK_SPEED)
    back_since = [math.inf, math.inf]  # when the cam began turning back, and doing so
    # against the roller (inf: it turns forward)

    def record(mbs_: Any, t: float) -> bool:
        q = [mbs.GetNodeOutput(n, exu.OutputVariableType.Coordinates) for n in
             (cam_node, fol_node, out_node, rod_node, con_node)]
        v = [mbs.GetNodeOutput(n, exu.OutputVariableType.Coordinates_t) for n in
             (cam_node, fol_node, out_node, rod_node, con_node)]
        fn, _, torque = roller_contact()
        kinetic = 0.5 * (mech.cam_inertia * v[0][2] ** 2
                         + max(mech.follower_inertia, tiny_inertia) * v[1][2] ** 2
                         + tiny_inertia * v[2][2] ** 2 + mech.rod_mass * v[3][1] ** 2
                         + mech.contacts_mass * v[4][1] ** 2)
        rows.append([mbs.systemData.GetTime(), q[0][2], v[0][2], q[3][1], v[3][1], q[4][1],
                     v[4][1], fn, torque, kinetic])
        psi, omega, now = q[0][2], v[0][2], mbs.systemData.GetTime()
        back_since[0] = min(back_since[0], now) if omega < 0 else math.inf
        back_since[1] = min(back_since[1], now) if omega < 0 and fn > 0 else math.inf
        # stalled: turning back before it ever turned forward (it does not release) or
        # once the contacts have touched (nothing throws the cam back then), back past
        # the release, turning back while the roller presses on it
        # for longer than an impact lasts, or at all for longer than a bounce lasts
        moved[0] = moved[0] or omega > BACK_SPEED
        stalled = ((omega < 0 and (q[4][1] >= mech.gap or not moved[0]))
                   or psi < mech.release_angle - BACK_ANGLE
                   or now - back_since[1] > PRESSED_TIME or now - back_since[0] > BACK_TIME)
        return not (psi >= mech.cam_end or stalled)

    mbs.SetPreStepUserFunction(record)
    mbs.Assemble()
    settings = exu.SimulationSettings()
    ti = settings.timeIntegration
    ti.numberOfSteps = int(round(end_time / step))
    ti.endTime = end_time
    ti.generalizedAlpha.spectralRadius = 1.0
    ti.newton.useModifiedNewton = True
    ti.computeLoadsJacobian = 2
    ti.verboseMode = 0
    settings.solution.file.write = False
    settings.linearSolver.solverType = exu.LinearSolverType.EXUdense
    settings.show.computationTime = False
    settings.show.statistics = False
    printing = exu.config.printToConsole
    exu.config.printToConsole = False  # its warnings would break a JSON report on stdout
    try:
        exu.SolveDynamic(mbs, settings, showHints=False)
    finally:
        exu.config.printToConsole = printing
    data = np.asarray(rows)
    return Trace(*(data[:, i] for i in range(10)))


def run(mech: Mechanism, step: float = STEP, restitution: float = 0.0,
        stiffness: float = CONTACT_STIFFNESS, contact_restitution: float = 0.0,
        ) -> tuple[Events, Trace]:
    """The simulated closing of ``mech`` and its events."""
    trace = simulate(mech, step, restitution, stiffness,
                     contact_restitution=contact_restitution)
    return events_of(mech, trace), trace
