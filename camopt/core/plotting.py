"""Figure helpers shared by :mod:`camopt.reporting.plots` and the cases' ``figures`` modules
(matplotlib with the Agg backend: no screen needed)."""

from __future__ import annotations

import textwrap
from typing import Any

import matplotlib

matplotlib.use("Agg")
import numpy as np  # noqa: E402
from matplotlib.figure import Figure  # noqa: E402

PAPER_STYLE = {"color": "crimson", "linestyle": "--", "linewidth": 1.2}
"""How a paper's reported value is drawn (a reference line or marker)."""

UNITS = {"j": "J", "ms": "ms", "n": "N", "nm": "N m", "mm": "mm", "rad": "rad", "sq": "",
         "deg": "deg", "mpa": "MPa", "s": "s", "pct": "%"}


def figure(**kwargs: Any) -> Figure:
    """A matplotlib Figure not registered with pyplot (``kwargs`` as ``Figure``'s): a
    report or test that makes many keeps none alive once it is saved and dropped
    (pyplot's figures stay open until closed, and warn past 20)."""
    return Figure(**kwargs)


TITLE_CHARS = 64
"""Longest title line (characters) a 7-inch figure shows whole at the default font."""


def wrapped(title: str, width: int = TITLE_CHARS) -> str:
    """A title broken into lines of at most ``width`` characters (its own line breaks
    kept), so none is cut at the figure's edge."""
    return "\n".join(part for line in title.splitlines()
                     for part in textwrap.wrap(line, width) or [""])


def new_figure(title: str, xlabel: str, ylabel: str) -> tuple[Figure, Any]:
    """A figure with one labelled axes and a light grid; a long title wraps."""
    fig = figure(figsize=(7, 4.5), layout="constrained")
    ax = fig.subplots()
    ax.set_title(wrapped(title))
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    ax.grid(alpha=0.3)
    return fig, ax


def readable(name: str) -> str:
    """'closure_time_ms' -> 'closure time (ms)'."""
    if name.endswith("_m_s"):  # a two-word unit
        return f"{name[:-4].replace('_', ' ')} (m/s)"
    stem, _, unit = name.rpartition("_")
    if stem and unit in UNITS:
        return f"{stem.replace('_', ' ')} ({UNITS[unit]})" if UNITS[unit] else stem
    return name.replace("_", " ")


def log_scale_if_spread(ax: Any, values: np.ndarray, factor: float = 20.0) -> None:
    """Use a log y axis when the largest finite value exceeds ``factor`` times the median."""
    finite = np.asarray(values, dtype=float)
    finite = finite[np.isfinite(finite)]
    if finite.size and finite.min() > 0 and finite.max() > factor * np.median(np.abs(finite)):
        ax.set_yscale("log")


def close(fig: Figure) -> None:
    """Release a saved figure's artists (no pyplot state holds it: :func:`figure`)."""
    fig.clear()
