#!/usr/bin/env python3
"""run_round.py ROUND.json OUTDIR: generate every run of a round."""
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
    runs = json.load(open(sys.argv[1]))
    outdir = sys.argv[2]
    os.makedirs(outdir, exist_ok=True)
    failed = 0
    for r in runs:
        t = time.time()
        try:
            path, truth = gen.generate(r["case"], int(r["seed"]), r["name"], outdir, dict(r.get("params", {})))
            print("%-10s %-18s %5.1f s  %s  accept=%s" % (r["name"], r["case"], time.time() - t, path,
                                                          truth["acceptable_verdicts"]))
        except gen.Refused:
            failed += 1
            print("%-10s %-18s REFUSED" % (r["name"], r["case"]))
    sys.exit(1 if failed else 0)


if __name__ == "__main__":
    main()
