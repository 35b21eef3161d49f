"""Identification of the VCB parameters the paper omits, from the numbers it reports.

Unknowns: the rod arm's angle on the output link, the opening spring's arm ratio
r7/r6 and the interrupters' free-contact force. Evidence (Kang 2023): rod travel
18 mm (Sec 3.2), the vendor design's objective 1.75e3 and the Table 6 optimum's
near-zero objective (Table 6). Least squares of the normalised residuals, solved
by any of the project's generic solvers; vectorised over candidate parameters.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from camopt.cases.vcb.config import VcbDynamicsIdentifyConfig, VcbIdentifyConfig
from camopt.cases.vcb.dynamics import Inertia, closing_motion, opening_motion
from camopt.cases.vcb.model import DEG, MM, VcbModel
from camopt.problem import Evaluation, Problem, Variable


class VcbIdentification(Problem):
    """Fit (rod offset, opening arm ratio, free-contact force) to the paper's evidence."""

    objective_name = "misfit"
    constraint_names = ()

    def __init__(self, config: VcbIdentifyConfig) -> None:
        self.config = c = config
        self.model = m = VcbModel(config)
        b = c.rod_offset_bounds_deg, c.opening_arm_bounds, c.free_contact_bounds_n
        self.variables = (
            Variable("rod_arm_offset_deg", b[0].lower * DEG, b[0].upper * DEG, 1 / DEG),
            Variable("opening_arm_ratio", b[1].lower, b[1].upper),
            Variable("free_contact_force_n", b[2].lower, b[2].upper),
        )
        d = c.paper_optimum
        self.A = np.array([m.vendor_a, [m.phi0(), d.a1, d.a2, d.a3]])
        self.kc = np.array([[c.kc1_n_per_mm, c.kc2_n_per_mm],
                            [d.kc1_n_per_mm, d.kc2_n_per_mm]]) * 1e3

    def evaluate(self, X: NDArray) -> Evaluation:
        """Squared normalised misfit of (rod travel, vendor surplus, optimum surplus) to
        the paper's evidence, with each residual and work as extras; no constraints."""
        c, m = self.config, self.model
        X = np.atleast_2d(np.asarray(X, dtype=float))
        n = len(X)
        offset, arm, free = (X[:, i : i + 1] for i in range(3))
        link = np.tile(m.vendor_link, (n, 1))
        out = {}
        travel = None
        for label, A, kc in zip(("vendor", "optimum"), self.A, self.kc):
            kin = m.kinematics(np.tile(A, (n, 1)), link, offset)
            if travel is None:
                travel = kin.s1[:, -1:]
            loads = m.loads(travel, arm, free)
            kcs = np.tile(kc, (n, 1))
            bal = m.balance(kin, kcs, m.closing_torque(kcs), loads)
            out[label] = bal
        assert travel is not None
        r_travel = (travel[:, 0] - c.rod_travel_mm * MM) / (c.rod_travel_tolerance_mm * MM)
        r_vendor = ((out["vendor"].surplus - c.vendor_surplus_target_j)
                    / out["vendor"].driving)
        r_optimum = ((out["optimum"].surplus - c.optimum_surplus_target_j)
                     / out["optimum"].driving)
        f = r_travel**2 + r_vendor**2 + r_optimum**2
        extras = {
            "rod_travel_mm": travel[:, 0] / MM,
            "vendor_surplus_j": out["vendor"].surplus,
            "optimum_surplus_j": out["optimum"].surplus,
            "vendor_driving_work_j": out["vendor"].driving,
            "vendor_resistant_work_j": out["vendor"].resistant,
            "optimum_resistant_work_j": out["optimum"].resistant,
            "misfit_travel": r_travel, "misfit_vendor": r_vendor, "misfit_optimum": r_optimum,
        }
        return Evaluation(f=np.where(np.isfinite(f), f, np.inf), g=np.zeros((n, 0)),
                          extras=extras)


class VcbDynamicsIdentification(Problem):
    """Fit the lumped inertias (cam, rod side, moving contacts) to the vendor design's ADAMS
    results (Kang 2023 Sec 3.2): the average closing velocity 1.71 m/s, the average opening
    velocity 2.5 m/s and the contacts' separation 3.2 ms after the hook lets go. Three
    numbers, three unknowns; the other reported times (cam meets roller 13.1 ms, contacts
    meet 27.8 ms, closed 45 ms) are predictions, reported as extras for comparison."""

    objective_name = "misfit"
    constraint_names = ()

    def __init__(self, config: VcbDynamicsIdentifyConfig) -> None:
        self.config = c = config
        self.model = m = VcbModel(config)
        b = c.cam_inertia_bounds_kg_m2, c.rod_mass_bounds_kg, c.contacts_mass_bounds_kg
        self.variables = (
            Variable("cam_inertia_kg_m2", b[0].lower, b[0].upper),
            Variable("rod_mass_kg", b[1].lower, b[1].upper),
            Variable("contacts_mass_kg", b[2].lower, b[2].upper),
        )
        self.rod_offset = c.rod_arm_offset_deg * DEG
        self.A = m.vendor_a[None, :]
        self.kc = np.array([[c.kc1_n_per_mm, c.kc2_n_per_mm]]) * 1e3
        vendor = m.kinematics(self.A, m.vendor_link[None, :], self.rod_offset)
        self.travel = float(vendor.s1[0, -1])
        self.load = m.loads(self.travel, c.opening_arm_ratio, c.free_contact_force_n)

    def evaluate(self, X: NDArray) -> Evaluation:
        """Squared relative misfit of (closing velocity, opening velocity, departure time);
        every simulated time and velocity as extras."""
        c, m = self.config, self.model
        X = np.atleast_2d(np.asarray(X, dtype=float))
        n = len(X)
        inertia = Inertia(X[:, 0], X[:, 1], X[:, 2])
        closing = closing_motion(m, np.tile(self.A, (n, 1)), np.tile(self.kc, (n, 1)),
                                 np.tile(m.vendor_link, (n, 1)), self.rod_offset, self.load,
                                 inertia, c.dynamics_steps)
        opening = opening_motion(np.full(n, self.travel), self.load, inertia, c.efficiency)
        r_close = closing.closing_velocity_avg / c.closing_velocity_target_m_s - 1
        r_open = opening.opening_velocity_avg / c.opening_velocity_target_m_s - 1
        r_depart = opening.departure_time / (c.departure_time_target_ms * 1e-3) - 1
        f = r_close**2 + r_open**2 + r_depart**2
        extras = {
            "closing_velocity_avg_m_s": closing.closing_velocity_avg,
            "opening_velocity_avg_m_s": opening.opening_velocity_avg,
            "departure_time_ms": opening.departure_time * 1e3,
            "cam_contact_time_ms": closing.cam_contact_time * 1e3,
            "touch_after_cam_contact_ms": (closing.touch_time - closing.cam_contact_time) * 1e3,
            "closing_time_ms": closing.closing_time * 1e3,
            "latch_kinetic_energy_j": closing.final_kinetic,
        }
        return Evaluation(f=np.where(np.isfinite(f), f, np.inf), g=np.zeros((n, 0)),
                          extras=extras)
