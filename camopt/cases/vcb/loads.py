"""The loads at the VCB's rod: the opening and contact springs and the free-contact force
(Eq 24's general resistant force and its work, Eqs 23-24)."""

from __future__ import annotations

from dataclasses import dataclass, fields, replace

import numpy as np
from numpy.typing import NDArray


@dataclass(frozen=True)
class Loads:
    """Load model at the rod: resisting springs, free-contact force, efficiency (SI). The
    springs' rates may be (n, 1) columns, one per design (springs made to a tolerance),
    the efficiency (n,) (Eq 26's surplus)."""

    opening_k: NDArray | float
    opening_arm: NDArray | float
    opening_stretch_open: NDArray | float  # opening-spring stretch in the opened state
    wipe_k: NDArray | float  # all contact springs together
    wipe_preload: NDArray | float  # contact-spring compression at touch
    gap: float
    free_contact: NDArray | float
    efficiency: NDArray | float

    def tiled(self, sets: int) -> Loads:
        """The loads of n designs for ``sets`` parameter sets per design (sets x n rows,
        set-major, as :meth:`~camopt.cases.vcb.dynamics.MotionParameters.repeat`): the
        per-design columns repeated; shared values unchanged."""
        def tile(v: NDArray | float) -> NDArray | float:
            return np.tile(v, (sets,) + (1,) * (np.ndim(v) - 1)) if np.ndim(v) else v
        return replace(self, **{f.name: tile(getattr(self, f.name))  # type: ignore[arg-type]
                                for f in fields(self)})

    def resistant_force(self, s1: NDArray) -> NDArray:
        """General resistant force Fr (Eq 24) at rod travel s1 (N)."""
        arm_k = self.opening_arm * self.opening_k  # coefficients first: few full-size ops
        # contact springs once the contacts touch, the free-contact force before
        touching = np.multiply(s1, self.wipe_k)
        touching += self.wipe_k * (self.wipe_preload - self.gap)
        force = np.where(s1 >= self.gap, touching, -self.free_contact)
        opening = np.multiply(s1, arm_k * self.opening_arm, out=touching)
        opening += arm_k * self.opening_stretch_open
        force += opening
        return force

    def resistant_energy(self, s1: NDArray) -> NDArray:
        """Work done against Fr from the opened position to rod travel s1 (J), exactly:
        Fr depends on s1 alone, so its work is a potential difference (Eqs 23, 24) and
        needs no sampling. Opening spring 1/2 k ((x0 + r s1)^2 - x0^2) with r = r7/r6;
        contact springs 1/2 k_w ((s1 - gap + p)^2 - p^2) after touch; the free-contact
        force -F_fc min(s1, gap) before it."""
        s1 = np.asarray(s1, dtype=float)
        x0 = self.opening_stretch_open
        stretch = x0 + self.opening_arm * s1
        energy = 0.5 * self.opening_k * (stretch * stretch - x0 * x0)
        wipe = np.maximum(s1 - self.gap, 0.0) + self.wipe_preload
        energy = energy + 0.5 * self.wipe_k * (wipe * wipe - self.wipe_preload**2)
        return energy - self.free_contact * np.minimum(s1, self.gap)
