"""What a sweep runs: the Cartesian product of grid values x seeds, as plain data.

A cell is a plain, picklable spec (validated config data, seed entropy, seed index),
so the same function runs it inline, in a local process pool or on a Dask cluster,
and its result does not depend on where it ran. Seed k of every grid point is child k
of ``SeedSequence(run.seed)``.
"""

from __future__ import annotations

import copy
import hashlib
import itertools
import json
import re
from collections.abc import Iterable
from dataclasses import dataclass
from typing import Any

from camopt.config.loader import apply_override, parse_value
from camopt.config.raw import RawDoc
from camopt.errors import ConfigError

# ---- specification ------------------------------------------------------------------
# Storage is O(1) per cell (a journal line; snapshots when the cells double), but the
# summary and the snapshots hold every cell in memory: 100,000 cells is far beyond any
# gated sweep here and still a few hundred MB at most.
MAX_CELLS = 100_000
# keys a grid may not set: seeds come from --seeds (child k of SeedSequence(run.seed) for
# every grid point), so a grid over run.seed would run the same seeds at every point
_NOT_GRIDDED = {"run.seed": "give seeds with --seeds; every grid point uses child k of "
                "SeedSequence(run.seed)", "run.repeats": "a sweep cell is one repeat; give "
                "more seeds with --seeds", "run.name": "the sweep has one name"}


def parse_seeds(text: str) -> tuple[int, int]:
    """'0:25' -> (0, 25); '7' -> (0, 7)."""
    m = re.fullmatch(r"\s*(\d+)\s*(?::\s*(\d+)\s*)?", text)
    if not m:
        raise ConfigError("--seeds", text, "expected START:STOP (e.g. 0:25) or a count")
    if any(len(g) > 19 for g in m.groups() if g):  # int() refuses > 4,300 digits anyway
        raise ConfigError("--seeds", text[:40] + ("..." if len(text) > 40 else ""),
                          "seed indices below 2^63 expected")
    start, stop = (0, int(m.group(1))) if m.group(2) is None else (int(m.group(1)),
                                                                    int(m.group(2)))
    if stop <= start:
        raise ConfigError("--seeds", text, "STOP must be above START")
    if stop - start > MAX_CELLS or stop >= 2**63:
        raise ConfigError("--seeds", text, f"at most {MAX_CELLS} seeds in one sweep (every "
                          "cell is held in memory)")
    return start, stop


def _split_top(text: str) -> list[str]:
    parts, depth, cur = [], 0, ""
    for ch in text:
        depth += ch in "[{"
        depth -= ch in "]}"
        if ch == "," and depth == 0:
            parts.append(cur)
            cur = ""
        else:
            cur += ch
    return [*parts, cur]


def parse_grid(items: Iterable[str]) -> list[tuple[str, list[Any]]]:
    """'solver.population=50,100,200' -> [('solver.population', [50, 100, 200])]."""
    grid: list[tuple[str, list[Any]]] = []
    for item in items:
        key, sep, raw = item.partition("=")
        key = key.strip()
        if not sep or not re.fullmatch(r"[A-Za-z_]\w*(\.[A-Za-z_]\w*)+", key):
            raise ConfigError("--grid", item, "expected section.key=v1,v2,...")
        if key in _NOT_GRIDDED:
            raise ConfigError("--grid", key, _NOT_GRIDDED[key])
        if key in (k for k, _ in grid):
            raise ConfigError("--grid", key, "given twice; list every value in one --grid")
        values = []
        for part in _split_top(raw):
            try:
                values.append(parse_value(part))
            except ValueError:
                raise ConfigError("--grid", key, f"cannot parse value {part!r}") from None
        if len({json.dumps(v, sort_keys=True) for v in values}) < len(values):
            raise ConfigError("--grid", key, "a value is given twice")
        grid.append((key, values))
    return grid


@dataclass(frozen=True)
class SweepSpec:
    """What a sweep runs: the base config, the grid, the seed range."""

    data: RawDoc
    source: str
    text: str
    grid: list[tuple[str, list[Any]]]
    seeds: tuple[int, int]

    @property
    def entropy(self) -> int:
        """The root seed every cell's generator derives from (``run.seed``)."""
        return int(self.data["run"]["seed"])

    def points(self) -> list[RawDoc]:
        """Every grid point as ``{key: value}`` (one empty point without a grid)."""
        keys = [k for k, _ in self.grid]
        return [dict(zip(keys, combo))
                for combo in itertools.product(*(v for _, v in self.grid))] or [{}]

    def point_data(self, point: RawDoc) -> RawDoc:
        """The base case-file data with a grid point's values set."""
        data = copy.deepcopy(self.data)
        for key, value in point.items():
            apply_override(data, key, value)
        return data

    def cells(self) -> list[CellSpec]:
        """Every cell; the cells of one grid point share its (read-only) config data."""
        out = []
        for i, p in enumerate(self.points()):
            data = self.point_data(p)
            out += [CellSpec(data, self.source, self.entropy, s, i) for s in range(*self.seeds)]
        return out

    @property
    def sweep_id(self) -> str:
        """What ties a journal line to its sweep: a hash of the spec (config data, grid,
        seeds). Two sweeps with equal ids run equal cells (same seeds, same results)."""
        return hashlib.sha256(self.to_json().encode()).hexdigest()[:16]

    def to_json(self) -> str:
        """The spec as JSON text (stored in the sweep archive)."""
        return json.dumps({"data": self.data, "source": self.source, "grid": self.grid,
                           "seeds": list(self.seeds)})

    @classmethod
    def from_json(cls, text: str, toml_text: str) -> SweepSpec:
        """A spec from :meth:`to_json` text and the case file's text."""
        d = json.loads(text)
        return cls(d["data"], d["source"], toml_text, [tuple(g) for g in d["grid"]],
                   tuple(d["seeds"]))


@dataclass(frozen=True)
class CellSpec:
    """One cell: a grid point's config data and one seed index."""

    data: RawDoc
    source: str
    entropy: int
    seed: int
    point: int

    @property
    def key(self) -> tuple[int, int]:
        return (self.point, self.seed)
