"""The compiled closing kernel's cache from a read-only install: numba keeps it beside the
module (``__pycache__``) where that is writable, else in the user's cache folder
(``$XDG_CACHE_HOME/numba``), so the compile (README, "Installation") is paid once per user,
not on every run. Root may write anywhere, so the read-only folder is simulated: numba's
in-tree locator is told it cannot write."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

numba_caching = pytest.importorskip("numba.core.caching")


def test_kernel_cache_falls_back_to_the_user_cache_folder(monkeypatch: pytest.MonkeyPatch,
                                                          tmp_path: Path) -> None:
    kernel = pytest.importorskip("camopt.cases.vcb.kernel")

    def read_only(self: object) -> None:
        raise OSError("read-only file system")

    monkeypatch.setattr(numba_caching.InTreeCacheLocator, "ensure_cache_path", read_only)
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path))
    impl = numba_caching.CompileResultCacheImpl(kernel._first_zero.py_func)
    assert isinstance(impl.locator, numba_caching.UserWideCacheLocator)
    assert Path(impl.locator.get_cache_path()).is_relative_to(tmp_path / "numba")
    # and a writable package folder (this checkout) keeps it beside the module
    monkeypatch.undo()
    impl = numba_caching.CompileResultCacheImpl(kernel._first_zero.py_func)
    if os.access(Path(kernel.__file__).parent, os.W_OK):
        assert Path(impl.locator.get_cache_path()) == Path(kernel.__file__).parent / "__pycache__"
