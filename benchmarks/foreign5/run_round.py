#!/usr/bin/env python
"""Generate a round: run_round.py ROUND.json OUTDIR [--jobs N]

Writes OUTDIR/<name>.<fmt>, OUTDIR/<name>_truth.json for every run and
OUTDIR/index.json (name, log, truth, acceptable verdicts, fit command).
"""
import argparse
import json
import os
import subprocess
import sys
from concurrent.futures import ThreadPoolExecutor

HERE = os.path.dirname(os.path.abspath(__file__))


def one(run, outdir):
    cmd = [sys.executable, os.path.join(HERE, "gen.py"), run["case"], "--seed", str(run["seed"]),
           "--out", run["name"], "--outdir", outdir, "--format", run["format"]]
    for k, v in run.get("params", {}).items():
        cmd += ["--p", f"{k}={v}"]
    p = subprocess.run(cmd, capture_output=True, text=True)
    return run, p.returncode, (p.stdout + p.stderr).strip()


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("round")
    ap.add_argument("outdir")
    ap.add_argument("--jobs", type=int, default=1)
    a = ap.parse_args()
    runs = json.load(open(a.round))
    os.makedirs(a.outdir, exist_ok=True)
    index, failed = [], 0
    with ThreadPoolExecutor(max_workers=max(1, a.jobs)) as ex:
        for run, rc, out in ex.map(lambda r: one(r, a.outdir), runs):
            print(f"[{'ok' if rc == 0 else 'FAIL'}] {run['name']}: {out.splitlines()[-1] if out else ''}", flush=True)
            if rc != 0:
                failed += 1
                continue
            tpath = os.path.join(a.outdir, f"{run['name']}_truth.json")
            t = json.load(open(tpath))
            index.append(dict(name=run["name"], log=f"{run['name']}.{run['format']}", truth=os.path.basename(tpath),
                              case=run["case"], effect=t["effect"], acceptable_verdicts=t["acceptable_verdicts"],
                              dp_change_s05_pct=t["dp_change_s05_pct"], fit_command=t["fit_command"]))
    json.dump(index, open(os.path.join(a.outdir, "index.json"), "w"), indent=1)
    print(f"{len(index)} runs written, {failed} failed")
    sys.exit(1 if failed else 0)


if __name__ == "__main__":
    main()
