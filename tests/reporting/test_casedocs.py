"""docs/cases/<kind>.md and ``camopt init`` from the config models' field descriptions
(issue #22): the pages are up to date, and every field says what it is and where its value
comes from."""

from __future__ import annotations

import re

import pytest

from camopt.config.models import unit_of
from camopt.reporting import casedocs

# a source a reader can follow: the paper's section, equation, table or figure, a value
# identified or assumed (docs/assumptions.md), a search range or camopt's own option
SOURCE = re.compile(r"\b(Sec|Eqs?|Table|Fig|Nomenclature|Monotonicity Analysis)\b|"
                    r"identified|assumed|search range|camopt|configs/|docs/|handbook|"
                    r"standard|three-phase|beyond the paper")


def test_case_pages_are_up_to_date():
    pages = casedocs.pages()
    stale = [name for name, text in pages.items()
             if not (casedocs.DOCS / name).is_file()
             or (casedocs.DOCS / name).read_text(encoding="utf-8") != text]
    extra = sorted(p.name for p in casedocs.DOCS.glob("*.md")) != sorted(pages)
    assert not stale and not extra, (f"regenerate with `python -m camopt.reporting.casedocs` "
                                     f"(stale: {stale}, extra files: {extra})")


@pytest.mark.parametrize("kind", sorted(casedocs.built_in()))
def test_every_case_field_has_a_meaning_and_a_source(kind):
    model = casedocs.built_in()[kind].config
    missing = [name for name, info in model.model_fields.items()
               if name != "kind" and not (info.description and SOURCE.search(info.description))]
    assert not missing, f"{kind}: fields without a description naming a source: {missing}"


def test_units_come_from_the_names():
    assert [unit_of(n) for n in ("l1_mm", "kc1_n_per_mm", "closing_velocity_m_s", "t0_ms",
                                 "cam_inertia_kg_m2", "k_kn_per_mm3", "latch_energy_min_j",
                                 "alpha", "positions")] == \
        ["mm", "N/mm", "m/s", "ms", "kg m^2", "kN/mm^3", "J", "", ""]


def test_a_page_lists_default_unit_and_source():
    page = casedocs.render(casedocs.built_in()["vcb"])
    assert "| `rod_arm_offset_deg` | 7.46 | deg | identified | angle of EM" in page
    assert "| `kc1_n_per_mm` | 7.72 | N/mm | hardware | vendor closing spring 1 (Table 2) |" in page


@pytest.mark.parametrize("kind", ["vcb", "vcb_identify", "vcb_identify_dynamics"])
def test_every_vcb_field_has_a_role_shown_in_the_docs_and_init(kind):
    """Each [case] field of the VCB cases is hardware, identified, requirement, solver
    setting or measured data; docs/cases/<kind>.md has the role column and camopt init
    the role at the end of each field's comment."""
    from camopt.cases import get_case
    from camopt.config import template
    from camopt.config.models import ROLES
    from camopt.reporting.casedocs import render
    from camopt.solvers import solvers

    spec = get_case(kind)
    fields = set(spec.config.model_fields) - {"kind"}
    assert set(spec.config.field_roles) == fields
    assert set(spec.config.field_roles.values()) <= set(ROLES)
    page = render(spec)
    assert "| field | default | unit | role | meaning (source) |" in page
    assert "| `rod_mass_kg` | 2.8807 | kg | identified |" in page
    assert "| `l1_mm` | 139.79 | mm | hardware |" in page
    text = template(spec.config, solvers()[spec.default_solver].Options.model_validate({}))
    assert "fixed link BE (Sec 2.3) [mm] (hardware)" in text
    assert "(identified): fitted to measurements" in text
