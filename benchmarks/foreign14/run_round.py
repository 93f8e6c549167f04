#!/usr/bin/env python
"""run_round.py ROUND.json OUTDIR: generate every run of a round, one line per run."""
import json
import os
import subprocess
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))


def main():
    if len(sys.argv) != 3:
        print(__doc__)
        return 1
    rnd, outdir = sys.argv[1], sys.argv[2]
    if not os.path.isabs(rnd) and not os.path.exists(rnd):
        rnd = os.path.join(HERE, rnd)
    runs = json.load(open(rnd))
    os.makedirs(outdir, exist_ok=True)
    bad = 0
    for r in runs:
        cmd = [sys.executable, os.path.join(HERE, "gen.py"), r["case"], "--seed", str(r["seed"]),
               "--out", r["name"], "--outdir", outdir]
        for k, v in r.get("params", {}).items():
            cmd += ["--p", f"{k}={json.dumps(v)}"]
        t = time.time()
        pr = subprocess.run(cmd, capture_output=True, text=True)
        line = (pr.stdout.strip() or pr.stderr.strip().splitlines()[-1] if (pr.stdout or pr.stderr) else "")
        print(f"{r['name']} {r['case']:20s} rc={pr.returncode} {time.time() - t:5.1f}s  {line}", flush=True)
        bad += pr.returncode != 0
    print(f"{len(runs) - bad}/{len(runs)} runs generated")
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
