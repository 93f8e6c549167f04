#!/usr/bin/env python3
"""Generate every run of a round file once: run_round.py [round1.json] --outdir DIR.
Prints the time per run and any refused run (gen.py exit code 2)."""
import argparse
import json
import os
import subprocess
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("round", nargs="?", default=os.path.join(HERE, "round1.json"))
    ap.add_argument("--outdir", required=True)
    a = ap.parse_args()
    runs = json.load(open(a.round))
    bad = 0
    for r in runs:
        cmd = [sys.executable, os.path.join(HERE, "gen.py"), r["case"], "--seed", str(r["seed"]),
               "--out", r["name"], "--outdir", a.outdir]
        for k, v in r.get("params", {}).items():
            cmd += ["--p", "%s=%s" % (k, v)]
        t = time.time()
        p = subprocess.run(cmd, capture_output=True, text=True)
        dt = time.time() - t
        msg = (p.stdout.strip().splitlines() or [p.stderr.strip()[-300:]])[-1]
        print("%-9s %-22s seed %d rc=%d %5.1f s  %s" % (r["name"], r["case"], r["seed"], p.returncode, dt, msg))
        bad += p.returncode != 0
    print("%d runs, %d not generated" % (len(runs), bad))
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
