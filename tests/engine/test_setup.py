"""What a run needs before its loop (camopt/engine/setup.py): here the generator that
``validate`` builds a solver with."""

from __future__ import annotations

import numpy as np

from camopt.engine.setup import FirstUseRng


def test_first_use_rng_is_the_seeded_generator_made_when_first_used() -> None:
    """Nothing is made until an attribute is read; then every draw is the stream of
    ``default_rng(seed)`` itself (the proxy hands over that generator's own methods, so
    the values are compared exactly: the same generator, not another computation)."""
    lazy = FirstUseRng(7)
    assert lazy._rng is None
    eager = np.random.default_rng(7)
    for draw in ("random", "standard_normal", "integers"):
        args = (0, 10, 5) if draw == "integers" else (5,)
        np.testing.assert_array_equal(getattr(lazy, draw)(*args), getattr(eager, draw)(*args))
    assert isinstance(lazy._rng, np.random.Generator)
    assert lazy.bit_generator is lazy._rng.bit_generator  # one generator, made once
