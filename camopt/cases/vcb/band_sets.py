"""The parameter sets a VCB closing is judged under: the identified set and the band's
(``dynamics_band``), grouped by model form. Each kept form is judged under its own fit
and its other sets: a breaker's true parameters are some set of some form, and the ADAMS
data do not say which."""

from __future__ import annotations

from dataclasses import dataclass, fields, replace

import numpy as np

from camopt.cases.vcb.config import VcbConfig
from camopt.cases.vcb.dynamics import MotionParameters
from camopt.cases.vcb.forms import form_of
from camopt.mechanics import Floats
from camopt.units import DEG


@dataclass(frozen=True)
class FormSets:
    """The parameter sets a closing is judged under: the ``nominal`` set (its values and
    metrics are the design's ``closing_*``) and the ``members`` of the band beside it
    (``count`` sets, set-major arrays; None when there are none). Release offsets are the
    sets' own (rad); a design's latch moves every one with it."""

    name: str
    nominal: MotionParameters
    members: MotionParameters | None
    count: int


def identified(c: VcbConfig) -> MotionParameters:
    """The identified parameters of the case (``[case]``'s inertias, masses, latch and
    friction), with its spring mass and rod damping."""
    return MotionParameters(c.cam_inertia_kg_m2, c.follower_inertia_kg_m2, c.rod_mass_kg,
                            c.contacts_mass_kg, c.release_offset_deg * DEG,
                            c.cam_friction_nm, spring_kg=c.spring_mass_kg,
                            rod_damping_n_s_per_m=c.rod_damping_n_s_per_m)


def band_rows(c: VcbConfig) -> Floats:
    """``dynamics_band`` as eight-value rows (k, 8): a six-value row (the shipped form)
    takes the same friction for the free rotation and the case's efficiency."""
    return np.array([tuple(r) + ((r[5], c.efficiency) if len(r) == 6 else ())
                     for r in c.dynamics_band], dtype=float).reshape(-1, 8)


def parameter_sets(rows: Floats, c: VcbConfig | None = None) -> MotionParameters:
    """Eight-value band rows (k, 8) as k parameter sets (SI), with the case ``c``'s
    spring mass and rod damping (one value for every set; none without ``c``)."""
    return MotionParameters(rows[:, 0], rows[:, 1], rows[:, 2], rows[:, 3], rows[:, 4] * DEG,
                            rows[:, 5], rows[:, 6], rows[:, 7],
                            spring_kg=0.0 if c is None else c.spring_mass_kg,
                            rod_damping_n_s_per_m=0.0 if c is None else c.rod_damping_n_s_per_m)


def joined(form: FormSets, efficiency: float) -> MotionParameters:
    """A form's fit and its other sets as k + 1 parameter sets ((k + 1,) arrays, the fit
    first), every field resolved as :meth:`MotionParameters.columns` resolves it."""
    columns = [form.nominal.columns(1, efficiency)]
    if form.members is not None:
        columns.append(form.members.columns(form.count, efficiency))
    return MotionParameters(**{f.name: np.concatenate([getattr(c, f.name)[:, 0]
                                                       for c in columns])
                               for f in fields(MotionParameters)})


def form_sets(c: VcbConfig, band: Floats, dynamics: MotionParameters
              ) -> tuple[FormSets, ...]:
    """The sets of every model form in the band (the identified parameters' form
    first): each form's closing is judged under its own fit (the identified set
    ``dynamics`` for that form, else the form's first row: the identification lists each
    form's fit first) and its other sets. A single form gives one entry, the full band."""
    ident = np.array([[c.cam_inertia_kg_m2, c.follower_inertia_kg_m2, c.rod_mass_kg,
                       c.contacts_mass_kg, c.release_offset_deg, c.cam_friction_nm,
                       c.cam_friction_nm, c.efficiency]])
    names = [form_of(ident[0])] + [form_of(r) for r in band]
    order = list(dict.fromkeys(names))
    if len(order) == 1:
        return (FormSets(order[0], dynamics, parameter_sets(band, c) if len(band) else None,
                         len(band)),)
    out = []
    for name in order:
        rows = band[[i for i, f in enumerate(names[1:]) if f == name]]
        if name == names[0]:
            nominal, members = dynamics, rows
        else:
            nominal = replace(parameter_sets(rows[:1], c), **{
                f: float(np.ravel(getattr(parameter_sets(rows[:1]), f))[0]) for f in
                ("cam_kg_m2", "follower_kg_m2", "rod_kg", "contacts_kg",
                 "release_offset_rad", "friction_nm")})
            nominal = replace(nominal, release_friction_nm=float(rows[0, 6]),
                              efficiency=float(rows[0, 7]))
            members = rows[1:]
        out.append(FormSets(name, nominal, parameter_sets(members, c) if len(members)
                            else None, len(members)))
    return tuple(out)
