"""Fresh corpus of broken CLI calls and faults, as a new user would try them (subprocess,
60 s limit each): exit 0 or 2, one error line, no traceback, nothing outside the folder."""
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

W = Path(tempfile.mkdtemp(prefix="camopt-cli-corpus-"))
os.chdir(W)
C = str(Path(__file__).resolve().parents[1] / "configs")
CAM = [sys.executable, "-m", "camopt"]
(W / "out").mkdir()
run = W / "out/run.h5"
subprocess.run(CAM + ["run", f"{C}/fast_switch.toml", "--out", str(run), "--quiet"], check=True)
subprocess.run(CAM + ["sweep", f"{C}/fast_switch_de.toml", "--out", "out/sw.h5", "--seeds", "0:2", "--quiet", "--jobs", "1", "--set", "solver.generations=3", "--set", "solver.population=8"], check=True)
Path("notes.txt").write_text("hello")
Path("empty.toml").write_text("")
Path("bom.toml").write_bytes(b"\xef\xbb\xbf[case]\nkind='fast_switch'\n[solver]\nname='enumeration'\n")
Path("self.toml").write_text('extends = "self.toml"\n')
Path("dir.toml").mkdir()
Path("ro").mkdir(); os.chmod("ro", 0o500)
Path("afile").write_text("x")
os.mkfifo("fifo.toml")
os.symlink("/nonexistent/target", "dangling.toml")
FS, DE, EMB = f"{C}/fast_switch.toml", f"{C}/fast_switch_de.toml", f"{C}/emb.toml"
SM = ["--set", "solver.generations=3", "--set", "solver.population=8"]
calls = [
  ["run"], ["run", "missing.toml"], ["run", "dir.toml"], ["run", "fifo.toml"], ["run", "/dev/zero"],
  ["validate", "/dev/zero"], ["validate", "/dev/null"], ["validate", "empty.toml"], ["validate", "bom.toml"],
  ["validate", "self.toml"], ["validate", "dangling.toml"], ["validate", "notes.txt"], ["validate", str(run)],
  ["validate", FS, "--set", "case"], ["validate", FS, "--set", "=1"], ["validate", FS, "--set", "case.m3_kg=1e999"],
  ["validate", FS, "--set", "case.m3_kg=-0.0"], ["validate", FS, "--set", "solver.name=nope"],
  ["validate", FS, "--set", "case.kind=vcb"], ["validate", FS, "--set", "run.seed=-1"],
  ["validate", FS, "--set", "run.seed=1e3"], ["validate", FS, "--set", "run.name=\"\""],
  ["validate", FS, "--set", "run.name=\"a b\""], ["validate", FS, "--set", "run.name=\"..\""],
  ["validate", FS, "--set", "foo.bar=1"], ["validate", FS, "--set", "case.m3_kg.x=1"],
  ["validate", FS, "--set", "case.sf_bounds_mm=[5, 1]"], ["validate", FS, "--set", "case.sf_bounds_mm=[1]"],
  ["validate", FS, "--set", "case.sf_bounds_mm=\"x\""], ["validate", EMB, "--set", "case.weights=[nan]"],
  ["validate", EMB, "--set", "case.knot_density=[0.5, 1e300, 0.1]"], ["validate", EMB, "--set", "solver.polish={maxiter = 1e9}"],
  ["validate", EMB, "--set", "solver.polish={limits = {x = nan}}"], ["validate", EMB, "--set", "case.r_g_mm=0.02"],
  ["run", DE, "--seed", "99999999999999999999999999999999999999999", "--quiet", "--out", "out/a.h5"],
  ["run", DE, "--repeats", "0"], ["run", DE, "--out", "out", "--quiet"], ["run", DE, "--out", "/dev/null", "--force"],
  ["run", DE, "--out", "/dev/full", "--force"], ["run", DE, "--out", "afile/x.h5"], ["run", DE, "--out", "ro/x.h5"],
  ["run", DE, "--out", "nodir/x.h5"], ["run", DE, "--out", "x" * 300 + ".h5"], ["run", DE, "--out", "out/" + "é" * 120 + ".h5"],
  ["run", DE, "--out", "out/[/]x.h5", "--quiet", *SM], ["run", DE, "--out", "out/[red]x[/red].h5", *SM],
  ["run", FS, "--set", "run.name=../../escape"], ["run", FS, "--set", "run.name=/tmp/abs"],
  ["show"], ["show", "notes.txt"], ["show", "/dev/zero"], ["show", "missing.h5"], ["show", "out/sw.h5"], ["show", "dir.toml"],
  ["show", str(run), "--format", "xml"], ["compare", str(run)], ["compare", "out/sw.h5", str(run)], ["compare", str(run), "notes.txt"],
  ["plot", "notes.txt"], ["plot", str(run), "--out", "afile"], ["plot", str(run), "--out", "ro/p"], ["plot", str(run), "--out", "/dev/null/x"],
  ["export", str(run), "--out", "afile"], ["export", str(run), "--out", "ro"], ["export", "out/sw.h5"], ["export", str(run), "--format", "xls"],
  ["init", "nope"], ["init", "fast_switch", "--out", "nodir/x.toml"], ["init", "fast_switch", "--out", "ro/x.toml"],
  ["init", "fast_switch", "--out", "afile"], ["init", "fast_switch", "--out", "/dev/null", "--force"], ["init", "fast_switch", "--out", "dir.toml", "--force"],
  ["sweep"], ["sweep", DE, "--seeds", "0:99999999999"], ["sweep", DE, "--seeds", "5:2"], ["sweep", DE, "--seeds", "x"],
  ["sweep", DE, "--grid", "run.seed=1,2"], ["sweep", DE, "--grid", "solver.population=8,8"], ["sweep", DE, "--grid", "solver.population"],
  ["sweep", DE, "--grid", "solver.population=1,2"], ["sweep", DE, "--grid", "solver.population=" + ",".join(str(i + 8) for i in range(2000)), "--seeds", "0:100"],
  ["sweep", DE, "--executor", "dask", "--out", "out/d.h5"], ["sweep", DE, "--executor", "spark"],
  ["sweep", DE, "--executor", "dask", "--scheduler", "tcp://127.0.0.1:1", "--seeds", "0:1", "--out", "out/d2.h5", "--quiet", *SM],
  ["sweep", DE, "--executor", "dask", "--scheduler", "not an address", "--seeds", "0:1", "--out", "out/d3.h5", "--quiet", *SM],
  ["sweep", DE, "--check", "--out", "out/c.h5", "--seeds", "0:1", *SM], ["sweep", "--resume", "missing.h5"],
  ["sweep", "--resume", str(run)], ["sweep", "--resume", "notes.txt"], ["sweep", "--resume", "out/sw.h5", "--quiet", "--jobs", "1"],
  ["sweep", FS, "--resume", "out/sw.h5"], ["sweep", DE, "--jobs", "0"], ["nope"], ["--help"], ["solvers"],
]
stats = {"calls": 0, "exit0": 0, "exit2": 0, "bad": 0}
before_outside = set(os.listdir("/tmp"))
for args in calls:
    t0 = time.time()
    try:
        p = subprocess.run(CAM + args, capture_output=True, text=True, timeout=60, stdin=subprocess.DEVNULL)
        code, err = p.returncode, p.stderr
    except subprocess.TimeoutExpired:
        code, err = "timeout", ""
    stats["calls"] += 1
    lines = [l for l in err.splitlines() if l.strip() and not l.startswith("note:")]
    usage = code == 2 and ("Usage:" in err)  # click's own usage errors (boxed, no traceback)
    ok = code == 0 or usage or (code == 2 and len(lines) == 1 and lines[0].startswith("error: ") and "internal error" not in err)
    ok = ok and "Traceback" not in err
    stats["exit0" if code == 0 else "exit2" if code == 2 else "bad"] += 1
    if not ok:
        stats["bad"] += 1 if code in (0, 2) else 0
        print("BAD", args[:6], code, err[-400:], flush=True)
    mx = max(globals().get("mx", 0), time.time() - t0); globals()["mx"] = mx
    if time.time() - t0 > 20:
        print("slow", args[:6], round(time.time() - t0, 1), flush=True)
after_outside = set(os.listdir("/tmp")) - before_outside
print(json.dumps(stats), "slowest", round(mx, 1), "new in /tmp:", sorted(after_outside))
print("escape.h5?", [p for p in Path("/tmp").glob("escape*")], list(Path("/").glob("abs*")))
