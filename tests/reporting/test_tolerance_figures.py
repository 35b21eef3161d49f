"""The tolerance figures (camopt/reporting/tolerance_figures.py) against the data they plot:
the tornado's bars from a hand-built one-at-a-time summary, no analysis run."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest
from matplotlib.colors import to_rgba

from camopt.reporting.tolerance_figures import tornado

ROWS = [{"input": "a_mm", "low": 9.0, "high": 12.5},   # swing 3.5, +X above nominal
        {"input": "b_deg", "low": 10.8, "high": 9.6},  # swing 1.2, +X below nominal
        {"input": "case.c_mm", "low": 10.1, "high": 10.0}]  # swing 0.1
NOMINAL = 10.0


def _bars(fig) -> dict[str, dict[str, float]]:
    """Per legend entry ("input at -X" / "input at +X"): input name -> the value the bar
    reaches (its far end from the nominal), read from the drawn rectangles."""
    ax = fig.axes[0]
    names = [t.get_text() for t in ax.get_yticklabels()]
    handles, labels = ax.get_legend_handles_labels()
    out: dict[str, dict[str, float]] = {}
    for handle, label in zip(handles, labels):
        colour = to_rgba(handle.patches[0].get_facecolor())
        out[label] = {}
        for p in ax.patches:
            if to_rgba(p.get_facecolor()) == colour:
                y = round(p.get_y() + p.get_height() / 2)
                out[label][names[y]] = p.get_x() + p.get_width()
    return out


def test_tornado_draws_each_inputs_plus_x_end_at_its_high_value():
    """Each input's +X bar runs from the nominal to the metric with the input at +X
    (``high``), its -X bar to the value at -X (``low``), whichever side of the nominal
    they fall; the widest swing is on top (the last row of the y axis)."""
    t = SimpleNamespace(summary={"one_at_a_time": {"f_ms": ROWS}, "nominal": {"f_ms": NOMINAL}})
    fig = tornado(t, "f_ms")
    bars = _bars(fig)
    assert set(bars) == {"input at -X", "input at +X"}
    for r in ROWS:
        assert bars["input at +X"][r["input"]] == pytest.approx(r["high"], abs=1e-12)
        assert bars["input at -X"][r["input"]] == pytest.approx(r["low"], abs=1e-12)
    ax = fig.axes[0]
    assert [t.get_text() for t in ax.get_yticklabels()] == ["case.c_mm", "b_deg", "a_mm"]
    assert all(np.isclose(p.get_x(), NOMINAL) for p in ax.patches)  # from the nominal


def _by_gid(ax):
    return {p.get_gid(): p for p in ax.patches}


def test_tornado_labels_carry_the_tolerance_and_the_legend_its_colours():
    """With the analysis' ``vary`` rows, each label names the input and its tolerance; the
    legend's colours are the bars' (-X blue, +X orange)."""
    # a: raising the input lowers the metric; b: raising it raises the metric
    summary = {"nominal": {"m": 10.0},
               "one_at_a_time": {"m": [{"input": "a", "low": 12.0, "high": 7.0},
                                       {"input": "b", "low": 9.5, "high": 10.5}]},
               "vary": [{"input": "a", "tolerance": 5.0, "unit": "%"},
                        {"input": "b", "tolerance": 0.1, "unit": "own"}]}
    ax = tornado(SimpleNamespace(summary=summary, run=None), "m").axes[0]
    bars = _by_gid(ax)
    # widest swing on top: b (width 1) at y 0, a (width 5) at y 1
    assert [t.get_text() for t in ax.get_yticklabels()] == ["b ±0.1", "a ±5%"]
    for y, (low, high) in enumerate(((9.5, 10.5), (12.0, 7.0))):
        plus, minus = bars[f"high-{y}"], bars[f"low-{y}"]
        assert plus.get_x() == pytest.approx(10.0)  # from nominal ...
        assert plus.get_x() + plus.get_width() == pytest.approx(high)  # ... to +X's value
        assert minus.get_x() + minus.get_width() == pytest.approx(low)
        assert plus.get_facecolor() != minus.get_facecolor()
    legend = {t.get_text(): h.get_facecolor()
              for t, h in zip(ax.get_legend().get_texts(), ax.get_legend().legend_handles)}
    assert legend == {"input at -X": bars["low-0"].get_facecolor(),
                      "input at +X": bars["high-0"].get_facecolor()}
