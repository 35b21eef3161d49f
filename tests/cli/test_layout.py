"""One table layout (camopt/cli/layout.py): columns when every word fits, else
``name: value`` lines; a word is never split across lines."""

from __future__ import annotations

import pytest

from camopt.cli.console import out
from camopt.cli.layout import fits, print_table

COLUMNS = ["metric", "nominal", "p05", "p50", "p95", "driver", "rho"]
ROWS = [["closing_velocity_avg_m_s", "0.771234", "0.701234", "0.771234", "0.841234",
         "case.theta1_deg", "-0.987654"],
        ["tau_max_mpa", "249.123", "240.456", "249.123", "258.789", "kc1_n_per_mm",
         "0.999999"]]


def _printed(width: int, columns=COLUMNS, rows=ROWS) -> str:
    old = out.width
    out.width = width
    try:
        with out.capture() as cap:
            print_table("metrics", columns, rows)
    finally:
        out.width = old
    return cap.get()


@pytest.mark.parametrize("width", [60, 80, 200])
def test_no_word_is_split_at_any_width(width):
    text = _printed(width)
    words = set(text.replace("│", " ").replace(";", " ").split())
    for row in ROWS:
        for cell in row:
            assert cell in words or f"{cell}" in text.split(), (width, cell)
    assert max(len(line) for line in text.splitlines()) <= width


def test_narrow_is_vertical_and_wide_is_a_table():
    assert not fits(COLUMNS, ROWS, 80)  # 24 + 15 + 5 numbers + borders > 80
    narrow = _printed(80)
    assert "┃" not in narrow and "closing_velocity_avg_m_s\n  nominal: 0.771234;" in narrow
    wide = _printed(200)
    assert "┃ metric" in wide and fits(COLUMNS, ROWS, 200)


def test_sweep_rows_keep_their_numbers_whole_at_80_columns():
    """``sweep``'s summary (print_rows) split 'successes' and '36.1001' at 80 columns."""
    from camopt.cli.layout import print_rows

    rows = [{"point": 0, "runs": 2, "successes": 2, "success_rate": 1.0, "best": 36.1001,
             "median": 36.1002, "worst": 36.1003, "median_nfev_to_target": 3850,
             "wall_s_median": 229.225}]
    old = out.width
    out.width = 80
    try:
        with out.capture() as cap:
            print_rows("sweep s.h5", rows, list(rows[0]), None)
    finally:
        out.width = old
    words = cap.get().replace(";", " ").split()
    for token in ("successes:", "36.1001", "median_nfev_to_target:", "229.225"):
        assert token in words
