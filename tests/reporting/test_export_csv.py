"""``camopt export --format csv`` of a handed-over archive (issue #30): no cell a
spreadsheet would run as a formula; numbers, negative ones included, stay numbers."""

from __future__ import annotations

import csv
import io
import math
import shutil

import h5py
import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st
from typer.testing import CliRunner

from camopt.cli import app
from camopt.reporting import export

FORMULA = ("=", "+", "-", "@", "\t", "\r")
cells = st.one_of(st.text(max_size=12), st.floats(allow_nan=False), st.integers(),
                  st.sampled_from(["=1+2", "+SUM(A1)", "-2+3", "@cmd", "=HYPERLINK(\"x\")",
                                   "\tx", "-1.5", -1.5, -0.0, -7]))


def read(data: bytes) -> list[list[str]]:
    return list(csv.reader(io.StringIO(data.decode(), newline="")))


@settings(max_examples=200, derandomize=True)
@given(st.lists(st.lists(cells, min_size=1, max_size=4), min_size=1, max_size=5))
def test_no_string_cell_starts_a_formula_and_numbers_stay_numbers(rows):
    back = read(export._csv(rows))
    assert len(back) == len(rows)
    for row, got in zip(rows, back):
        for cell, text in zip(row, got):
            if isinstance(cell, str):
                assert not text.startswith(FORMULA)
                assert text in (cell, "'" + cell)  # nothing else changed
            elif isinstance(cell, int):
                assert int(text) == cell  # exactly, beyond 2^53 too
            else:
                assert float(text) == cell or (math.isinf(cell) and math.isinf(float(text)))


def test_export_of_a_crafted_archive_neutralises_its_strings(tmp_path, fast_run):
    """Strings an archive carries (a metric's text, a curve's name) reach the CSV files
    with a leading apostrophe when they would start a formula; its numbers stay numbers."""
    path = tmp_path / "crafted.h5"
    shutil.copy(fast_run, path)
    with h5py.File(path, "a") as f:
        f["best"]["metrics"].attrs["exact_dynamics"] = '=HYPERLINK("http://x","y")'
        f["best"]["metrics"].attrs["margin_mm"] = -2.5
        f["analysis"].create_dataset("@evil", data=-np.arange(3.0))
        f["analysis"].create_dataset("+also", data=np.arange(3.0))
    out = tmp_path / "out"
    r = CliRunner().invoke(app, ["export", str(path), "--format", "csv", "--out", str(out)])
    assert r.exit_code == 0, r.output
    texts = [cell for p in sorted(out.glob("*.csv")) for row in read(p.read_bytes())
             for cell in row]
    assert "'=HYPERLINK(\"http://x\",\"y\")" in texts and "'@evil" in texts
    assert "-2.5" in texts and "-2.0" in texts  # numbers kept
    for text in texts:
        if text.startswith(FORMULA):
            float(text)  # only a number may start with '-' or '+'
