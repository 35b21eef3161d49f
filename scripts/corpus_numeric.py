"""Fresh corpus: every numeric field of the non-VCB configs set to hostile values."""
import json
import signal
import time
from pathlib import Path

from typer.testing import CliRunner

from camopt.cli import app

runner = CliRunner()
ROOT = Path(__file__).resolve().parents[1] / "configs"
SMALL = {"de_gr": ["solver.population=8", "solver.generations=3"],
         "pso": ["solver.particles=6", "solver.iterations=3"],
         "newton_pp": ["solver.starts=2"], "simplex": ["solver.starts=1", "solver.maxiter=50"],
         "enumeration": [], "evaluate": []}
VALUES = ["nan", "inf", "-inf", "1e308", "-1", "0", "1e11", "9223372036854775807", "1e-300",
          '"x"', "[1]", "{a=1}", "true", "0.14"]
class Timeout(Exception): pass
def alarm(*a): raise Timeout()
signal.signal(signal.SIGALRM, alarm)
stats = {"calls": 0, "exit0": 0, "exit2": 0, "bad": 0}
bad = []
import tempfile

out = Path(tempfile.mkdtemp(prefix="camopt-corpus-"))
files = [f for f in sorted(ROOT.glob("*.toml")) if not f.name.startswith("vcb")]
for f in files:
    from camopt.engine.driver import load as _load
    data = _load(f).data
    solver = data["solver"]["name"]
    keys = [f"case.{k}" for k, v in data["case"].items() if isinstance(v, (int, float)) and not isinstance(v, bool)]
    keys += [f"solver.{k}" for k, v in data["solver"].items() if isinstance(v, (int, float)) and not isinstance(v, bool)]
    keys += [f"run.{k}" for k, v in data.get("run", {}).items() if isinstance(v, (int, float)) and not isinstance(v, bool)]
    for key in keys:
        for val in VALUES:
            sets = []
            for s in SMALL[solver]:
                if s.split("=")[0] != key:
                    sets += ["--set", s]
            if key != "run.repeats":
                sets += ["--set", "run.repeats=1"]
            args = ["run", str(f), "--out", str(out / "r.h5"), "--force", "--quiet",
                    "--set", f"{key}={val}", *sets]
            signal.alarm(60)
            t0 = time.time()
            try:
                r = runner.invoke(app, args)
                code, err, exc = r.exit_code, r.stderr, r.exception
            except Timeout:
                code, err, exc = "timeout", "", None
            signal.alarm(0)
            stats["calls"] += 1
            lines = [l for l in err.splitlines() if l.strip() and not l.startswith("note:")]
            ok = code in (0, 2) and (code == 0 or (len(lines) == 1 and lines[0].startswith("error: ") and "internal error" not in lines[0]))
            if isinstance(exc, Exception) and not isinstance(exc, SystemExit): ok = False
            if ok: stats[f"exit{code}"] += 1
            else:
                stats["bad"] += 1; bad.append((f.name, key, val, code, err[-300:], repr(exc)))
            if time.time() - t0 > 20: print("slow", f.name, key, val, time.time() - t0, flush=True)
print(json.dumps(stats))
for b in bad: print(b)
