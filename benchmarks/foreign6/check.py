#!/usr/bin/env python
"""Physics check of terra.py against scipy.integrate.quad, and sanity checks of generated tables.

usage: check.py [OUTDIR ...]      (OUTDIRs: generated rounds to sanity-check; optional)
"""
import csv
import glob
import json
import math
import os
import sys
import tempfile

import numpy as np
from scipy.integrate import quad

import gen
import terra
from gen import WHEEL, SOILS, lab_soil


def quad_forces(Z, s, wheel, soil, law=None, dist=None, shear=None, tau_mult=1.0):
    if law is None:
        law = terra.Bekker(soil.keq(wheel.b), soil.n)
    th1 = terra.contact_theta1(Z, wheel, law)
    pts = terra._breaks(Z, s, wheel, law, dist)

    def comp(i):
        def f(t):
            sg, ta = terra.stresses(np.array([t]), Z, s, wheel, soil, law, dist, shear, tau_mult)
            sg, ta = float(sg[0]), float(ta[0])
            return (sg * math.cos(t) + ta * math.sin(t), ta * math.cos(t) - sg * math.sin(t), ta)[i]
        return quad(f, 0.0, th1, points=pts[1:-1] or None, limit=200, epsabs=0, epsrel=1e-11)[0]

    r, b = wheel.r, wheel.b
    return r * b * comp(0), r * b * comp(1), r * r * b * comp(2)


def quad_flexible(delta, z0, s, wheel, soil, pg):
    r, b = wheel.r, wheel.b
    law = terra.Bekker(soil.keq(b), soil.n)
    thf = math.acos(1 - delta / r)
    th1 = math.acos(1 - (z0 + delta) / r)
    tp = math.tan(soil.phi)

    def st(t):
        sg = float(law(r * (math.cos(t) - math.cos(th1))))
        j = max(r * ((th1 - t) - (1 - s) * (math.sin(th1) - math.sin(t))), 0.0)
        return sg, (soil.c + sg * tp) * (1 - math.exp(-j / soil.K))

    q = lambda f, a, bb: quad(f, a, bb, limit=200, epsabs=0, epsrel=1e-11)[0]
    W = r * b * q(lambda t: st(t)[0] * math.cos(t) + st(t)[1] * math.sin(t), thf, th1)
    Dp = r * b * q(lambda t: st(t)[1] * math.cos(t) - st(t)[0] * math.sin(t), thf, th1)
    T = r * r * b * q(lambda t: st(t)[1], thf, th1)
    lf = 2 * r * math.sin(thf)
    jf = r * ((th1 - thf) - (1 - s) * (math.sin(th1) - math.sin(thf)))
    Fx = b * q(lambda x: (soil.c + pg * tp) * (1 - math.exp(-(jf + s * x) / soil.K)), 0, lf)
    return W + pg * b * lf, Dp + Fx, T + (r - delta) * Fx


def physics_check():
    worst = 0.0
    worst_at = None
    n = 0
    configs = []
    for key in ("A", "B"):
        so = lab_soil(key)
        for Z in (0.005, 0.02, 0.045):
            for s in (0.0, 0.1, 0.5, 0.9):
                configs.append((f"{key} wong Z={Z} s={s}", dict(Z=Z, s=s, soil=so)))
                configs.append((f"{key} ding N=n+0.4s Z={Z} s={s}", dict(Z=Z, s=s, soil=so.with_(n=so.n + 0.4 * s))))
                configs.append((f"{key} wong-reece Z={Z} s={s}", dict(Z=Z, s=s, soil=so, dist=("wr", 0.35, 0.2))))
                configs.append((f"{key} peak shear Z={Z} s={s}", dict(Z=Z, s=s, soil=so, shear=("peak", 0.6, 2.5 * so.K))))
                z1 = 0.7 * Z
                law = terra.Reload(so.keq(WHEEL.b), so.n, z1, 5e8 * z1)
                configs.append((f"{key} multipass Z={Z} s={s}", dict(Z=Z, s=s, soil=so, law=law)))
                configs.append((f"{key} multipass+WR Z={Z} s={s}", dict(Z=Z, s=s, soil=so, law=law, dist=("wr", 0.3, 0.1))))
    for label, c in configs:
        Z, s, so = c["Z"], c["s"], c["soil"]
        kw = {k: c[k] for k in ("law", "dist", "shear") if k in c}
        a = terra.forces(Z, s, WHEEL, so, **kw)
        q = quad_forces(Z, s, WHEEL, so, **kw)
        scale = max(abs(q[0]), 1.0)
        for i, (x, y) in enumerate(zip(a, q)):
            ref = abs(y) if i != 1 else max(abs(y), 0.02 * scale)   # Dp relative to max(|Dp|, 2 % of W)
            d = abs(x - y) / max(ref, 1e-9)
            n += 1
            if d > worst:
                worst, worst_at = d, (label, ["W", "Dp", "T"][i], x, y)
    # flexible tyre
    for key in ("A", "B"):
        so = lab_soil(key)
        for delta in (0.002, 0.01):
            for s in (0.1, 0.6):
                z0 = 0.02
                a = terra.flexible_forces(delta, z0, s, WHEEL, so, 60e3)
                q = quad_flexible(delta, z0, s, WHEEL, so, 60e3)
                for i, (x, y) in enumerate(zip(a, q)):
                    ref = abs(y) if i != 1 else max(abs(y), 0.02 * abs(q[0]))
                    d = abs(x - y) / ref
                    n += 1
                    if d > worst:
                        worst, worst_at = d, (f"{key} flexible d={delta} s={s}", ["W", "Dp", "T"][i], x, y)
    print(f"quadrature vs scipy.integrate.quad: {n} comparisons, worst relative difference {worst:.2e}")
    print(f"   worst at {worst_at[0]} ({worst_at[1]}): own {worst_at[2]:.6g}  quad {worst_at[3]:.6g}")
    assert worst < 1e-4, "quadrature not accurate enough"


def sinkage_check():
    print("static sinkage: vertical force balance (Eq. 7 = W, used) vs closed form Eq. 10, at s = 0 and 0.5:")
    for key in ("A", "B"):
        so = lab_soil(key)
        for W in SOILS[key]["loads"]:
            z7 = terra.solve_sinkage(W, 0.0, WHEEL, so)
            z75 = terra.solve_sinkage(W, 0.5, WHEEL, so)
            z10 = terra.eq10_sinkage(W, WHEEL, so)
            W7 = terra.forces(z7, 0.0, WHEEL, so)[0]
            assert abs(W7 - W) < 1e-6 * W
            assert z7 < 2 * WHEEL.r / 6, "static sinkage above D/6"
            print(f"   soil {key} W={W:6.0f} N: Eq7 z(s=0)={z7*1e3:5.1f} mm, z(s=0.5)={z75*1e3:5.1f} mm, "
                  f"Eq10 z={z10*1e3:5.1f} mm ({100*(z10/z7-1):+.1f} %), D/6={2*WHEEL.r/6*1e3:.0f} mm")


def read_csv(path):
    with open(path) as f:
        r = list(csv.DictReader(f))
    return r


def table_check(outdir):
    files = sorted(glob.glob(os.path.join(outdir, "*_truth.json")))
    bad = 0
    pos_hi = 0
    for tf in files:
        t = json.load(open(tf))
        rows = read_csv(os.path.join(outdir, t["name"] + ".csv"))
        side = json.load(open(os.path.join(outdir, t["name"] + ".json")))
        cols = list(rows[0].keys())
        assert cols[:3] == ["slip", "load_n", "drawbar_pull_n"], cols
        assert set(cols) <= {"slip", "load_n", "drawbar_pull_n", "torque_nm", "sinkage_m"}
        assert side["wheel"]["radius_m"] > 0
        assert set(t["acceptable_verdicts"]) <= {"none", "slip_sinkage", "terrain_mismatch",
                                                 "stress_distribution", "terrain_drift", "unexplained"}
        probs = []
        for r in rows:
            s, W, D = float(r["slip"]), float(r["load_n"]), float(r["drawbar_pull_n"])
            if not (0 <= s < 1):
                probs.append(f"slip {s}")
            if not (-W < D < W):
                probs.append(f"Dp {D} outside (-W, W) W={W}")
            if "sinkage_m" in r:
                z = float(r["sinkage_m"])
                if not (0 < z < 0.5 * WHEEL.r):
                    probs.append(f"sinkage {z}")
            if "torque_nm" in r:
                T = float(r["torque_nm"])
                if not (-0.05 * W * WHEEL.r < T < 1.2 * W * WHEEL.r):
                    probs.append(f"torque {T}")
        hi = [float(r["drawbar_pull_n"]) for r in rows if float(r["slip"]) >= 0.4]
        if hi and max(hi) > 0:
            pos_hi += 1
        if probs:
            bad += 1
            print(f"   {t['name']}: {probs[:3]}")
    print(f"table sanity in {outdir}: {len(files)} tables, {bad} with problems, "
          f"{pos_hi} with Dp > 0 somewhere at s >= 0.4")
    return bad


def main():
    physics_check()
    sinkage_check()
    # quick generation smoke test of every case
    with tempfile.TemporaryDirectory() as td:
        defaults = {"vasilev": {"H": 0.01}, "lyasko": {"m1": 0.3, "m2": 0.05}, "ding": {"n1": 0.2},
                    "terrain_mismatch": {"change": {"k_rel": -0.4}}, "stress_distribution": {"a1": 0.3, "a2": 0.1},
                    "crosstalk": {"kappa": 0.02}, "bearing_torque": {"T0": 3, "Tv": 1},
                    "shear_peak": {"Kr": 0.6, "Kw_rel": 2.5}, "bulldozing": {"zeta": 1.0},
                    "sinkage_datum": {"dz": 0.005}, "flexible_tyre": {"pg_kpa": 70},
                    "multipass": {"s_prev": 0.2, "Au": 5e8}, "load_transfer": {"lam": 0.3},
                    "rate_effect": {"beta": 0.08}, "none": {}}
        for case, p in sorted(defaults.items()):
            gen.generate(case, 1, "smoke_" + case, td, p)
        bad = table_check(td)
        assert bad == 0
    for d in sys.argv[1:]:
        table_check(d)


if __name__ == "__main__":
    main()
