"""`python -m camopt` and the `camopt` command (:func:`run`): the command-line interface,
started with Python's cyclic garbage collector off. Its passes over the objects that
importing typer, pydantic, numpy and camopt's models creates were ~0.035 s of a ~0.4 s
``camopt validate`` or ``show`` (docs/design.md, start-up's seventh pass); reference
counting still frees everything but cycles, and :func:`camopt.cli.main` turns the
collector on again before any command that computes (:data:`camopt.cli.STARTS_ONLY`).
A start-up command keeps it off while Python exits too (:func:`exit_uncollected`)."""

from __future__ import annotations

import gc


def run() -> None:
    """The console script's entry point."""
    gc.disable()
    from camopt.cli import main

    try:
        main()
    finally:
        if not gc.isenabled():  # a start-up command: off to the end, exit included
            exit_uncollected()


def exit_uncollected() -> None:
    """Leave the objects of a command that ran with the collector off out of the
    collections Python makes while it exits (``gc.freeze``): they would walk every object
    (~0.04 s of CPU after ``validate`` or ``show``, bench/bench_startup.py) only to free
    cycles whose memory the ending process gives back anyway. Reference counting still
    frees the modules' objects; an object in a cycle is not finalized at exit, as none
    was collected while the command ran."""
    gc.freeze()


if __name__ == "__main__":
    run()
