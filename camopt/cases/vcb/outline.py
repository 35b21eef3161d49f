"""The VCB cam's full-turn outline for the workshop (``camopt export --format dxf``): the
run's best cam law closed over the turn (:mod:`camopt.mechanics.cam_outline`)."""

from __future__ import annotations

import numpy as np

from camopt.cases.vcb.config import VcbConfig
from camopt.cases.vcb.model import VcbModel
from camopt.core.runview import RunView
from camopt.mechanics.cam_outline import CamOutline, closed_outline


def outline(run: RunView, step: float | None = None) -> CamOutline | None:
    """The closed outline of the run's best cam in SI (None when the archive lacks the
    law's coefficients a0.. or they are not finite). The geometry is the case's own
    model (l2, l6, xi, rf and the actuated grid), so the rise is the archived profile;
    the closure's convex radius is held to the no-undercut requirement's rf_mm (Sec 2.3),
    its pressure angle to the rise's peak. ``step`` (rad): the sampling; None: the
    case's grid."""
    metrics = run.best.metrics
    a = [metrics.get(f"a{k}") for k in range(6)]
    law = np.array([v for v in a if isinstance(v, (int, float))], dtype=float)
    if law.size < 2 or not np.all(np.isfinite(law)):
        return None
    model = VcbModel(VcbConfig.model_validate(run.case))
    return closed_outline(law, float(model.theta_c[-1]), model.c.positions, model.xi,
                          model.l2, model.l6, model.rf, model.rf, step)
