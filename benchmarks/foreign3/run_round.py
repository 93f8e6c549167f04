#!/usr/bin/env python3
"""Generate every run of a round file:  python run_round.py round1.json OUTDIR
(one process per run, sequential; prints the wall time per run)."""
import json
import os
import subprocess
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))


def main(argv):
    rounds, outdir = argv[0], argv[1]
    runs = json.load(open(rounds))
    os.makedirs(outdir, exist_ok=True)
    rows = []
    for r in runs:
        cmd = [sys.executable, os.path.join(HERE, "gen.py"), r["case"], "--seed", str(r["seed"]),
               "--out", r["name"], "--outdir", outdir, "--format", r["format"]]
        for k, v in r.get("params", {}).items():
            cmd += ["--p", f"{k}={json.dumps(v)}"]
        t0 = time.time()
        p = subprocess.run(cmd, capture_output=True, text=True)
        wall = time.time() - t0
        ok = p.returncode == 0
        rows.append({"name": r["name"], "case": r["case"], "seed": r["seed"], "format": r["format"],
                     "ok": ok, "wall_s": round(wall, 2)})
        print(f"{r['name']:8s} {r['case']:16s} {r['format']:4s} {'ok ' if ok else 'ERR'} {wall:6.1f} s  "
              f"{p.stdout.strip().splitlines()[-1] if ok else p.stderr[-500:]}", flush=True)
    json.dump(rows, open(os.path.join(outdir, "walltimes.json"), "w"), indent=1)
    return 0 if all(r["ok"] for r in rows) else 1


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
