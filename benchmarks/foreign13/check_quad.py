#!/usr/bin/env python3
"""Check foreign13's Gauss-Legendre quadrature (wong13.integrate) against
scipy.integrate.quad of the same stress functions, for both lab soils and
every stress law the generator uses; also check the vertical balance and
print Eq. 10's sinkage next to the balance sinkage.  Exit 1 on failure."""
import math
import warnings
import os
import sys

import numpy as np
from scipy.integrate import quad

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
import gen  # noqa: E402
import wong13 as wm  # noqa: E402

r, b = gen.WHEEL["r"], gen.WHEEL["b"]
TOL = 5e-5          # relative to the larger of |value| and 1 % of W
TOL_KINK = 3e-4     # smooth_tread: tau = min(...) has a kink that GL does not resolve exactly


def quad_forces(th1, s, P, law):
    Pc = {k: np.full((1, 1), float(v)) for k, v in P.items()}
    th1c = np.full((1, 1), th1)
    sc = np.full((1, 1), s)
    if "wr" in law:
        a1, a2 = law["wr"]
        thm = min(max((a1 + a2 * min(max(s, 0), 1)) * th1, 1e-9), th1)
    else:
        thm = None

    def st(th):
        t = np.full((1, 1), th)
        te = t
        if thm is not None and th < thm:
            te = th1c - t / thm * (th1c - thm)
        sig, tau = wm.stresses(t, te, th1c, sc, Pc, law, r)
        return float(sig[0, 0]), float(tau[0, 0])

    pts = [thm] if thm else None
    kw = dict(limit=400, epsabs=1e-9, epsrel=1e-10)
    if law.get("rut") is not None:
        ck = math.cos(th1) + P["rebound"] / r
        if ck < 1.0:
            pts = [math.acos(ck)]
    kw["points"] = pts
    W = r * b * (quad(lambda t: st(t)[0] * math.cos(t) + st(t)[1] * math.sin(t), 0, th1, **kw)[0])
    D = r * b * (quad(lambda t: st(t)[1] * math.cos(t) - st(t)[0] * math.sin(t), 0, th1, **kw)[0])
    T = r * r * b * quad(lambda t: st(t)[1], 0, th1, **kw)[0]
    return W, D, T


def main():
    warnings.simplefilter("ignore")
    worst = 0.0
    ok = True
    print("%-10s %-8s %6s %5s | %10s %10s | %10s %10s | %9s %9s | rel.err" % (
        "soil", "law", "th1", "s", "W_gl", "W_quad", "Dp_gl", "Dp_quad", "T_gl", "T_quad"))
    for soil in ("siltyclay", "loamysand"):
        lab = gen.load_lab(soil)
        P = gen.soil_dict(lab, {k: 0.0 for k in gen.KEYS}, b)
        sn = dict(zw=0.03, pw=14e3)
        zt, pt = wm.snow_table(P, sn)
        laws = {
            "wong": {},
            "w-reece": {"wr": (0.32, 0.18)},
            "smooth": {"smooth": (0.6 * P["c"], P["phi"] - math.radians(5))},
            "crust": {"crust": (2.4, 1.6, 0.02)},
            "snow": {"snow": dict(z=zt, sig=pt, c=1.1e3, phi=math.radians(21), K=0.013)},
        }
        Pr = dict(P)
        st = wm.rut_state(np.array([4100.0]), np.array([0.3]), {k: np.array([v]) for k, v in P.items()}, r, b, 2.5e8)
        for k in ("zfloor", "rebound", "ku", "jres"):
            Pr[k] = float(st[k][0]) * (0.5 if k == "jres" else 1.0)
        laws["rut"] = {"rut": dict(Au=2.5e8)}
        for name, law in laws.items():
            PP = Pr if name == "rut" else P
            for th1 in (0.35, 0.6, 0.9):
                for s in (0.0, 0.05, 0.3, 0.8):
                    Wg, Dg, Tg = (float(v[0]) for v in wm.integrate(np.array([th1]), np.array([s]), PP, law, r, b))
                    Wq, Dq, Tq = quad_forces(th1, s, PP, law)
                    scale = max(abs(Wq), 1.0)
                    e = max(abs(Wg - Wq) / scale, abs(Dg - Dq) / max(abs(Dq), 0.01 * scale),
                            abs(Tg - Tq) / max(abs(Tq), 0.01 * scale * r))
                    worst = max(worst, e)
                    tol = TOL_KINK if name == "smooth" else TOL
                    flag = "" if e < tol else "  <-- FAIL"
                    ok &= e < tol
                    if s in (0.05, 0.8) and th1 == 0.6 or flag:
                        print("%-10s %-8s %6.2f %5.2f | %10.1f %10.1f | %10.2f %10.2f | %9.2f %9.2f | %.1e%s" % (
                            soil, name, th1, s, Wg, Wq, Dg, Dq, Tg, Tq, e, flag))
        # vertical balance and Eq. 10
        for W in (4000.0, 5500.0, 7000.0):
            th = wm.balance_theta1(np.array([W]), np.array([0.2]), P, {}, r, b)[0]
            Wb = wm.integrate(np.array([th]), np.array([0.2]), P, {}, r, b)[0][0]
            z10 = (3 * W / ((3 - P["n"]) * b * P["keq"] * math.sqrt(2 * r))) ** (2 / (2 * P["n"] + 1))
            zb = r * (1 - math.cos(th))
            print("  %s W=%5.0f N s=0.2: balance z=%.1f mm (W back %.2f N), Eq.10 z=%.1f mm" % (
                soil, W, zb * 1e3, Wb, z10 * 1e3))
            ok &= abs(Wb - W) < 1e-3 * W
    print("worst relative error %.2e (tolerance %.0e, %.0e for the smooth-tread kink; %d Gauss-Legendre "
          "nodes per region): %s" % (worst, TOL, TOL_KINK, wm.NQ, "OK" if ok else "FAILED"))
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
