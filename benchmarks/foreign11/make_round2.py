#!/usr/bin/env python3
"""Write round2.json once (refuses to overwrite): the project's second round of this generator, written after
round 1 was scored and before any of its runs was generated. The same cases on the other soil and wheel of each
round-1 pair, fresh seeds 1431-1460; every size is drawn by the generator from its own ranges."""
import json, os, sys
HERE = os.path.dirname(os.path.abspath(__file__))
path = os.path.join(HERE, "round2.json")
if os.path.exists(path):
    print("round2.json exists; refusing to overwrite"); sys.exit(1)
r1 = json.load(open(os.path.join(HERE, "round1.json")))
other = {"loam": "wetsand", "wetsand": "loam", "A": "B", "B": "A"}
out = [{"name": f"f11r2_{i + 1:02d}", "case": r["case"], "seed": 1431 + i,
        "params": {"soil": other[r["params"]["soil"]], "wheel": other[r["params"]["wheel"]]}}
       for i, r in enumerate(r1)]
assert len(out) == 30
with open(path, "x") as f:
    json.dump(out, f, indent=1)
print("wrote", path)
