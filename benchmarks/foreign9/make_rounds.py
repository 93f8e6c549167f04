#!/usr/bin/env python3
"""Write round1.json: 30 runs, sizes chosen before anything was generated."""
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

if __name__ == "__main__":
    out = []
    for i, (case, p) in enumerate(R, 1):
        p = dict(p)
        if p["fmt"] in ("log", "asc"):
            p["duration"] = 120  # text logs are large: keep them at 120 s
        out.append({"name": f"f9r1_{i:02d}", "case": case, "seed": 1200 + i, "params": p})
    here = os.path.dirname(os.path.abspath(__file__))
    with open(os.path.join(here, "round1.json"), "w") as fh:
        json.dump(out, fh, indent=1)
    print(f"wrote round1.json ({len(out)} runs)")
