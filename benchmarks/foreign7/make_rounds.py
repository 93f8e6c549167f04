#!/usr/bin/env python
"""Write round1.json and round2.json (foreign7).  Refuses to overwrite: the
rounds are fixed before any data is generated for them."""
import json
import os
import sys

HERE = os.path.dirname(os.path.abspath(__file__))

R1 = [
    ("none", {"soil": "sand"}),
    ("none", {"soil": "loam"}),
    ("vasilev", {"soil": "sand", "H": 0.02}),
    ("vasilev", {"soil": "loam", "H": 0.015, "program": "steps", "fs": 200}),
    ("lyasko", {"soil": "sand", "m1": 0.5, "m2": 0.15}),
    ("lyasko", {"soil": "loam", "m1": 0.4, "m2": 0.1}),
    ("ding", {"soil": "sand", "n1": 0.3}),
    ("ding", {"soil": "loam", "n1": 0.25}),
    ("mismatch", {"soil": "sand", "changes": {"phi_deg": -5.0}}),
    ("mismatch", {"soil": "loam", "changes": {"k_eq": 0.55}}),
    ("mismatch", {"soil": "sand", "changes": {"K_m": 2.0}}),
    ("mismatch", {"soil": "loam", "changes": {"c_kpa": -1.8, "K_m": 1.8}}),
    ("wong_reece", {"soil": "sand", "a1": 0.1, "a2": 0.35}),
    ("wong_reece", {"soil": "loam", "a1": 0.2, "a2": 0.3}),
    ("drift", {"soil": "sand", "mode": "passes", "changes": {"k_eq": 1.7, "K_m": 0.6}}),
    ("drift", {"soil": "loam", "mode": "step", "at_pass": 3, "changes": {"phi_deg": -4.0, "c_kpa": -1.5}}),
    ("tilt", {"soil": "sand", "alpha_deg": 2.5}),
    ("tilt", {"soil": "loam", "alpha_deg": -2.0}),
    ("sinkage_gain", {"soil": "loam", "gain": 1.5, "drift_mm": 2.0}),
    ("bulldozing", {"soil": "sand", "f_b": 1.2}),
    ("bulldozing", {"soil": "loam", "f_b": 0.8}),
    ("peak_shear", {"soil": "loam", "Kr": 0.6, "Kw_rel": 1.5}),
    ("peak_shear", {"soil": "sand", "Kr": 0.65, "Kw_rel": 1.5}),
    ("lugged", {"soil": "sand", "h_g": 0.012, "n_g": 16}),
    ("rate", {"soil": "loam", "beta": 0.2, "speeds": [0.05, 0.25]}),
    ("drivetrain_drag", {"soil": "sand", "T0": 8.0, "mu_b": 0.006}),
    ("none", {"soil": "sand", "torque": False, "program": "sweeps"}),
    ("mismatch", {"soil": "loam", "changes": {"n": 0.13}}),
]

R2 = [
    ("none", {"soil": "loam", "program": "steps", "passes": 4, "loads": [1200, 1800]}),
    ("none", {"soil": "sand", "fs": 50, "noise": 1.5}),
    ("vasilev", {"soil": "sand", "H": 0.012, "program": "sweeps"}),
    ("vasilev", {"soil": "loam", "H": 0.03, "cycle_col": False, "valid_col": False}),
    ("lyasko", {"soil": "loam", "m1": 0.8, "m2": 0.2, "passes": 8}),
    ("lyasko", {"soil": "sand", "m1": 0.3, "m2": 0.1, "torque": False}),
    ("ding", {"soil": "loam", "n1": 0.4}),
    ("ding", {"soil": "sand", "n1": 0.18, "program": "steps"}),
    ("mismatch", {"soil": "loam", "changes": {"phi_deg": 4.5}}),
    ("mismatch", {"soil": "sand", "changes": {"k_eq": 1.5, "n": -0.1}}),
    ("mismatch", {"soil": "loam", "changes": {"K_m": 0.45}}),
    ("mismatch", {"soil": "sand", "changes": {"c_kpa": 1.3}}),
    ("wong_reece", {"soil": "sand", "a1": 0.2, "a2": 0.3, "program": "steps"}),
    ("wong_reece", {"soil": "loam", "a1": 0.05, "a2": 0.4, "fs": 200}),
    ("drift", {"soil": "loam", "mode": "ramp", "changes": {"c_kpa": 2.0, "k_eq": 1.5}}),
    ("drift", {"soil": "sand", "mode": "step", "at_pass": 4, "changes": {"k_eq": 0.6, "phi_deg": -3.0}}),
    ("drift", {"soil": "loam", "mode": "passes", "changes": {"k_eq": 1.4, "K_m": 0.75}, "cycle_col": False}),
    ("tilt", {"soil": "loam", "alpha_deg": 1.5}),
    ("sinkage_gain", {"soil": "sand", "gain": 0.6, "drift_mm": -1.5}),
    ("sinkage_gain", {"soil": "loam", "gain": 1.35, "drift_mm": 0.0, "program": "sweeps"}),
    ("bulldozing", {"soil": "loam", "f_b": 1.2, "loads": [1500, 2000, 2500]}),
    ("peak_shear", {"soil": "sand", "Kr": 0.7, "Kw_rel": 2.0}),
    ("lugged", {"soil": "loam", "h_g": 0.015, "n_g": 18}),
    ("rate", {"soil": "sand", "beta": 0.25, "speeds": [0.03, 0.15]}),
    ("drivetrain_drag", {"soil": "loam", "T0": 15.0, "mu_b": 0.008}),
    ("none", {"soil": "sand", "passes": 3, "loads": [500]}),
    ("mismatch", {"soil": "loam", "changes": {"kc": 4.0}}),
    ("lugged", {"soil": "sand", "h_g": 0.008, "n_g": 20, "program": "steps"}),
]


def build(rows, prefix, seed0):
    return [{"name": "%s_%02d" % (prefix, i + 1), "case": c, "seed": seed0 + i, "params": p} for i, (c, p) in enumerate(rows)]


def main():
    out = {"round1.json": build(R1, "f7r1", 1001), "round2.json": build(R2, "f7r2", 1031)}
    for fn in out:
        if os.path.exists(os.path.join(HERE, fn)):
            sys.exit("%s exists: refusing to overwrite (rounds are fixed)" % fn)
    for fn, rows in out.items():
        assert 24 <= len(rows) <= 30
        with open(os.path.join(HERE, fn), "w") as f:
            json.dump(rows, f, indent=1)
        print("wrote", fn, len(rows), "cases")


if __name__ == "__main__":
    main()
