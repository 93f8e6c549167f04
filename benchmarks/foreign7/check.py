#!/usr/bin/env python
"""foreign7 self-checks:
1. the vectorised Gauss-Legendre quadrature of terra.wheel_forces against
   scipy.integrate.quad on scalar integrands written directly from the equations;
2. Eq. 10 against the numerical vertical balance (information only);
3. smoke test of every case (files written, columns, sidecar, truth keys,
   determinism from the seed, timing)."""
import json
import os
import sys
import tempfile
import time

import numpy as np
from scipy.integrate import quad
from scipy.optimize import brentq

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
import gen  # noqa: E402
import terra  # noqa: E402


def ref_forces(s, Z, r, b, c, phi, K, n, kc, kphi, dist="wong", a1=0.4, a2=0.2, shear="janosi", Kr=0.6, Kw=None, h_g=0.0):
    keq = kc / b + kphi
    th1 = np.arccos(1 - Z / r)
    rs = r + h_g
    th1s = np.arccos((r - Z) / rs)
    thm = (a1 + a2 * s) * th1

    def sig(t):
        if t > th1:
            return 0.0
        if dist == "wong_reece" and t < thm:
            t = th1 - t / thm * (th1 - thm)
        z = r * (np.cos(t) - np.cos(th1))
        return keq * max(z, 0.0) ** n

    def tau(t):
        j = rs * (th1s - t - (1 - s) * r / rs * (np.sin(th1s) - np.sin(t)))
        tm = c + sig(t) * np.tan(phi)
        if shear == "janosi":
            return tm * (1 - np.exp(-j / K))
        e = np.e
        return tm * Kr * (1 + (1 / (Kr * (1 - 1 / e)) - 1) * np.exp(1 - j / Kw)) * (1 - np.exp(-j / Kw))

    pts = [thm] if dist == "wong_reece" else ([th1] if h_g > 0 else None)
    q = lambda f, hi: quad(f, 0, hi, points=[p for p in (pts or []) if p < hi] or None, limit=200, epsabs=1e-10, epsrel=1e-10)[0]
    W = b * (r * q(lambda t: sig(t) * np.cos(t), th1) + rs * q(lambda t: tau(t) * np.sin(t), th1s))
    Dp = b * (rs * q(lambda t: tau(t) * np.cos(t), th1s) - r * q(lambda t: sig(t) * np.sin(t), th1))
    T = rs * rs * b * q(tau, th1s)
    return W, Dp, T


def check_quadrature():
    worst = 0.0
    soils = {"sand": gen.load_toml(os.path.join(HERE, "soil_sand.toml")), "loam": gen.load_toml(os.path.join(HERE, "soil_loam.toml"))}
    for name, st in soils.items():
        S = terra.soil_si(st)
        pre = gen.PRESETS[name]
        r, b = pre["r"], pre["b"]
        for Z in (0.02, 0.05, 0.09):
            for s in (0.05, 0.2, 0.5, 0.85):
                for opt in ({}, {"dist": "wong_reece", "a1": 0.1, "a2": 0.35}, {"shear": "brittle", "Kr": 0.6, "Kw": 1.5 * S["K"]},
                            {"h_g": 0.012}):
                    f = terra.wheel_forces(s, Z, r, b, S["c"], S["phi"], S["K"], S["n"], S["kc"], S["kphi"], **opt)
                    R = ref_forces(s, Z, r, b, S["c"], S["phi"], S["K"], S["n"], S["kc"], S["kphi"], **opt)
                    scale = max(abs(R[0]), 1.0)
                    for k, rv in zip(("W", "Dp", "T"), R):
                        sc = scale if k != "T" else max(abs(R[2]), 0.1)
                        err = abs(float(f[k]) - rv) / sc
                        worst = max(worst, err)
                        assert err < 2e-3, (name, Z, s, opt, k, float(f[k]), rv)
    print("quadrature vs scipy quad: worst relative error %.2e (relative to W, or T)" % worst)


def check_eq10_vs_balance():
    for name in ("sand", "loam"):
        st = gen.load_toml(os.path.join(HERE, "soil_%s.toml" % name))
        S = terra.soil_si(st)
        pre = gen.PRESETS[name]
        r, b = pre["r"], pre["b"]
        for W in pre["loads"]:
            z10 = float(terra.static_sinkage_eq10(W, r, b, S["kc"], S["kphi"], S["n"]))
            zb = brentq(lambda z: float(terra.wheel_forces(0.0, z, r, b, 0.0, 0.0, 1.0, S["n"], S["kc"], S["kphi"])["W"]) - W, 1e-4, 0.5 * r)
            f = terra.forces_simple(np.array([0.2, 0.5]), W, r, b, S)
            print("%s W=%6.0f N: Eq.10 Z0=%.4f m, sigma-only balance Z=%.4f m (%+.1f%%); Eq.7 W/W at s=0.2,0.5: %s; D/6=%.3f m"
                  % (name, W, z10, zb, 100 * (zb / z10 - 1), np.round(f["W"] / W, 3), 2 * r / 6))


def check_cases():
    tmp = tempfile.mkdtemp(prefix="f7check_")
    for case in gen.CASES:
        t0 = time.time()
        tr = gen.write_case(case, 7, "c_" + case, tmp, {})
        dt = time.time() - t0
        d = np.genfromtxt(os.path.join(tmp, "c_%s.csv" % case), delimiter=",", names=True)
        cols = d.dtype.names
        for c in ("t_s", "slip", "load_n", "drawbar_pull_n", "torque_nm", "sinkage_m", "distance_m", "speed_mps", "valid", "cycle"):
            assert c in cols, (case, c)
        assert np.all(np.isfinite(d["drawbar_pull_n"])) and np.all(np.diff(d["t_s"]) > 0)
        assert np.all(np.diff(d["distance_m"]) >= -1e-9)
        side = json.load(open(os.path.join(tmp, "c_%s.json" % case)))
        assert side["wheel"]["radius_m"] > 0.1
        for k in ("name", "case", "family", "acceptable_verdicts", "form", "params", "fit_args", "notes", "generator"):
            assert k in tr, k
        ok = (d["valid"] == 1) & (d["cycle"] >= 0) & (d["slip"] > 0.1)
        zmax = d["sinkage_m"][ok].max()
        r = side["wheel"]["radius_m"]
        assert dt < 5.0, (case, dt)
        print("%-16s rows %6d  %.2fs  ncycles %2d  slip %.2f..%.2f  Dp(mean s>0.1) %7.1f N  max Z %.3f m (D/6 %.3f)  effect %s"
              % (case, len(d), dt, len(np.unique(d["cycle"][d["cycle"] >= 0])), d["slip"][ok].min(), d["slip"][ok].max(),
                 d["drawbar_pull_n"][ok].mean(), zmax, r / 3, {k: v for k, v in tr["effect"].items() if k.endswith("s05")}))
    # determinism
    gen.write_case("lyasko", 11, "a", tmp, {"soil": "loam"})
    gen.write_case("lyasko", 11, "b", tmp, {"soil": "loam"})
    assert open(os.path.join(tmp, "a.csv")).read() == open(os.path.join(tmp, "b.csv")).read()
    # optional columns
    gen.write_case("none", 3, "nt", tmp, {"torque": False, "sinkage": False, "cycle_col": False, "valid_col": False})
    hdr = open(os.path.join(tmp, "nt.csv")).readline().strip().split(",")
    assert hdr == ["t_s", "slip", "load_n", "drawbar_pull_n", "distance_m", "speed_mps"], hdr
    print("determinism and optional columns OK; files in", tmp)


if __name__ == "__main__":
    check_quadrature()
    check_eq10_vs_balance()
    check_cases()
    print("ALL CHECKS PASSED")
