#!/usr/bin/env python3
"""Write round2.json once (refuses to overwrite): the project's second round of this generator, written after
round 1 was scored and before any of its runs was generated. Round 1's plan (15 cases, each on both soils: the soil
follows the seed's parity), its case pairs in a fresh order, fresh seeds 1531-1560; every size is drawn by the
generator from its own ranges."""
import json
import os
import sys

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
path = os.path.join(HERE, "round2.json")
if os.path.exists(path):
    print("round2.json exists; refusing to overwrite")
    sys.exit(1)
r1 = json.load(open(os.path.join(HERE, "round1.json")))
pairs = [r1[i]["case"] for i in range(0, 30, 2)]
assert all(r1[i]["case"] == r1[i + 1]["case"] for i in range(0, 30, 2))
order = np.random.default_rng(12_2026_2).permutation(15)
out = [{"name": f"f12r2_{i + 1:02d}", "case": pairs[order[i // 2]], "seed": 1531 + i, "params": {}} for i in range(30)]
with open(path, "x") as f:
    json.dump(out, f, indent=1)
print("wrote", path)
