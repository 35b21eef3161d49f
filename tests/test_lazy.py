"""camopt/lazy.py: a package's names imported from their modules on first lookup."""

from __future__ import annotations

import pytest

from camopt import units
from camopt.lazy import lazy_names


def test_a_name_is_imported_from_its_module_once_and_kept():
    namespace = {"__name__": "camopt"}
    getattr_ = lazy_names(namespace, {"DEG": "units"})
    assert "DEG" not in namespace
    assert getattr_("DEG") is units.DEG
    assert namespace["DEG"] is units.DEG  # later lookups read the package's globals


def test_a_name_without_a_home_is_an_attribute_error():
    getattr_ = lazy_names({"__name__": "camopt.config"}, {})
    with pytest.raises(AttributeError, match="module 'camopt.config' has no attribute 'nope'"):
        getattr_("nope")
