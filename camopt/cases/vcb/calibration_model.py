"""The VCB closing a calibration simulates: designs (a follower law and spring rates), the
closing of every design under every parameter row of a model form, and the rod travel
sampled at a curve's times (:mod:`camopt.cases.vcb.calibrate` fits it to the curves)."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from types import ModuleType

import numpy as np

from camopt.cases.vcb.config import VcbConfig
from camopt.cases.vcb.dynamics import ClosingMotion
from camopt.cases.vcb.forms import ModelForm
from camopt.cases.vcb.model import Kinematics, Loads, VcbModel
from camopt.mechanics import Floats
from camopt.units import DEG


@dataclass(frozen=True)
class Design:
    """The design a curve (or a prediction) belongs to: follower-law coefficients ``a``
    (d + 1,) rad/rad^k, spring rates ``kc`` (2,) N/m, and a label."""

    label: str
    a: Floats
    kc: Floats


def closing(form: ModelForm, model: VcbModel, designs: Sequence[Design], P: Floats,
            steps: int) -> ClosingMotion:
    """The closing of every design under every parameter row of ``P`` (k, p) of
    ``form`` (:meth:`~camopt.cases.vcb.forms.ModelForm.closing`): k x n rows,
    parameter-major (row 0 for every design, then row 1, ...), the case's linkage and
    resisting loads."""
    P = np.atleast_2d(P)
    k, n = len(P), len(designs)
    degree = max(len(d.a) for d in designs)
    A = np.array([np.pad(d.a, (0, degree - len(d.a))) for d in designs])
    kc = np.array([d.kc for d in designs])
    link = np.tile(model.vendor_link, (k * n, 1))
    rod_offset = model.c.rod_arm_offset_deg * DEG
    return form.closing(model, np.tile(A, (k, 1)), np.tile(kc, (k, 1)), link, rod_offset,
                        _loads(model), np.repeat(P, n, axis=0),
                        model.c.follower_inertia_kg_m2, steps)


def travel(form: ModelForm, model: VcbModel, designs: Sequence[Design], P: Floats,
           steps: int) -> tuple[Floats, Floats]:
    """Time from the release (s) and rod travel (m) of each design under each parameter
    row of ``P`` (k, p): arrays (k, n, m) on the form's own grid, time increasing along m
    (inf after a stall)."""
    mo = closing(form, model, designs, P, steps)
    k, n = len(np.atleast_2d(P)), len(designs)
    return mo.time.reshape(k, n, -1), mo.rod.reshape(k, n, -1)


def velocity(form: ModelForm, model: VcbModel, designs: Sequence[Design], P: Floats,
             steps: int) -> tuple[Floats, Floats]:
    """The case's closing velocity (m/s) and the touch time from the release (s) of each
    design under each parameter row of ``P`` (k, p), (k, n) each."""
    mo = closing(form, model, designs, P, steps)
    k, n = len(np.atleast_2d(P)), len(designs)
    return mo.closing_velocity_avg.reshape(k, n), mo.touch_time.reshape(k, n)


class KinematicsMemo(VcbModel):
    """The case's model with its kinematics remembered by input (a calibration simulates
    the same few designs, tiled by as many parameter rows, hundreds of times: the
    kinematics depend on the designs alone; ~20 % of an evaluation). The arrays kept are
    read-only, so nothing downstream can change them in place."""

    SIZE = 16

    def __init__(self, config: VcbConfig) -> None:
        super().__init__(config)
        self._memo: dict[tuple[bytes, ...], Kinematics] = {}

    def kinematics(self, A: Floats, link: Floats, rod_offset: Floats | float,
                   theta_c: Floats | None = None, kernel: ModuleType | None = None
                   ) -> Kinematics:
        key = tuple(np.asarray(v, dtype=float).tobytes() + bytes(str(np.shape(v)), "ascii")
                    for v in (A, link, rod_offset, () if theta_c is None else theta_c))
        key += (b"numpy" if kernel is None else b"compiled",)  # one path's numbers each
        kin = self._memo.get(key)
        if kin is None:
            kin = super().kinematics(A, link, rod_offset, theta_c, kernel)
            for a in (kin.cos4, kin.sin4, kin.s1, kin.ds1, kin.follower.dphi):
                a.setflags(write=False)
            if len(self._memo) >= self.SIZE:
                self._memo.pop(next(iter(self._memo)))
            self._memo[key] = kin
        return kin


def _loads(model: VcbModel) -> Loads:
    """The case's resisting loads, with the rod travel of its reference design."""
    c = model.c
    kin = model.kinematics(model.vendor_a[None, :], model.vendor_link[None, :],
                           c.rod_arm_offset_deg * DEG)
    return model.loads(float(kin.s1[0, -1]), c.opening_arm_ratio, c.free_contact_force_n)


def sample_travel(time: Floats, rod: Floats, query: Floats) -> Floats:
    """Rod travel of each row at the query times (s from the release), linearly between
    the model's nodes, 0 before its first node, its last value after the last (the latch)
    or a stall: rows ``time``/``rod`` (r, m), ``query`` (r, q); one searchsorted for all
    rows (each row shifted past the previous one's span)."""
    r, m = time.shape
    never = ~np.isfinite(time[:, 0])  # the cam never leaves the release: no motion
    t = np.where(np.isfinite(time), time, np.nan)
    t[never, 0] = 0.0
    last = np.nanmax(t, axis=1, keepdims=True)
    t = np.where(np.isnan(t), last + 1.0 + np.arange(m) * 1e-9, t)  # held after a stall
    # the nodes a stalled row never reaches hold its last reached travel
    reached = np.maximum(np.sum(np.isfinite(time), axis=1) - 1, 0)
    rod = np.where(np.isfinite(time), rod, rod[np.arange(r), reached][:, None])
    span = np.max(t[:, -1] - np.minimum(t[:, 0], np.min(query, axis=1))) + 10.0
    shift = (np.arange(r) * span)[:, None]
    flat = (t + shift).ravel()
    q = np.clip(query, t[:, :1], t[:, -1:]) + shift
    idx = np.clip(np.searchsorted(flat, q.ravel(), side="right"), 1, r * m - 1).reshape(q.shape)
    row0 = (np.arange(r) * m)[:, None]
    idx = np.clip(idx, row0 + 1, row0 + m - 1)
    f_rod = rod.ravel()
    t0, t1 = flat[idx - 1], flat[idx]
    w = np.clip((q - t0) / (t1 - t0), 0.0, 1.0)
    out = (1 - w) * f_rod[idx - 1] + w * f_rod[idx]
    return np.where((query < t[:, :1]) | never[:, None], 0.0, out)
