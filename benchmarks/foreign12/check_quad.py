"""Check wongmodel's own quadrature against scipy.integrate.quad (rel. 1e-6)."""
import sys, os
import numpy as np
import warnings
warnings.filterwarnings("ignore")
from scipy.integrate import quad
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import wongmodel as wm

soils = {"loess": dict(c_kpa=4.2, phi_deg=24.0, K_m=0.019, n=0.78, kc=18.5, kphi=1120.0),
         "dunesand": dict(c_kpa=0.6, phi_deg=31.5, K_m=0.030, n=1.08, kc=1.2, kphi=1750.0)}
effs = [{"kind": "none"}, {"kind": "vasilev", "H": 0.05}, {"kind": "lyasko", "m1": 0.5, "m2": 0.05},
        {"kind": "ding", "n1": 0.4}, {"kind": "stress_distribution", "a1": 0.42, "a2": 0.3},
        {"kind": "soil_rebound", "rebound_ratio": 0.25},
        {"kind": "curved_envelope", "dphi_per_decade": 6.0, "sigma_ref_kpa": 25.0}]
r, b = 0.546, 0.365
worst = 0.0
for sn, soil in soils.items():
    for eff in effs:
        for s in (-0.3, 0.0, 0.05, 0.2, 0.5, 0.9):
            for W in (7000.0, 11300.0, 14000.0):
                m = wm.wheel(np.array([s]), np.array([W]), r, b, soil, eff, nq=64)
                z, N = wm.sinkage(np.array([W]), r, b, soil, np.array([s]), eff)
                th1 = float(np.arccos(1 - z[0] / r)); N = float(N[0]); z = float(z[0])
                keq = soil["kc"] * 1e3 / b + soil["kphi"] * 1e3
                c = soil["c_kpa"] * 1e3; tp = np.tan(np.radians(soil["phi_deg"])); K = soil["K_m"]
                kind = eff["kind"]
                sp = min(max(s, 0), 1)
                thm = (eff["a1"] + eff["a2"] * sp) * th1 if kind == "stress_distribution" else None
                th2 = np.arccos(1 - eff["rebound_ratio"] * z / r) if kind == "soil_rebound" else 0.0

                def sig(th):
                    if th < 0:
                        return keq * z ** N * (np.cos(th) - np.cos(th2)) / (1 - np.cos(th2))
                    if thm is not None and th < thm:
                        thq = th1 - th / thm * (th1 - thm)
                        return keq * max(r * (np.cos(thq) - np.cos(th1)), 0) ** N
                    return keq * max(r * (np.cos(th) - np.cos(th1)), 0) ** N

                def tau(th):
                    sg = sig(th)
                    j = r * ((th1 - th) - (1 - s) * (np.sin(th1) - np.sin(th)))
                    t = tp
                    if kind == "curved_envelope":
                        ref = eff["sigma_ref_kpa"] * 1e3
                        t = np.tan(np.radians(soil["phi_deg"] - eff["dphi_per_decade"] * np.log10(1.0 + sg / ref)))
                    return (c + sg * t) * (1 - np.exp(-abs(j) / K)) * np.sign(j)

                pts = [p for p in (0.0, thm) if p is not None]
                q = lambda f: quad(f, -th2, th1, points=pts, epsabs=0, epsrel=1e-12, limit=400)[0]
                ref = {"Wint": r * b * q(lambda t: sig(t) * np.cos(t) + tau(t) * np.sin(t)),
                       "Dp": r * b * q(lambda t: tau(t) * np.cos(t) - sig(t) * np.sin(t)),
                       "T": r * r * b * q(tau)}
                for k in ref:
                    scale = max(abs(ref[k]), 1e-3 * W * (r if k == "T" else 1))
                    err = abs(m[k][0] - ref[k]) / scale
                    worst = max(worst, err)
                    if err > 1e-6:
                        print("FAIL", sn, eff, s, W, k, m[k][0], ref[k], err)
print("worst relative deviation vs scipy quad: %.2e" % worst)
print("PASS" if worst <= 1e-6 else "FAIL")
sys.exit(0 if worst <= 1e-6 else 1)
