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

from camopt.cases.vcb.config import VcbIdentifyConfig
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
            bal = m.balance(kin, m.closing_torque(np.tile(kc, (n, 1))), loads)
            out[label] = bal
        assert travel is not None
        r_travel = (travel[:, 0] - c.rod_travel_target_mm * MM) / (c.rod_travel_tolerance_mm * MM)
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
