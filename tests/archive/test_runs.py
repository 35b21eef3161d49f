"""Run archives read back (camopt/archive/runs.py): older names of metrics."""

from __future__ import annotations

from camopt.archive.runs import renamed_metrics


def test_an_older_vcb_archives_closing_time_reads_as_release_to_latch():
    """Before the analyser's vocabulary a VCB run stored the release-to-latch time as
    closing_time_ms (and its band ends, and the reference's): read under today's name.
    An archive that already has release_to_latch_ms keeps its closing_time_ms (command to
    touch); other names are untouched."""
    old = {"closing_time_ms": 41.7, "closing_time_low_ms": 40.0,
           "initial_closing_time_high_ms": 43.0, "touch_time_ms": 27.0}
    assert renamed_metrics(old) == {
        "release_to_latch_ms": 41.7, "release_to_latch_low_ms": 40.0,
        "initial_release_to_latch_high_ms": 43.0, "touch_time_ms": 27.0}
    new = {"closing_time_ms": 30.4, "release_to_latch_ms": 41.7}
    assert renamed_metrics(new) == new
    assert renamed_metrics({"tau_max_mpa": 1.0}) == {"tau_max_mpa": 1.0}
