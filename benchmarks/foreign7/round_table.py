#!/usr/bin/env python
"""usage: round_table.py ROUND.json OUTDIR -- markdown table of a generated round
(reads OUTDIR/NAME_truth.json)."""
import json
import os
import sys


def main():
    rows = json.load(open(sys.argv[1]))
    outdir = sys.argv[2]
    print("| name | case | soil | params | family | acceptable | case dDp s=0.25 / 0.5 (%) | case dT s=0.5 (%) | case dZ s=0.5 (%) | bin-vs-lab dDp s=0.5 (%) |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    for row in rows:
        tr = json.load(open(os.path.join(outdir, row["name"] + "_truth.json")))
        e = tr["effect"]
        p = {k: v for k, v in row["params"].items() if k != "soil"}
        print("| %s | %s | %s | `%s` | %s | %s | %+.1f / %+.1f | %+.1f | %+.1f | %+.1f |" % (
            row["name"], row["case"], row["params"].get("soil", "sand"), json.dumps(p), tr["family"],
            ", ".join(tr["acceptable_verdicts"]), e["case_dp_pct_s025"], e["case_dp_pct_s05"], e["case_T_pct_s05"],
            e["case_Z_pct_s05"], e["bin_offset_dp_pct_s05"]))


if __name__ == "__main__":
    main()
