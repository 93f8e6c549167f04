"""Benchmark: Wong-model sample evaluations (W, Dp, T) per second, ours vs quad-per-sample.

Run: ``python benchmarks/bench_model.py [--samples 100000] [--quad-samples 300]``

Evaluates ``wong_forces`` (fixed substituted Gauss-Legendre rule, vectorised)
on 100k samples spread over the built-in terrains' paper soils (clay, sand)
with loads 2-20 kN and slips 0.01-0.95, and the obvious reference
``wong_forces_quad`` (one scipy.integrate.quad per integral and sample) on a
subset, in the same run; prints samples/s, the speed-up and the max relative
error of ours against the reference on that subset. Single process; numpy
element-wise work runs on one core. Targets (issue 3): >= 200k samples/s and
>= 100x the quad version at <= 1e-6 relative error.
"""

from __future__ import annotations

import argparse
import os
import time

# one core: keep BLAS (used by the quadrature's matrix-vector products) single-threaded
for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import numpy as np  # noqa: E402

from wheelsoil.model import DEFAULT_WHEEL, get_model, load_terrain, wong_forces  # noqa: E402
from wheelsoil.model.wong import QUAD_ORDER, wong_forces_quad  # noqa: E402


def _best_rate(fn, n_samples: int, repeat: int) -> float:
    best = float("inf")
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        best = min(best, time.perf_counter() - t0)
    return n_samples / best


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--samples", type=int, default=100_000, help="samples for ours (default 100000)")
    ap.add_argument("--quad-samples", type=int, default=300, help="samples for the quad version (default 300)")
    ap.add_argument("--repeat", type=int, default=5, help="timing repeats, best is kept (default 5)")
    args = ap.parse_args(argv)

    rng = np.random.default_rng(0)
    wheel = DEFAULT_WHEEL
    print(f"wheelsoil model benchmark: wheel r={wheel.radius} m b={wheel.width} m, "
          f"Gauss-Legendre order {QUAD_ORDER} (substituted), pid {os.getpid()}")
    for name in ("clay", "sand"):
        terrain = load_terrain(name)
        load = rng.uniform(2000.0, 20000.0, args.samples)
        slip = rng.uniform(0.01, 0.95, args.samples)
        ours = _best_rate(lambda: wong_forces(terrain, wheel, load, slip), args.samples, args.repeat)
        balance = _best_rate(lambda: wong_forces(terrain, wheel, load, slip, sinkage="balance"),
                             args.samples, max(1, args.repeat // 2))
        lyasko = get_model("lyasko")
        lyasko_rate = _best_rate(lambda: lyasko.predict(terrain, wheel, load, slip, {"m1": 0.1, "m2": 0.05}),
                                 args.samples, args.repeat)
        q = slice(0, args.quad_samples)
        t0 = time.perf_counter()
        ref = wong_forces_quad(terrain, wheel, load[q], slip[q])
        quad_rate = args.quad_samples / (time.perf_counter() - t0)
        got = wong_forces(terrain, wheel, load[q], slip[q])
        err = 0.0  # max relative error where the absolute error exceeds 1e-3 N (issue 3 criterion)
        raw = 0.0  # max relative error over all values with |ref| >= 1 N
        for field in ("load_model_n", "drawbar_pull_n", "torque_nm"):
            a, b = getattr(got, field), getattr(ref, field)
            rel = np.abs(a - b) / np.maximum(np.abs(b), 1e-300)
            raw = max(raw, float(rel[np.abs(b) >= 1.0].max()))
            err = max(err, float(np.where(np.abs(a - b) <= 1e-3, 0.0, rel).max()))
        print(f"{name:5s}: ours eq10 {ours:12,.0f} samples/s | ours balance {balance:10,.0f} samples/s | "
              f"quad {quad_rate:8,.0f} samples/s | speed-up {ours / quad_rate:8,.0f}x | "
              f"max rel err vs quad {raw:.1e} ({args.quad_samples} samples)")
        print(f"       lyasko predict (eq10) {lyasko_rate:12,.0f} samples/s")
        print(f"       targets: >= 200,000 samples/s {'OK' if ours >= 2e5 else 'MISSED'}; "
              f">= 100x quad {'OK' if ours >= 100 * quad_rate else 'MISSED'}; "
              f"<= 1e-6 {'OK' if err <= 1e-6 else 'MISSED'}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
