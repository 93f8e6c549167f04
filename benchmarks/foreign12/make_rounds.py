#!/usr/bin/env python3
"""Write round1.json for foreign12 (refuses to overwrite)."""
import json, os, sys
HERE = os.path.dirname(os.path.abspath(__file__))
out = os.path.join(HERE, "round1.json")
if os.path.exists(out):
    print("round1.json exists; refusing to overwrite")
    sys.exit(1)
cases = (["none"] * 2 + ["slip_sinkage_vasilev"] * 2 + ["slip_sinkage_lyasko"] * 2 + ["slip_sinkage_ding"] * 2
         + ["terrain_mismatch"] * 4 + ["stress_distribution"] * 2 + ["terrain_drift"] * 2
         + [c for c in ["soil_rebound", "tread_creep", "wft_calibration", "liquid_ballast", "tyre_swap",
                        "curved_envelope", "encoder_latch"] for _ in range(2)])
assert len(cases) == 30
# consecutive seeds alternate parity, and the soil is chosen by seed parity
# (odd: dunesand, even: loess), so every pair of runs covers both soils
runs = [{"name": "f12r1_%02d" % (i + 1), "case": c, "seed": 1501 + i, "params": {}} for i, c in enumerate(cases)]
with open(out, "w") as f:
    json.dump(runs, f, indent=1)
print("wrote", out, len(runs), "runs")
