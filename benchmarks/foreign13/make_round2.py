#!/usr/bin/env python3
"""Write round2.json once (refuses to overwrite): the project's second round of this generator, written after
round 1 was scored and before any of its runs was generated. Round 1's plan (15 cases on each soil: the soil
follows the seed's parity, odd silty clay, even loamy sand), each soil's cases in a fresh order, fresh seeds
1631-1660; every size is drawn by the generator from its own ranges."""
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
odd, even = [r["case"] for r in r1[0::2]], [r["case"] for r in r1[1::2]]
rng = np.random.default_rng(13_2026_2)
odd, even = [odd[i] for i in rng.permutation(15)], [even[i] for i in rng.permutation(15)]
out = [{"name": f"f13r2_{i + 1:02d}", "case": (odd if i % 2 == 0 else even)[i // 2], "seed": 1631 + i, "params": {}}
       for i in range(30)]
with open(path, "x") as f:
    json.dump(out, f, indent=1)
print("wrote", path)
