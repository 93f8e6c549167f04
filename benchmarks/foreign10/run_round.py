#!/usr/bin/env python3
"""usage: run_round.py ROUND.json OUTDIR [--jobs N]
Generates every run of a round with gen.py; prints one line per run:
name, case, ok/REFUSED, seconds."""
import argparse
import json
import os
import subprocess
import sys
import time
from concurrent.futures import ThreadPoolExecutor

HERE = os.path.dirname(os.path.abspath(__file__))


def one(e, outdir):
    cmd = [sys.executable, os.path.join(HERE, "gen.py"), e["case"], "--seed", str(e["seed"]),
           "--out", e["name"], "--outdir", outdir]
    for k, v in e.get("params", {}).items():
        cmd += ["--p", f"{k}={json.dumps(v)}"]
    t = time.time()
    p = subprocess.run(cmd, capture_output=True, text=True)
    dt = time.time() - t
    if p.returncode == 0:
        st = "ok"
    elif p.returncode == 2 and "REFUSED:" in p.stdout:
        st = "REFUSED " + p.stdout.strip().split("REFUSED:", 1)[1].strip()
    else:
        st = f"ERROR rc={p.returncode} {p.stderr.strip().splitlines()[-1] if p.stderr.strip() else ''}"
    return e["name"], e["case"], st, dt


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("round")
    ap.add_argument("outdir")
    ap.add_argument("--jobs", type=int, default=1)
    a = ap.parse_args()
    with open(a.round) as f:
        entries = json.load(f)
    os.makedirs(a.outdir, exist_ok=True)
    bad = 0
    with ThreadPoolExecutor(max_workers=max(1, a.jobs)) as ex:
        for name, case, st, dt in ex.map(lambda e: one(e, a.outdir), entries):
            print(f"{name}\t{case}\t{st}\t{dt:.1f}", flush=True)
            bad += not st.startswith("ok")
    sys.exit(1 if bad else 0)


if __name__ == "__main__":
    main()
