"""`python -m camopt` and the `camopt` command (:func:`run`): the command-line interface,
started with Python's cyclic garbage collector off. Its passes over the objects that
importing typer, pydantic, numpy and camopt's models creates were ~0.035 s of a ~0.4 s
``camopt validate`` or ``show`` (docs/design.md, start-up's seventh pass); reference
counting still frees everything but cycles, and :func:`camopt.cli.main` turns the
collector on again before any command that computes (:data:`camopt.cli.STARTS_ONLY`)."""

from __future__ import annotations

import gc


def run() -> None:
    """The console script's entry point."""
    gc.disable()
    from camopt.cli import main

    main()


if __name__ == "__main__":
    run()
