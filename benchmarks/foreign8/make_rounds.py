#!/usr/bin/env python3
"""Write round1.json and round2.json (refuses to overwrite existing files)."""
import json
import os
import sys

HERE = os.path.dirname(os.path.abspath(__file__))

R1 = [
    ("none", {"soil": "loam"}),
    ("none", {"soil": "sand", "format": "asc"}),
    ("vasilev", {"soil": "loam", "H": 0.02}),
    ("vasilev", {"soil": "sand", "H": 0.08}),
    ("lyasko", {"soil": "loam", "m1": 0.1, "m2": 0.05}),
    ("lyasko", {"soil": "sand", "m1": 0.6, "m2": 0.03, "format": "blf"}),
    ("ding", {"soil": "loam", "n1": 0.35}),
    ("ding", {"soil": "sand", "n1": 0.15}),
    ("mismatch", {"soil": "loam", "mismatch": {"k_eq": 1.35}}),
    ("mismatch", {"soil": "loam", "mismatch": {"n": 0.1}}),
    ("mismatch", {"soil": "loam", "mismatch": {"c": 0.5}}),
    ("mismatch", {"soil": "sand", "mismatch": {"phi": -4.0}}),
    ("mismatch", {"soil": "sand", "mismatch": {"k_eq": 0.75, "K": 1.5}, "format": "asc"}),
    ("wong_reece", {"soil": "loam", "a1": 0.3, "a2": 0.25}),
    ("wong_reece", {"soil": "sand", "a1": 0.15, "a2": 0.1}),
    ("drift", {"soil": "loam", "drift_mode": "compaction", "drift": {"k_eq": 1.6}}),
    ("wft_angle_offset", {"soil": "loam", "offset_deg": 0.5}),
    ("wft_angle_offset", {"soil": "sand", "offset_deg": 3.0}),
    ("torque_gain", {"soil": "loam", "gain": 0.04}),
    ("torque_gain", {"soil": "sand", "gain": -0.15, "format": "blf"}),
    ("my_zero_drift", {"soil": "loam", "drift_nm": 40.0}),
    ("wss_scale", {"soil": "loam", "scale": 0.015}),
    ("wss_scale", {"soil": "sand", "scale": -0.05}),
    ("strain_softening", {"soil": "loam", "Kr": 0.8}),
    ("strain_softening", {"soil": "loam", "Kr": 0.45}),
    ("rate_shear", {"soil": "loam", "beta": 0.1}),
    ("flexible_tyre", {"soil": "loam", "r_factor": 1.15}),
    ("flexible_tyre", {"soil": "sand", "r_factor": 1.5}),
    ("hardpan", {"soil": "loam", "h_frac": 0.8}),
    ("bulldozing", {"soil": "sand", "factor": 0.5, "format": "asc"}),
]

R2 = [
    ("none", {"soil": "sand"}),
    ("none", {"soil": "loam", "jitter_sigma": 1.0, "format": "blf"}),
    ("vasilev", {"soil": "loam", "H": 0.04}),
    ("vasilev", {"soil": "sand", "H": 0.012}),
    ("lyasko", {"soil": "loam", "m1": 0.3, "m2": 0.1}),
    ("lyasko", {"soil": "sand", "m1": 0.15, "m2": 0.02}),
    ("ding", {"soil": "sand", "n1": 0.5}),
    ("ding", {"soil": "loam", "n1": 0.25, "format": "asc"}),
    ("mismatch", {"soil": "sand", "mismatch": {"k_eq": 0.7}}),
    ("mismatch", {"soil": "sand", "mismatch": {"n": -0.12}}),
    ("mismatch", {"soil": "loam", "mismatch": {"c": 1.8}}),
    ("mismatch", {"soil": "loam", "mismatch": {"phi": 3.5, "c": 0.7}}),
    ("mismatch", {"soil": "loam", "mismatch": {"K": 0.5}, "format": "blf"}),
    ("wong_reece", {"soil": "loam", "a1": 0.42, "a2": 0.35}),
    ("drift", {"soil": "sand", "drift_mode": "patch", "patch_at": 0.55, "drift": {"phi": -4.0, "k_eq": 0.7}}),
    ("drift", {"soil": "sand", "drift_mode": "compaction", "drift": {"k_eq": 1.3, "n": 0.05}}),
    ("wft_angle_offset", {"soil": "loam", "offset_deg": -1.2}),
    ("torque_gain", {"soil": "loam", "gain": 0.08}),
    ("torque_gain", {"soil": "sand", "gain": -0.03}),
    ("my_zero_drift", {"soil": "sand", "drift_nm": -120.0, "format": "asc"}),
    ("my_zero_drift", {"soil": "loam", "drift_nm": 15.0}),
    ("wss_scale", {"soil": "loam", "scale": 0.008}),
    ("strain_softening", {"soil": "sand", "Kr": 0.65}),
    ("rate_shear", {"soil": "sand", "beta": 0.3}),
    ("rate_shear", {"soil": "loam", "beta": 0.05}),
    ("flexible_tyre", {"soil": "loam", "r_factor": 1.3, "format": "blf"}),
    ("hardpan", {"soil": "sand", "h_frac": 0.6}),
    ("hardpan", {"soil": "loam", "h_frac": 0.9}),
    ("bulldozing", {"soil": "sand", "factor": 1.5}),
    ("bulldozing", {"soil": "loam", "factor": 0.25}),
]


def build(rows, first_seed, rnd):
    return [{"name": "f8r%d_%02d" % (rnd, i + 1), "case": c, "seed": first_seed + i, "params": p}
            for i, (c, p) in enumerate(rows)]


def main():
    paths = [os.path.join(HERE, "round1.json"), os.path.join(HERE, "round2.json")]
    for p in paths:
        if os.path.exists(p):
            sys.exit("make_rounds.py: %s exists; refusing to overwrite" % p)
    assert len(R1) == 30 and len(R2) == 30
    for p, rows, seed, rnd in ((paths[0], R1, 1101, 1), (paths[1], R2, 1131, 2)):
        with open(p, "x") as f:
            json.dump(build(rows, seed, rnd), f, indent=1)
        print("wrote", p)


if __name__ == "__main__":
    main()
