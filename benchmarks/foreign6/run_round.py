#!/usr/bin/env python
"""usage: run_round.py ROUND.json OUTDIR  -- generate every case of a round, write OUTDIR/index.json."""
import json
import os
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import gen  # noqa: E402


def main():
    rnd, outdir = sys.argv[1], sys.argv[2]
    cases = json.load(open(rnd))
    os.makedirs(outdir, exist_ok=True)
    names = []
    for c in cases:
        t0 = time.time()
        t = gen.generate(c["case"], int(c["seed"]), c["name"], outdir, c.get("params", {}))
        names.append(c["name"])
        print(f"{c['name']}: {t['case']:20s} {t['family']:3s} {t['acceptable_verdicts']} "
              f"dDp(s=0.5)={t['dp_change_s05_pct']:+.1f}%  rows={t['protocol']['rows']}  {time.time()-t0:.2f}s",
              flush=True)
    with open(os.path.join(outdir, "index.json"), "w") as f:
        json.dump(names, f, indent=1)


if __name__ == "__main__":
    main()
