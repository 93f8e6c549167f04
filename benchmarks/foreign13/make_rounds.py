#!/usr/bin/env python3
"""Write foreign13's round1.json: 30 runs, seeds 1601-1630, names f13r1_01..30.
In family (16): 2 none, 2 of each slip-sinkage form, 4 terrain_mismatch,
2 stress_distribution, 2 terrain_drift.  Out of family (14): 7 causes x 2.
Soil alternates with the seed (odd: silty clay, even: loamy sand); every case
gets one run on each soil.  Refuses to overwrite an existing round1.json."""
import json
import os
import sys

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
OUT = os.path.join(HERE, "round1.json")
OUT_CAUSES = ["bead_slip", "smooth_tread", "snow_cover", "dry_crust", "curved_lane", "gnss_filter", "multipass"]


def main():
    if os.path.exists(OUT):
        print("round1.json exists; refusing to overwrite %s" % OUT)
        return 1
    half = (["none", "slip_sinkage_vasilev", "slip_sinkage_lyasko", "slip_sinkage_ding",
             "terrain_mismatch", "terrain_mismatch", "stress_distribution", "terrain_drift"] + OUT_CAUSES)
    assert len(half) == 15
    rng = np.random.default_rng(20131601)
    odd = [half[i] for i in rng.permutation(15)]     # seeds 1601, 1603, ... (silty clay)
    even = [half[i] for i in rng.permutation(15)]    # seeds 1602, 1604, ... (loamy sand)
    runs = []
    for i in range(30):
        seed = 1601 + i
        case = odd[i // 2] if i % 2 == 0 else even[i // 2]
        runs.append({"name": "f13r1_%02d" % (i + 1), "case": case, "seed": seed, "params": {}})
    with open(OUT, "w") as f:
        json.dump(runs, f, indent=1)
    print("wrote %s (%d runs)" % (OUT, len(runs)))
    return 0


if __name__ == "__main__":
    sys.exit(main())
