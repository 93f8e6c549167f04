#!/usr/bin/env python3
"""run_round.py ROUND.json OUTDIR: generate every run of a round."""
import json
import os
import subprocess
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))


def argv_for(run, outdir):
    a = [sys.executable, os.path.join(HERE, "gen.py"), run["case"], "--seed", str(run["seed"]),
         "--out", run["name"], "--outdir", outdir]
    for k, v in run.get("params", {}).items():
        a += ["--p", f"{k}={v if isinstance(v, str) else json.dumps(v)}"]
    return a


def main():
    rnd, outdir = sys.argv[1], sys.argv[2]
    runs = json.load(open(rnd))
    os.makedirs(outdir, exist_ok=True)
    bad = 0
    for run in runs:
        t0 = time.time()
        p = subprocess.run(argv_for(run, outdir), capture_output=True, text=True)
        dt = time.time() - t0
        msg = (p.stdout.strip() or p.stderr.strip()).splitlines()[-1:] or [""]
        state = {0: "ok", 2: "REFUSED"}.get(p.returncode, f"FAIL rc={p.returncode}")
        if p.returncode not in (0, 2):
            bad += 1
            print(p.stderr[-2000:])
        print(f"{run['name']:10s} {run['case']:10s} {state:8s} {dt:5.1f}s  {msg[0]}", flush=True)
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
