"""The typed documents (camopt/core/documents.py): the robust check's quantile key, named
by its quantile and placed where the archives have always had it."""

from __future__ import annotations

from camopt.core.documents import DesignCheck, quantile_key, with_quantile


def test_the_quantile_key_names_its_percentile_in_two_digits():
    assert quantile_key(0.9) == "objective_q90"
    assert quantile_key(0.05) == "objective_q05"
    assert quantile_key(0.95) == "objective_q95"


def test_the_quantile_follows_the_mean_and_the_document_given_is_left_alone():
    doc: DesignCheck = {"samples": 10, "objective_nominal": 1.0, "objective_mean": 2.0,
                        "nominal_feasible": True, "margins": {}}
    out = with_quantile(doc, 0.9, 3.0)
    assert list(out) == ["samples", "objective_nominal", "objective_mean", "objective_q90",
                         "nominal_feasible", "margins"]
    assert out["objective_q90"] == 3.0
    assert "objective_q90" not in doc
