"""TOML text written from user strings (issue #49): a name stays a name."""

from __future__ import annotations

import sys

from hypothesis import given, settings
from hypothesis import strategies as st

from camopt.config.models import toml_comment, toml_string

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

NAMES = st.text() | st.sampled_from(["x\nrun = {repeats = 777, seed = 666}\n#",
                                     "a\r\nb", "\x1b[31m", "q\"\\'", "\u2028\u0085x"])


@settings(max_examples=300, derandomize=True, deadline=None)
@given(NAMES)
def test_a_name_in_a_comment_adds_nothing(name):
    """A comment holding any text (a curve file's name) parses as a comment: the file's
    settings are those around it, and the comment is one line."""
    text = f"# RMS misfit on {toml_comment(name)}.\nextends = \"case.toml\"\n"
    assert tomllib.loads(text) == {"extends": "case.toml"}
    assert len(text.splitlines()) == 2


@settings(max_examples=300, derandomize=True, deadline=None)
@given(NAMES)
def test_a_name_in_a_string_reads_back_as_itself(name):
    text = f"extends = {toml_string(name)}\n"
    assert tomllib.loads(text) == {"extends": name} and text.count("\n") == 1
