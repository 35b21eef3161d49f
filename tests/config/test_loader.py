"""Command-line values for --set and --grid."""

from __future__ import annotations

import pytest

from camopt.config.loader import parse_overrides, parse_value
from camopt.errors import ConfigError


@pytest.mark.parametrize("raw, value", [
    ("3", 3), ("1.5", 1.5), ("true", True), ("[1, 2]", [1, 2]), ('"a b"', "a b"),
    ("{peak_torque_nm = 5.4}", {"peak_torque_nm": 5.4}), ("simplex", "simplex"),
    ("runs/vcb-20261122.h5", "runs/vcb-20261122.h5"), ("/tmp/a.h5", "/tmp/a.h5"),
    ("./a.h5", "./a.h5"), ("~/runs/a.h5", "~/runs/a.h5"),
])
def test_values_are_toml_or_a_bare_word_or_path(raw, value):
    assert parse_value(raw) == value


@pytest.mark.parametrize("raw", ["[1,", "two words", "a=b"])
def test_other_text_is_refused(raw):
    with pytest.raises(ValueError):
        parse_value(raw)


def test_override_names_the_key_it_cannot_parse():
    with pytest.raises(ConfigError, match="case.x: cannot parse value"):
        parse_overrides(["case.x=two words"])
