"""Hidden-effect benchmark, in-family causes only (superseded by ``bench_diagnosis.py``).

Runs ``benchmarks/bench_diagnosis.py`` on the first ``--seeds`` seeds whose hidden effect is
in the hypotheses' family (none, Vasil'ev, Lyasko, Ding, terrain mismatch, stress
distribution, terrain drift): the old question "does the pipeline find what the simulator
hid?". The adversarial version with out-of-family causes is ``bench_diagnosis.py``.

    python benchmarks/bench_hidden_effect.py [--seeds 20] [--jobs 2] [--duration 180]
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=20, help="number of in-family seeds (default 20)")
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--duration", type=float, default=180.0)
    args = ap.parse_args(argv)
    sys.path.insert(0, str(Path(__file__).resolve().parent))
    import bench_diagnosis

    from wheelsoil.simulate import EFFECTS, IN_FAMILY

    seeds, s = [], 0
    while len(seeds) < args.seeds:
        if EFFECTS[s % len(EFFECTS)] in IN_FAMILY:
            seeds.append(s)
        s += 1
    extra = sum((["--seed", str(x)] for x in seeds), [])
    return bench_diagnosis.main(extra + ["--jobs", str(args.jobs), "--duration", str(args.duration)])


if __name__ == "__main__":
    sys.exit(main())
