#!/usr/bin/env python
"""usage: run_round.py ROUND.json OUTDIR  -- generate every case of a round."""
import json
import os
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
import gen  # noqa: E402


def main():
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    rows = json.load(open(sys.argv[1]))
    outdir = sys.argv[2]
    os.makedirs(outdir, exist_ok=True)
    for row in rows:
        t0 = time.time()
        tr = gen.write_case(row["case"], int(row["seed"]), row["name"], outdir, dict(row["params"]))
        e = tr["effect"]
        print("%-9s %-16s %-4s %-40s dDp(s=.25/.5) %6.1f/%6.1f %%  dZ(.5) %6.1f %%  %.1fs"
              % (row["name"], row["case"], tr["family"], ",".join(tr["acceptable_verdicts"]),
                 e["dp_pct_s025"], e["dp_pct_s05"], e["Z_pct_s05"], time.time() - t0), flush=True)


if __name__ == "__main__":
    main()
