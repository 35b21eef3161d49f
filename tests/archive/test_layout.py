"""docs/archive.md documents every object and attribute a run archive holds."""

from __future__ import annotations

import re

import h5py
import pytest

from camopt import archive
from camopt.engine.driver import execute
from tests.conftest import CONFIGS, ROOT
from tests.helpers import load

DOC = (ROOT / "docs" / "archive.md").read_text()
PROSE = re.sub(r"```.*?```", "", DOC, flags=re.S)  # code blocks are examples, not names
DOCUMENTED = set(re.findall(r"`([^`]+)`", PROSE))


@pytest.fixture(scope="module")
def run_file(tmp_path_factory):
    path = tmp_path_factory.mktemp("layout") / "a.h5"
    archive.write_run(execute(load(CONFIGS / "fast_switch_de.toml", "run.repeats=2",
                                   "solver.generations=5")), path)
    return path


def test_every_root_attribute_is_documented(run_file):
    with h5py.File(run_file, "r") as f:
        missing = sorted(set(f.attrs) - DOCUMENTED)
    assert missing == []


def test_every_repeat_and_best_object_is_documented(run_file):
    with h5py.File(run_file, "r") as f:
        rep = f["repeats/r000"]
        names = set(rep.attrs) | (set(rep) - {"history"}) | {f"history/{k}"
                                                             for k in rep["history"]}
        names |= set(f["best"].attrs) | set(f["best"])
        names |= {"/repeats/rNNN", "/best", "/analysis/<curve>", "/table/<column>",
                  "/summary/<column>"}
        names |= set(f["summary"])
    assert sorted(names - DOCUMENTED) == []
