"""Every shipped config's archive, before and after a change: the same numbers (refactors).

A move of code that should change nothing is shown to change nothing by running each
config in ``configs/`` at a tiny budget (``BUDGETS``: a few generations, two repeats, the
config's own seed) from two checkouts, then comparing the two archives' content: every
dataset and attribute, numbers within ``--rtol``, text exactly, JSON text parsed and its
numbers within ``--rtol``; the wall times and the creation date (``IGNORED``) left out.

    python scripts/archive_identity.py run CHECKOUT OUTDIR     # one checkout's archives
    python scripts/archive_identity.py compare DIR_A DIR_B [--rtol 1e-12]

``run`` starts ``python -m camopt run`` with ``PYTHONPATH=CHECKOUT`` (so an unpacked older
commit, ``git archive <commit> | tar -x -C /tmp/base``, runs with this venv) on this
checkout's config files, so both sides read the same TOML. A config missing from
``BUDGETS`` stops the script: a new config is added to the table, not skipped.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import subprocess
import sys
import time
from pathlib import Path

import h5py
import numpy as np

CONFIGS = Path(__file__).resolve().parents[1] / "configs"

DE = ["solver.generations=4", "solver.population=16"]
NSGA2 = ["solver.generations=3", "solver.population=16"]
PSO = ["solver.iterations=4", "solver.particles=12", "solver.polish.evaluations=100"]
CMAES = ["solver.evaluations=120", "solver.restarts=0"]
ROBUST = ["robust.samples=8", "robust.check_samples=200"]
VCB_ROBUST = [*ROBUST, "robust.race=4", "robust.centre_generations=2"]

BUDGETS: dict[str, list[str]] = {
    "emb": PSO,
    "emb_linear": PSO,
    "emb_pareto": NSGA2,
    "emb_robust": ["solver.iterations=4", "solver.particles=12", *ROBUST],
    "fast_switch": [],
    "fast_switch_de": [*DE, "solver.polish.maxiter=5"],
    "fast_switch_pareto": NSGA2,
    "fast_switch_robust": [*DE, *ROBUST, "robust.finalists=2"],
    "opening_spring_identify": ["solver.starts=2"],
    "opening_spring_lse6": ["solver.starts=2"],
    "opening_spring_lse6_pinned": ["solver.starts=2"],
    "opening_spring_pp3": ["solver.starts=2"],
    "opening_spring_pp4": ["solver.starts=2"],
    "vcb": DE,
    "vcb_fourbar": DE,
    "vcb_identify": CMAES,
    "vcb_identify_dynamics": CMAES,
    "vcb_pareto": [*NSGA2, "solver.cmaes_evaluations=64"],
    "vcb_velocity": CMAES,
    "vcb_velocity_robust": [*DE, *VCB_ROBUST],
    "vcb_velocity_serviced": [*DE, *VCB_ROBUST],
}
REPEATS = 2

IGNORED = {"created", "wall_s"}
"""Attributes and datasets that measure the run, not compute it (compared nowhere)."""


def run(checkout: Path, out: Path) -> int:
    """Each config's archive from ``checkout`` into ``out``; the configs that failed."""
    out.mkdir(parents=True, exist_ok=True)
    configs = sorted(CONFIGS.glob("*.toml"))
    missing = [c.stem for c in configs if c.stem not in BUDGETS]
    if missing:
        print(f"error: no budget for {', '.join(missing)} (add them to BUDGETS)",
              file=sys.stderr)
        return 2
    # run from the checkout: ``python -m`` puts the working directory first on sys.path,
    # ahead of PYTHONPATH, so from another checkout it would import that one's camopt
    checkout, out = checkout.resolve(), out.resolve()
    env = {**os.environ, "PYTHONPATH": str(checkout)}
    failed = 0
    for config in configs:
        sets = [a for s in BUDGETS[config.stem] for a in ("--set", s)]
        cmd = [sys.executable, "-m", "camopt", "run", str(config), "--out",
               str(out / f"{config.stem}.h5"), "--force", "--quiet",
               "--repeats", str(REPEATS), *sets]
        start = time.perf_counter()
        done = subprocess.run(cmd, env=env, cwd=checkout, capture_output=True, text=True,
                              check=False)
        took = time.perf_counter() - start
        print(f"{config.stem:28s} rc={done.returncode} {took:6.1f} s", flush=True)
        if done.returncode not in (0, 1):   # 1: ran, target not met
            failed += 1
            print(done.stderr.strip()[-2000:], file=sys.stderr)
    return 1 if failed else 0


def _numbers_differ(a: object, b: object, rtol: float) -> float | None:
    """The largest relative difference of two JSON values' numbers, None when the
    structure or any text differs (inf when so)."""
    if isinstance(a, dict) and isinstance(b, dict):
        if list(a) != list(b):  # the keys and their order (the bytes scripts read)
            return math.inf
        diffs = [_numbers_differ(a[k], b[k], rtol) for k in a if k not in IGNORED]
        return max((d for d in diffs if d is not None), default=0.0)
    if isinstance(a, list) and isinstance(b, list):
        if len(a) != len(b):
            return math.inf
        return max((_numbers_differ(x, y, rtol) or 0.0 for x, y in zip(a, b)), default=0.0)
    if isinstance(a, (int, float)) and isinstance(b, (int, float)) \
            and not isinstance(a, bool) and not isinstance(b, bool):
        return _rel(np.asarray(a, float), np.asarray(b, float))
    return 0.0 if a == b else math.inf


def _rel(a: np.ndarray, b: np.ndarray) -> float:
    """Largest |a - b| / max(|a|, |b|, tiny), NaN matching NaN and inf matching inf."""
    if a.shape != b.shape:
        return math.inf
    if a.size == 0:
        return 0.0
    a, b = a.astype(float).ravel(), b.astype(float).ravel()
    same = (a == b) | (np.isnan(a) & np.isnan(b))
    if same.all():
        return 0.0
    scale = np.maximum(np.maximum(abs(a), abs(b)), 1e-300)
    with np.errstate(invalid="ignore"):
        rel = np.where(same, 0.0, abs(a - b) / scale)
    return float(np.nan_to_num(rel, nan=math.inf).max())


def _value_diff(a: object, b: object, rtol: float, dirs: tuple[str, str]) -> float:
    """The relative difference of two HDF5 values (attribute or dataset content), each
    archive's directory in its text (``camopt tolerance <archive>``) read as the same."""
    if isinstance(a, bytes):
        a = a.decode()
    if isinstance(b, bytes):
        b = b.decode()
    if isinstance(a, str):
        a = a.replace(dirs[0], "<out>")
    if isinstance(b, str):
        b = b.replace(dirs[1], "<out>")
    if isinstance(a, str) and isinstance(b, str):
        if a == b:
            return 0.0
        try:
            ja, jb = json.loads(a), json.loads(b)
        except ValueError:
            return math.inf
        return _numbers_differ(ja, jb, rtol) or 0.0
    aa, bb = np.asarray(a), np.asarray(b)
    if aa.dtype.kind in "OSU" or bb.dtype.kind in "OSU":
        return 0.0 if aa.shape == bb.shape and (aa == bb).all() else math.inf
    return _rel(aa, bb)


def compare_files(a: Path, b: Path, rtol: float) -> list[str]:
    """What differs between two archives beyond ``rtol`` (empty: the same)."""
    found: list[str] = []
    worst = 0.0
    dirs = (str(a.resolve().parent), str(b.resolve().parent))
    with h5py.File(a, "r") as fa, h5py.File(b, "r") as fb:
        def items(f: h5py.File) -> dict[str, object]:
            out: dict[str, object] = {}

            def visit(name: str, obj: object) -> None:
                out[name] = obj
            f.visititems(visit)
            return out
        na, nb = items(fa), items(fb)
        for name in sorted(set(na) ^ set(nb)):
            found.append(f"{name}: in one archive only")
        for name in ["", *sorted(set(na) & set(nb))]:
            if name.rsplit("/", 1)[-1] in IGNORED:
                continue
            oa, ob = (fa, fb) if name == "" else (fa[name], fb[name])
            keys_a, keys_b = set(oa.attrs) - IGNORED, set(ob.attrs) - IGNORED
            for key in sorted(keys_a ^ keys_b):
                found.append(f"{name or '/'}@{key}: in one archive only")
            for key in sorted(keys_a & keys_b):
                d = _value_diff(oa.attrs[key], ob.attrs[key], rtol, dirs)
                worst = max(worst, d)
                if d > rtol:
                    found.append(f"{name or '/'}@{key}: differs (rel {d:.3g})")
            if isinstance(oa, h5py.Dataset):
                d = _value_diff(oa[()], ob[()], rtol, dirs)
                worst = max(worst, d)
                if d > rtol:
                    found.append(f"{name}: differs (rel {d:.3g})")
    if not found and worst > 0:
        found.append(f"(same within rtol; largest relative difference {worst:.3g})")
    return found


def compare(dir_a: Path, dir_b: Path, rtol: float) -> int:
    """Every archive of ``dir_a`` against its namesake in ``dir_b``."""
    names = sorted({p.name for p in dir_a.glob("*.h5")} | {p.name for p in dir_b.glob("*.h5")})
    bad = 0
    for name in names:
        a, b = dir_a / name, dir_b / name
        if not (a.exists() and b.exists()):
            print(f"{name}: in one directory only")
            bad += 1
            continue
        found = compare_files(a, b, rtol)
        real = [f for f in found if not f.startswith("(")]
        bad += bool(real)
        print(f"{name:34s} {'DIFFERS' if real else 'identical'} {' '.join(found[:1])}")
        for line in real[:20]:
            print(f"    {line}")
    print(f"{len(names) - bad} of {len(names)} archives identical (rtol {rtol:g}, "
          f"ignoring {', '.join(sorted(IGNORED))})")
    return 1 if bad else 0


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    sub = parser.add_subparsers(dest="command", required=True)
    r = sub.add_parser("run")
    r.add_argument("checkout", type=Path)
    r.add_argument("out", type=Path)
    c = sub.add_parser("compare")
    c.add_argument("a", type=Path)
    c.add_argument("b", type=Path)
    c.add_argument("--rtol", type=float, default=1e-12)
    args = parser.parse_args()
    if args.command == "run":
        return run(args.checkout, args.out)
    return compare(args.a, args.b, args.rtol)


if __name__ == "__main__":
    sys.exit(main())
