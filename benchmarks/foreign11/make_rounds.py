#!/usr/bin/env python3
"""Write round1.json once (refuses to overwrite)."""
import json, os, sys
HERE = os.path.dirname(os.path.abspath(__file__))
path = os.path.join(HERE, "round1.json")
if os.path.exists(path):
    print("round1.json exists; refusing to overwrite"); sys.exit(1)
L, S = "loam", "wetsand"
runs = [
    ("none", {"soil": L, "wheel": "A"}), ("none", {"soil": S, "wheel": "B"}),
    ("vasilev", {"soil": L, "wheel": "B"}), ("vasilev", {"soil": S, "wheel": "A"}),
    ("lyasko", {"soil": S, "wheel": "B"}), ("lyasko", {"soil": L, "wheel": "A"}),
    ("ding", {"soil": L, "wheel": "A"}), ("ding", {"soil": S, "wheel": "B"}),
    ("terrain_mismatch", {"soil": L, "wheel": "A"}), ("terrain_mismatch", {"soil": S, "wheel": "A"}),
    ("terrain_mismatch", {"soil": L, "wheel": "B"}), ("terrain_mismatch", {"soil": S, "wheel": "B"}),
    ("stress_distribution", {"soil": L, "wheel": "B"}), ("stress_distribution", {"soil": S, "wheel": "A"}),
    ("terrain_drift", {"soil": S, "wheel": "B"}), ("terrain_drift", {"soil": L, "wheel": "A"}),
    ("tyre_deflation", {"soil": L, "wheel": "A", "p_end_kpa": 120}), ("tyre_deflation", {"soil": S, "wheel": "B", "p_end_kpa": 80}),
    ("root_mat", {"soil": L, "wheel": "B", "c_mat": 3000}), ("root_mat", {"soil": S, "wheel": "A", "c_mat": 6000}),
    ("shear_rate", {"soil": L, "wheel": "A", "beta_rate": 0.04}), ("shear_rate", {"soil": S, "wheel": "B", "beta_rate": 0.07}),
    ("cross_slope", {"soil": S, "wheel": "A", "slope_deg": 8, "alpha_deg": 3}), ("cross_slope", {"soil": L, "wheel": "B", "slope_deg": 14, "alpha_deg": 6}),
    ("mud_buildup", {"soil": L, "wheel": "A", "mud_max_kg": 15}), ("mud_buildup", {"soil": L, "wheel": "B", "mud_max_kg": 30}),
    ("hardpan", {"soil": L, "wheel": "B", "pan_depth_frac": 0.65}), ("hardpan", {"soil": S, "wheel": "A", "pan_depth_frac": 0.45}),
    ("wft_thermal", {"soil": S, "wheel": "A", "dT_K": 30}), ("wft_thermal", {"soil": L, "wheel": "B", "dT_K": 45}),
]
out = [{"name": f"f11r1_{i+1:02d}", "case": c, "seed": 1401 + i, "params": p} for i, (c, p) in enumerate(runs)]
assert len(out) == 30
with open(path, "x") as f:
    json.dump(out, f, indent=1)
print("wrote", path)
