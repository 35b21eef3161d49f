"""Hostile corpus of issue #23 (beyond its list): planted FIFOs, symlinks and existing files
at every output name, archives reaching outside themselves, forged journals, --force onto
inputs, a full disk (RLIMIT_FSIZE) under every writer, signals at random moments (early
ones into every writing command too), huge
arguments. Each call is a subprocess with a 40 s limit. Counted: calls, exit codes, hangs
(over the limit), tracebacks (a traceback, camopt's internal-error line, or more than one
error line), losses (a file outside the output folder changed, an existing file replaced
without --force, a temporary or lock file left, finished work missing after a signal).

    python scripts/corpus_faults.py        # prints the counts as JSON, then each problem
    python scripts/corpus_faults.py 'journal fifo' forged-virtual   # only the calls whose
        # description (arguments and [fixture], as printed with a problem) holds one of these
"""
import hashlib
import json
import os
import random
import resource
import shutil
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import h5py

W = Path(tempfile.mkdtemp(prefix="camopt-fault-corpus-"))
os.chdir(W)
C = Path(__file__).resolve().parents[1] / "configs"
CAM = [sys.executable, "-m", "camopt"]
FS, DE = str(C / "fast_switch.toml"), str(C / "fast_switch_de.toml")
TINY = ["--set", "solver.generations=3", "--set", "solver.population=8",
        "--set", "solver.polish.maxiter=5"]
LIMIT = 40
ONLY = sys.argv[1:]
rng = random.Random(23)
stats = {"calls": 0, "exit0": 0, "exit2": 0, "exit130": 0, "other": 0, "hangs": 0,
         "tracebacks": 0, "losses": 0}
problems: list[str] = []

subprocess.run(CAM + ["run", FS, "--out", "run.h5", "--quiet"], check=True,
               stdout=subprocess.DEVNULL)
subprocess.run(CAM + ["run", str(C / "emb.toml"), "--out", "emb.h5", "--quiet", "--repeats", "2",
                      "--set", "solver.iterations=3", "--set", "solver.particles=6",
                      "--set", "solver.polish.evaluations=48"], check=True,
               stdout=subprocess.DEVNULL)
subprocess.run(CAM + ["sweep", DE, "--out", "sweep.h5", "--seeds", "0:3", "--jobs", "1",
                      "--quiet", *TINY], check=True, stdout=subprocess.DEVNULL)
OUTSIDE = W / "outside.txt"  # stands for any file outside the output folders
OUTSIDE.write_text("precious")


def digest(path: Path, skip: tuple[str, ...] = ()) -> str:
    """Content of every regular file under ``path`` (links and FIFOs by their kind) but
    those whose names match a pattern of ``skip``."""
    h = hashlib.sha256()
    for p in sorted(path.rglob("*")):
        if any(p.match(pattern) for pattern in skip):
            continue
        if p.is_symlink() or not (p.is_file() or p.is_dir()):
            h.update(f"{p}:special".encode())
        elif p.is_file():
            h.update(str(p).encode() + p.read_bytes())
    return h.hexdigest()


def fsize_limit():
    signal.signal(signal.SIGXFSZ, signal.SIG_IGN)
    resource.setrlimit(resource.RLIMIT_FSIZE, (3000, 3000))


def call(args, folder: Path | None = None, keep: list[Path] = (), limit_fs=False,
         signal_after: float | None = None, expect_archive: Path | None = None,
         fixture: str = "", may_change: tuple[str, ...] = ()):
    """Run one call; count it. ``keep``: files that must be unchanged afterwards;
    ``fixture``: what was planted for it, named in every problem it reports;
    ``may_change``: name patterns in ``inputs/`` this call may write (its own outputs,
    when its output folder is ``inputs/``): every other file there must stay as it was."""
    args = [str(a) for a in args]
    what = f"{args}" + (f" [{fixture}]" if fixture else "")
    if ONLY and not any(s in what for s in ONLY):
        return "skipped", "", 0.0
    before = {p: (p.read_bytes() if p.is_file() and not p.is_symlink() else None)
              for p in [OUTSIDE, *keep]}
    outside_before = digest(W / "inputs", may_change)
    t0 = time.time()
    proc = subprocess.Popen(CAM + args, stdin=subprocess.DEVNULL,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            preexec_fn=fsize_limit if limit_fs else None)
    if signal_after is not None:
        time.sleep(signal_after)
        if proc.poll() is None:
            proc.send_signal(rng.choice([signal.SIGINT, signal.SIGTERM]))
            if rng.random() < 0.5:  # a second Ctrl-C soon after the first
                time.sleep(rng.uniform(0.0, 0.3))
                if proc.poll() is None:
                    proc.send_signal(signal.SIGINT)
    try:
        _, err = proc.communicate(timeout=LIMIT)
        code = proc.returncode
    except subprocess.TimeoutExpired:
        proc.kill()
        _, err = proc.communicate()
        code = "hang"
        problems.append(f"hang: {what}: over {LIMIT} s: {err[-200:]}")
    stats["calls"] += 1
    key = {0: "exit0", 2: "exit2", 130: "exit130", "hang": "hangs"}.get(code, "other")
    stats[key] += 1
    lines = [ln for ln in err.splitlines() if ln.startswith("error:")]
    if "Traceback" in err or "internal error" in err or len(lines) > 1 or (
            code == 2 and not lines and "Usage:" not in err):
        stats["tracebacks"] += 1
        problems.append(f"traceback: {what}: {err[-300:]}")
    lost = [str(p) for p, data in before.items()
            if data is not None and (not p.is_file() or p.read_bytes() != data)]
    if digest(W / "inputs", may_change) != outside_before:
        lost.append("inputs/")
    if folder is not None and folder.is_dir():
        lost += [p.name for p in folder.iterdir() if p.name.endswith((".tmp", ".lock"))]
        if limit_fs:  # a full disk: any file written must be complete (readable) or absent
            lost += [p.name for p in folder.iterdir() if p.suffix == ".csv"
                     and p.stat().st_size >= 3000]
    if expect_archive is not None and code == 130 and "kept" in err and not expect_archive.exists():
        lost.append("archive said kept but missing")
    if lost:
        stats["losses"] += 1
        problems.append(f"loss: {what}: {lost} (exit {code}) {err[-200:]}")
    if key == "other":
        problems.append(f"exit {code}: {what}: {err[-200:]}")
    return code, err, time.time() - t0


inputs = W / "inputs"
inputs.mkdir()
for name in ("run.h5", "emb.h5", "sweep.h5"):
    shutil.copy(name, inputs / name)
RUN, EMB, SWEEP = inputs / "run.h5", inputs / "emb.h5", inputs / "sweep.h5"


def fresh(name: str) -> Path:
    d = W / name
    if d.exists():
        shutil.rmtree(d)
    d.mkdir()
    return d


# 1. planted FIFOs, symlinks and existing files at every output name, with/without --force
OUTPUTS = {  # command -> (args with {out} folder/file, the names it writes)
    "export-csv": (["export", EMB, "--out", "{d}"], ["emb-summary.csv", "emb-curves-1.csv",
                                                      "emb-profile.txt"]),
    "export-json": (["export", EMB, "--format", "json", "--out", "{d}"], ["emb.json"]),
    "export-dxf": (["export", EMB, "--format", "dxf", "--out", "{d}"], ["emb.dxf"]),
    "plot": (["plot", RUN, "--out", "{d}"], ["run-convergence.png"]),
    "report": (["report", RUN, "--out", "{d}/r.html"], ["r.html"]),
    "init": (["init", "fast_switch", "--out", "{d}/c.toml"], ["c.toml"]),
    "run": (["run", FS, "--out", "{d}/a.h5", "--quiet"], ["a.h5"]),
    "tolerance": (["tolerance", RUN, "--samples", "50", "--out", "{d}/t.h5"], ["t.h5"]),
    "tolerance-plot": (["tolerance", RUN, "--samples", "50", "--plot", "{d}"],
                       ["run-tolerance-yield.png"]),
    "sweep": (["sweep", DE, "--out", "{d}/s.h5", "--seeds", "0:1", "--jobs", "1", "--quiet",
               *TINY], ["s.h5"]),
}
for label, (template, names) in OUTPUTS.items():
    for plant in ("fifo", "symlink", "existing", "dangling", "directory"):
        for force in ([], ["--force"]):
            d = fresh(f"out-{label}")
            target = d / rng.choice(names)
            if plant == "fifo":
                os.mkfifo(target)
            elif plant == "symlink":
                target.symlink_to(OUTSIDE)
            elif plant == "existing":
                target.write_text("mine")
            elif plant == "dangling":
                target.symlink_to(W / "nowhere" / "x")
            else:
                target.mkdir()
            keep = [target] if plant == "existing" and not force else []
            call([a.format(d=d) if isinstance(a, str) else a for a in template] + force,
                 folder=d, keep=keep, fixture=f"{plant} at {target.name}"
                 + (" --force" if force else ""))

# 2. --force onto the command's own input, and into the folder holding it. The rule
# (docs/reliability.md section 6): --force replaces only the output names the command
# announces, never one of its inputs; so each call's inputs must stay as they were, and
# so must every other file in inputs/ but the call's own output names (``may_change``).
CASE = inputs / "case.toml"
(inputs / "notes.txt").write_text("a file of the user's beside the inputs")
for old in ("run-convergence.png", "run-summary.csv", "run.json"):  # --force replaces these
    (inputs / old).write_text("an earlier output")
for args, own, may in (
        (["tolerance", RUN, "--out", RUN, "--force", "--samples", "20"], [RUN], ()),
        (["report", RUN, "--out", RUN, "--force"], [RUN], ()),
        (["run", CASE, "--out", CASE, "--force"], [CASE], ()),
        (["sweep", CASE, "--out", CASE, "--force", "--seeds", "0:1"], [CASE], ()),
        (["init", "fast_switch", "--out", CASE, "--force"], [], ("case.toml",)),  # no input
        (["plot", RUN, "--out", inputs, "--force"], [RUN], ("run-*.png",)),
        (["export", RUN, "--out", inputs, "--force"], [RUN], ("run-*.csv",)),
        (["export", RUN, "--format", "json", "--out", inputs, "--force"], [RUN],
         ("run.json",))):
    if not CASE.exists():
        shutil.copy(FS, CASE)
    call(args, keep=own, may_change=may, fixture="--force in the input's folder")
for p in inputs.iterdir():  # back to the three archives
    if p not in (RUN, EMB, SWEEP):
        p.unlink()

# 3. archives that reach outside themselves or are forged
fifo = W / "fifo"
os.mkfifo(fifo)
(W / "raw.bin").write_bytes(b"\0" * 80)


def forged(kind: str) -> Path:
    p = W / f"forged-{kind}.h5"
    shutil.copy(RUN, p)
    with h5py.File(p, "a") as f:
        if kind == "external-fifo":
            f["analysis/evil"] = h5py.ExternalLink(str(fifo), "/x")
        elif kind == "external-dev-zero":
            f["best/evil"] = h5py.ExternalLink("/dev/zero", "/x")
        elif kind == "external-self":
            f["analysis/loop"] = h5py.ExternalLink(str(p), "/analysis/loop")
        elif kind == "virtual":
            layout = h5py.VirtualLayout(shape=(10,), dtype="f8")
            layout[:] = h5py.VirtualSource(str(fifo), "x", shape=(10,))
            f["analysis"].create_virtual_dataset("v", layout)
        elif kind == "external-storage":
            f["analysis"].create_dataset("e", shape=(10,), dtype="f8",
                                         external=[(str(fifo), 0, 80)])
        elif kind == "soft-loop":
            f["analysis/a"] = h5py.SoftLink("/analysis/b")
            f["analysis/b"] = h5py.SoftLink("/analysis/a")
        elif kind == "dangling-soft":
            f["analysis/x"] = h5py.SoftLink("/nowhere")
        elif kind == "best-x-link":
            del f["best/x"]
            f["best/x"] = h5py.ExternalLink(str(fifo), "/x")
    return p


READERS = [["show", "{a}"], ["compare", "{a}", RUN], ["export", "{a}", "--out", "{d}"],
           ["plot", "{a}", "--out", "{d}"], ["report", "{a}", "--out", "{d}/r.html"],
           ["tolerance", "{a}", "--samples", "30"]]
for kind in ("external-fifo", "external-dev-zero", "external-self", "virtual",
             "external-storage", "soft-loop", "dangling-soft", "best-x-link"):
    a = forged(kind)
    for reader in READERS:
        d = fresh("out-readers")
        call([x.format(a=a, d=d) if isinstance(x, str) else x for x in reader], folder=d,
             fixture=f"archive {kind}")

# 4. forged journals beside a sweep archive, through every reader and --resume
ROW = {"point": 0, "seed": 1, "objective": 1.0, "feasible": True, "success": True, "nfev": 1,
       "nit": 1, "wall_s": 0.1, "converged_nit": 1, "nfev_to_target": -1, "x": [1.0],
       "history": {}}
JOURNALS = {
    "fifo": None, "directory": None, "symlink": None,
    "foreign": json.dumps(ROW) + "\n",
    "point-true": json.dumps({**ROW, "point": True}) + "\n",
    "wrong-id": json.dumps({**ROW, "sweep": "0" * 16}) + "\n",
    "garbage": "\x00\xff{not json\n",
    "nan-strings": json.dumps({**ROW, "objective": "nan"}) + "\n",
    "deep": "[" * 100000 + "\n",
    "cut": json.dumps(ROW)[:30],
    "empty": "",
}
for kind, text in JOURNALS.items():
    for reader in (["show", "{a}"], ["compare", "{a}"], ["report", "{a}", "--out", "{d}/r.html"],
                   ["plot", "{a}", "--out", "{d}"], ["sweep", "--resume", "{a}", "--jobs", "1",
                                                      "--quiet"]):
        d = fresh("out-journal")
        a = d / "s.h5"
        shutil.copy(SWEEP, a)
        journal = d / ".s.h5.cells"
        if kind == "fifo":
            os.mkfifo(journal)
        elif kind == "directory":
            journal.mkdir()
        elif kind == "symlink":
            journal.symlink_to(OUTSIDE)
        else:
            journal.write_text(text)
        call([x.format(a=a, d=d) for x in reader], keep=[OUTSIDE], fixture=f"journal {kind}")

# 5. a full disk under every writer (the kernel's EFBIG past 3,000 bytes)
for label, (template, _) in OUTPUTS.items():
    d = fresh(f"full-{label}")
    call([a.format(d=d) if isinstance(a, str) else a for a in template], folder=d,
         limit_fs=True, fixture="RLIMIT_FSIZE 3000")

# 6. signals at random moments (a second Ctrl-C half the time)
for i in range(12):
    d = fresh("signals")
    if i % 3 == 2:
        args = ["sweep", DE, "--out", d / "s.h5", "--seeds", "0:6", "--jobs", str(1 + i % 2),
                "--quiet", *TINY]
    else:
        args = ["run", DE, "--out", d / "a.h5", "--quiet", "--repeats", "6",
                "--jobs", str(1 + i % 2), *TINY]
    code, err, _ = call(args, folder=d, signal_after=rng.uniform(1.5, 6.0),
                        expect_archive=d / ("s.h5" if i % 3 == 2 else "a.h5"),
                        fixture=f"signal {i}")
    for p in d.glob("*.h5"):  # what a signal left must be readable
        r = subprocess.run(CAM + ["show", str(p)], capture_output=True, text=True, timeout=LIMIT)
        if r.returncode != 0:
            stats["losses"] += 1
            problems.append(f"loss: unreadable after signal: {p}: {r.stderr[-200:]}")

# 6b. signals early (0.1-1.5 s: while Python and the command's modules load, h5py reads the
# input, a chunk of draws runs) into every writing command, one signal each: five defects
# were found here on 29 Nov 2026 that section 6's later signals into run and sweep missed
EARLY = [["tolerance", RUN, "--samples", "200000", "--out", "{d}/t.h5", "--quiet"],
         ["report", RUN, "--out", "{d}/r.html"], ["plot", RUN, "--out", "{d}"],
         ["export", RUN, "--out", "{d}"],
         ["run", DE, "--out", "{d}/a.h5", "--quiet", "--repeats", "6", *TINY]]
for i in range(20):
    d = fresh("early-signals")
    template = EARLY[i % len(EARLY)]
    call([a.format(d=d) if isinstance(a, str) else a for a in template], folder=d,
         signal_after=rng.uniform(0.1, 1.5), fixture=f"early signal {i}")

# 7. huge and odd arguments
for args in (["sweep", DE, "--seeds", "9" * 5000], ["sweep", DE, "--seeds", "0:" + "9" * 4400],
             ["sweep", DE, "--seeds", "٣"], ["sweep", DE, "--seeds", "0:3", "--jobs", "1000000",
                                              "--out", "huge-jobs.h5", "--quiet", *TINY],
             ["run", FS, "--jobs", "100000"], ["tolerance", RUN, "--samples", "9" * 5000],
             ["tolerance", RUN, "--seed", "9" * 5000, "--samples", "10"],
             ["run", FS, "--seed", "9" * 5000], ["run", FS, "--repeats", "9" * 5000],
             ["tolerance", RUN, "--vary", "x=±1e308%", "--samples", "10"],
             ["tolerance", RUN, "--plot", "/proc/camopt", "--samples", "10"],
             ["tolerance", RUN, "--plot", "/dev/null", "--samples", "10"],
             ["export", RUN, "--out", "/proc/camopt"], ["plot", RUN, "--out", "/dev/null"],
             ["report", RUN, "--out", "/dev/full", "--force"],
             ["sweep", DE, "--executor", "dask", "--scheduler", "tcp://127.0.0.1:1",
              "--seeds", "0:1", "--out", "dask.h5", "--quiet", *TINY]):
    d = W
    call(args, folder=None)
    for leftover in ("dask.h5", ".dask.h5.cells", ".dask.h5.lock"):
        if (W / leftover).exists():
            stats["losses"] += 1
            problems.append(f"loss: {leftover} left by an unreachable scheduler")

print(json.dumps(stats))
for p in problems:
    print(p)
shutil.rmtree(W, ignore_errors=True)
