#!/usr/bin/env python3
"""Write round1.json: 30 runs, sizes chosen before anything was generated; and round2.json: 30 more on
seeds 1231-1260, the same cases on the other soil and format at other sizes, chosen by the project after
round 1 was scored and before any round-2 run was generated."""
import json
import os

R = [
    # in family (16)
    ("none", {"soil": "loam", "fmt": "log"}),
    ("none", {"soil": "sand", "fmt": "blf"}),
    ("vasilev", {"soil": "sand", "fmt": "asc", "H": 0.015}),
    ("vasilev", {"soil": "loam", "fmt": "blf", "H": 0.05}),
    ("lyasko", {"soil": "loam", "fmt": "log", "m1": 0.15, "m2": 0.10}),
    ("lyasko", {"soil": "sand", "fmt": "blf", "m1": 0.40, "m2": 0.30}),
    ("ding", {"soil": "sand", "fmt": "log", "n1": 0.10}),
    ("ding", {"soil": "loam", "fmt": "asc", "n1": 0.30}),
    ("mismatch", {"soil": "loam", "fmt": "blf", "mismatch": {"c": 3.0}}),
    ("mismatch", {"soil": "sand", "fmt": "log", "mismatch": {"phi": -2.5}}),
    ("mismatch", {"soil": "loam", "fmt": "blf", "mismatch": {"k_eq": 2.5, "n": -2.0}}),
    ("mismatch", {"soil": "sand", "fmt": "asc", "mismatch": {"K": 3.0}}),
    ("wong_reece", {"soil": "loam", "fmt": "log", "a1": 0.35, "a2": 0.10}),
    ("wong_reece", {"soil": "sand", "fmt": "blf", "a1": 0.20, "a2": 0.20}),
    ("drift", {"soil": "loam", "fmt": "blf", "mode": "compaction", "rate": 0.30}),
    ("drift", {"soil": "sand", "fmt": "log", "mode": "patch", "k_factor": 0.55, "c_factor": 0.5, "dphi_deg": -3.0}),
    # out of family (14)
    ("steer", {"soil": "loam", "fmt": "log", "alpha_deg": 3.0}),
    ("steer", {"soil": "sand", "fmt": "blf", "alpha_deg": 8.0}),
    ("rate", {"soil": "sand", "fmt": "asc", "beta": 0.10, "small": True}),
    ("rate", {"soil": "loam", "fmt": "blf", "beta": 0.30}),
    ("lugs", {"soil": "loam", "fmt": "log", "h": 0.015}),
    ("lugs", {"soil": "sand", "fmt": "blf", "h": 0.04}),
    ("xtalk", {"soil": "sand", "fmt": "log", "kappa": 0.02, "small": True}),
    ("xtalk", {"soil": "loam", "fmt": "blf", "kappa": 0.06}),
    ("sticky", {"soil": "loam", "fmt": "asc", "dr": 0.01}),
    ("sticky", {"soil": "sand", "fmt": "blf", "dr": 0.03}),
    ("hardpan", {"soil": "sand", "fmt": "log", "depth_frac": 0.75}),
    ("hardpan", {"soil": "loam", "fmt": "blf", "depth_frac": 0.50}),
    ("bulldoze", {"soil": "loam", "fmt": "log", "kb": 1.5}),
    ("flextyre", {"soil": "sand", "fmt": "blf", "e": 0.35}),
]

R2 = [
    # in family (16)
    ("none", {"soil": "loam", "fmt": "asc"}),
    ("none", {"soil": "sand", "fmt": "log"}),
    ("vasilev", {"soil": "loam", "fmt": "log", "H": 0.03}),
    ("vasilev", {"soil": "sand", "fmt": "blf", "H": 0.025}),
    ("lyasko", {"soil": "sand", "fmt": "asc", "m1": 0.25, "m2": 0.15}),
    ("lyasko", {"soil": "loam", "fmt": "blf", "m1": 0.30, "m2": 0.20}),
    ("ding", {"soil": "loam", "fmt": "log", "n1": 0.20}),
    ("ding", {"soil": "sand", "fmt": "blf", "n1": 0.25}),
    ("mismatch", {"soil": "sand", "fmt": "blf", "mismatch": {"c": -2.5}}),
    ("mismatch", {"soil": "loam", "fmt": "log", "mismatch": {"phi": 3.0}}),
    ("mismatch", {"soil": "sand", "fmt": "blf", "mismatch": {"n": 2.5}}),
    ("mismatch", {"soil": "loam", "fmt": "asc", "mismatch": {"k_eq": -3.0}}),
    ("wong_reece", {"soil": "sand", "fmt": "log", "a1": 0.30, "a2": 0.15}),
    ("wong_reece", {"soil": "loam", "fmt": "blf", "a1": 0.25, "a2": 0.25}),
    ("drift", {"soil": "sand", "fmt": "blf", "mode": "compaction", "rate": 0.25}),
    ("drift", {"soil": "loam", "fmt": "log", "mode": "patch", "k_factor": 0.6, "c_factor": 0.6, "dphi_deg": -2.5}),
    # out of family (14)
    ("steer", {"soil": "sand", "fmt": "log", "alpha_deg": 5.0}),
    ("steer", {"soil": "loam", "fmt": "blf", "alpha_deg": 6.0}),
    ("rate", {"soil": "loam", "fmt": "asc", "beta": 0.20}),
    ("rate", {"soil": "sand", "fmt": "blf", "beta": 0.25}),
    ("lugs", {"soil": "sand", "fmt": "log", "h": 0.025}),
    ("lugs", {"soil": "loam", "fmt": "blf", "h": 0.03}),
    ("xtalk", {"soil": "loam", "fmt": "log", "kappa": 0.04}),
    ("xtalk", {"soil": "sand", "fmt": "blf", "kappa": 0.05}),
    ("sticky", {"soil": "sand", "fmt": "asc", "dr": 0.02}),
    ("sticky", {"soil": "loam", "fmt": "blf", "dr": 0.02}),
    ("hardpan", {"soil": "loam", "fmt": "log", "depth_frac": 0.60}),
    ("hardpan", {"soil": "sand", "fmt": "blf", "depth_frac": 0.60}),
    ("bulldoze", {"soil": "sand", "fmt": "log", "kb": 1.0}),
    ("flextyre", {"soil": "loam", "fmt": "blf", "e": 0.25}),
]


if __name__ == "__main__":
    here = os.path.dirname(os.path.abspath(__file__))
    for rnd, runs, seed0 in ((1, R, 1200), (2, R2, 1230)):
        out = []
        for i, (case, p) in enumerate(runs, 1):
            p = dict(p)
            if p["fmt"] in ("log", "asc"):
                p["duration"] = 120  # text logs are large: keep them at 120 s
            out.append({"name": f"f9r{rnd}_{i:02d}", "case": case, "seed": seed0 + i, "params": p})
        with open(os.path.join(here, f"round{rnd}.json"), "w") as fh:
            json.dump(out, fh, indent=1)
        print(f"wrote round{rnd}.json ({len(out)} runs)")
