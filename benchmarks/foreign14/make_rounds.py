#!/usr/bin/env python
"""Write roundK.json (30 runs f14rK_01..f14rK_30, seeds 1701-1730 for round 1, 1731-1760 for round 2,
cases shuffled, per-run sizes drawn and written into params).  Refuses to overwrite an existing round file.

    python make_rounds.py [round1.json|round2.json]

Round 1 was written by the generator's author before any run; round 2 by the project after round 1 was
scored and before any of its runs was generated (the same plan, fresh seeds and a fresh shuffle)."""
import json
import os
import sys

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
import gen  # noqa: E402

PLAN = (["none"] * 2 + ["vasilev"] * 2 + ["lyasko"] * 2 + ["ding"] * 2 + ["terrain_mismatch"] * 3
        + ["stress_distribution"] * 2 + ["terrain_drift"] * 3
        + [c for c in gen.OUT_CASES for _ in range(2)])
# the knobs that define a run's size and setting (the rest is drawn by gen.py from the seed)
SIZE_KEYS = ["soil", "fmt", "duration_s", "gnss_latency_s", "H", "m1", "m2", "n1", "mismatch_sd",
             "a1", "a2", "drift_sd", "runout_m", "runout_phase_deg", "t_flip_frac", "drag_n_per_mps",
             "clip_frac", "n_links", "f_link_n", "beta", "sig_d_kpa", "depth_m", "patches_m"]


def main():
    fname = sys.argv[1] if len(sys.argv) > 1 else "round1.json"
    rnd = {"round1.json": 1, "round2.json": 2}[fname]
    out = os.path.join(HERE, fname)
    if os.path.exists(out):
        print(f"refusing to overwrite {out}")
        return 1
    assert len(PLAN) == 30
    rng = np.random.default_rng(14_2026 + (rnd - 1))
    cases = list(rng.permutation(PLAN))
    runs = []
    for i, case in enumerate(cases):
        seed = 1701 + 30 * (rnd - 1) + i
        p = gen.draw_params(str(case), seed, {})
        params = {k: p[k] for k in SIZE_KEYS if k in p}
        runs.append({"name": f"f14r{rnd}_{i + 1:02d}", "case": str(case), "seed": seed, "params": params})
    with open(out, "w") as f:
        json.dump(runs, f, indent=1)
    print(f"wrote {out}: {len(runs)} runs")
    return 0


if __name__ == "__main__":
    sys.exit(main())
