#!/usr/bin/env python3
"""run_round.py ROUND.json OUTDIR [--jobs N]"""
import argparse, json, os, subprocess, sys, time
from concurrent.futures import ThreadPoolExecutor
HERE = os.path.dirname(os.path.abspath(__file__))


def one(run, outdir):
    cmd = [sys.executable, os.path.join(HERE, "gen.py"), run["case"], "--seed", str(run["seed"]), "--out", run["name"], "--outdir", outdir]
    for k, v in run.get("params", {}).items():
        cmd += ["--p", f"{k}={json.dumps(v)}"]
    t0 = time.time()
    r = subprocess.run(cmd, capture_output=True, text=True)
    st = "ok" if r.returncode == 0 else ("REFUSED" if r.returncode == 2 else "ERROR")
    msg = (r.stdout.strip() + " " + r.stderr.strip()[-300:]).strip() if st != "ok" else ""
    return f"{run['name']} {run['case']} {st} {time.time()-t0:.1f}s {msg}"


def main():
    ap = argparse.ArgumentParser(); ap.add_argument("round"); ap.add_argument("outdir"); ap.add_argument("--jobs", type=int, default=1)
    a = ap.parse_args(); os.makedirs(a.outdir, exist_ok=True)
    runs = json.load(open(a.round))
    with ThreadPoolExecutor(a.jobs) as ex:
        for line in ex.map(lambda r: one(r, a.outdir), runs):
            print(line, flush=True)


if __name__ == "__main__":
    main()
