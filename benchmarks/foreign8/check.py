#!/usr/bin/env python3
"""foreign8 self-check: quadrature vs scipy.integrate.quad, determinism, every
case runs, refusal of an impossible soil, CAN round trip, timing."""
import json
import math
import os
import sys
import tempfile
import time

import numpy as np
from scipy.integrate import quad

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
import gen  # noqa: E402
import terra  # noqa: E402

FAIL = []


def ok(cond, msg):
    print(("PASS " if cond else "FAIL ") + msg)
    if not cond:
        FAIL.append(msg)


def quad_forces(s, W, soil, wheel, eff):
    """Reference: the same integrands with scipy.integrate.quad."""
    r, b = wheel["r"] * eff.get("r_soil_factor", 1.0), wheel["b"]
    _, _, _, z0 = terra.forces(np.array([s]), np.array([W]), soil, wheel, eff)
    z0 = float(z0[0])
    th1 = math.acos(1 - z0 / r)
    n = soil["n"] + (eff["n1"] * max(s, 0) if eff.get("sinkage") == "ding" else 0.0)
    keq = soil["kc"] / b + soil["kphi"]
    sp = min(max(s, 0), 0.99)
    thm = (eff["a1"] + eff["a2"] * sp) * th1 if eff.get("stress") == "wong_reece" else 0.0

    def sig(th):
        if th < thm:
            th = th1 - th / thm * (th1 - thm)
        return keq * max(r * (math.cos(th) - math.cos(th1)), 0.0) ** n

    def tau(th):
        j = r * ((th1 - th) - (1 - s) * (math.sin(th1) - math.sin(th)))
        return math.copysign(1, j) * (soil["c"] + sig(th) * math.tan(soil["phi"])) * (1 - math.exp(-abs(j) / soil["K"]))

    pts = [thm] if thm > 0 else None
    q = lambda f: quad(f, 0, th1, points=pts, limit=200, epsabs=1e-10, epsrel=1e-10)[0]
    Wm = r * b * (q(lambda t: sig(t) * math.cos(t)) + q(lambda t: tau(t) * math.sin(t)))
    Dp = r * b * (q(lambda t: tau(t) * math.cos(t)) - q(lambda t: sig(t) * math.sin(t)))
    T = r * r * b * q(tau)
    return Dp, T, Wm


def check_quadrature():
    wheel = dict(r=gen.WHEEL["r"], b=gen.WHEEL["b"])
    worst = 0.0
    for soil_name in ("loam", "sand"):
        soil = terra.soil_si(gen.load_lab(soil_name))
        for eff in ({}, {"stress": "wong_reece", "a1": 0.35, "a2": 0.3}, {"sinkage": "ding", "n1": 0.4},
                    {"sinkage": "lyasko", "m1": 0.4, "m2": 0.05}):
            for s in (-0.1, 0.0, 0.05, 0.2, 0.5, 0.9):
                for W in (8000.0, 13000.0):
                    Dp, T, Wm, _ = terra.forces(np.array([s]), np.array([W]), soil, wheel, eff)
                    ref = quad_forces(s, W, soil, wheel, eff)
                    for got, want, scale in ((Dp[0], ref[0], W), (T[0], ref[1], W * wheel["r"]), (Wm[0], ref[2], W)):
                        worst = max(worst, abs(got - want) / scale)
    ok(worst < 1e-4, "Gauss-Legendre quadrature vs scipy quad: worst error %.2e of W (or W r)" % worst)


def decode_all(path):
    import can
    db = gen.load_db()
    out = []
    with can.LogReader(path) as rd:
        for m in rd:
            out.append((round(m.timestamp, 6), m.arbitration_id, bytes(m.data)))
    return out, db


def check_run_and_roundtrip(tmp):
    t = time.time()
    path, truth = gen.generate("none", 4242, "det_a", tmp, {"soil": "loam"})
    dt = time.time() - t
    ok(dt < 20, "one run generated in %.1f s (< 20 s)" % dt)
    dur = truth["params"]["procedure"]["duration_s"]
    ok(120 <= dur <= 240, "run covers %.0f s of driving (2-4 min)" % dur)
    path2, truth2 = gen.generate("none", 4242, "det_b", tmp, {"soil": "loam"})
    a = open(path, "rb").read()
    b = open(path2, "rb").read()
    ok(a == b, "determinism: same seed -> identical CAN log bytes")
    ta = dict(truth["params"]); tb = dict(truth2["params"])
    ok(json.dumps(ta, sort_keys=True, default=str) == json.dumps(tb, sort_keys=True, default=str),
       "determinism: same seed -> identical truth")
    path3, _ = gen.generate("none", 4243, "det_c", tmp, {"soil": "loam"})
    ok(open(path3, "rb").read() != a, "different seed -> different data")
    # CAN round trip: decode WFT, rebuild hub-frame forces, compare with the model-side values
    frames, db = decode_all(path)
    ids = {}
    for ts, aid, data in frames:
        ids[aid] = ids.get(aid, 0) + 1
    need = {0x120, 0x121, 0x122, 0x123, 0x300, 0x301, 0x9567C22, 0x9588322, 0x9566D22, 0x9566C22}
    ok(need <= set(ids), "all hardware.md messages present: %s" % sorted(hex(i) for i in ids))
    rate = ids[0x120] / dur
    ok(abs(rate - 500) < 5, "WFT force rate %.1f Hz" % rate)
    ok(abs(ids[0x300] / dur - 100) < 2, "wheel speed rate %.1f Hz" % (ids[0x300] / dur))
    ok(abs(ids[0x9588322] / dur - 20) < 1, "GNSS velocity rate %.1f Hz" % (ids[0x9588322] / dur))
    # rebuild hub Fx, Fz from first 5000 samples
    f = [db.decode_message(aid, d) for ts, aid, d in frames if aid == 0x120][:5000]
    g = [db.decode_message(aid, d) for ts, aid, d in frames if aid == 0x122][:5000]
    cnt_ok = all(x["Counter"] == y["Counter"] for x, y in zip(f, g))
    ok(cnt_ok, "WFT Force/Angle counters agree sample by sample")
    ang = np.radians([x["WheelAngle"] for x in g])
    Fxw = np.array([x["Fx_w"] for x in f]); Fzw = np.array([x["Fz_w"] for x in f])
    Fz = -Fxw * np.sin(ang) + Fzw * np.cos(ang)
    Fx = Fxw * np.cos(ang) + Fzw * np.sin(ang)
    W0 = truth["params"]["vehicle"]["static_load_measured_wheel_n"]
    ok(abs(np.median(Fz) / W0 - 1) < 0.05, "hub Fz from rotating frame = static load (%.0f vs %.0f N)"
       % (np.median(Fz), W0))
    ok(np.median(Fx) > 0, "hub Fx during cruise positive (drawbar pull against light tow): %.0f N" % np.median(Fx))


def check_every_case(tmp):
    worst = 0.0
    for case in gen.CASES:
        t = time.time()
        try:
            path, truth = gen.generate(case, 77, "c_" + case, tmp, {"soil": "loam", "duration_s": 30})
            good = os.path.getsize(path) > 0 and truth["acceptable_verdicts"]
            good = good and set(truth["acceptable_verdicts"]) <= {
                "none", "slip_sinkage", "terrain_mismatch", "stress_distribution", "terrain_drift", "unexplained"}
            good = good and truth["fit_args"][0] == path and truth["fit_args"][1] == "--terrain"
            good = good and (truth["family"] == "in" or truth["acceptable_verdicts"] == ["unexplained"])
        except gen.Refused:
            good = False
        worst = max(worst, time.time() - t)
        ok(bool(good), "case %s runs (30 s of driving) and writes a valid truth" % case)
    for fmt in ("asc", "blf"):
        path, _ = gen.generate("none", 78, "fmt_" + fmt, tmp, {"soil": "sand", "duration_s": 20, "format": fmt})
        n = len(decode_all(path)[0])
        ok(path.endswith("." + fmt) and n > 20000, "format %s writes and reads back (%d frames)" % (fmt, n))


def check_refusal(tmp):
    try:
        gen.generate("mismatch", 5, "stuck", tmp, {"soil": "sand", "mismatch": {"k_eq": 0.05, "c": 0.05, "phi": -20}})
        ok(False, "impossible soil refused")
    except gen.Refused:
        ok(not os.path.exists(os.path.join(tmp, "stuck.log")), "impossible soil refused with a message, no file written")


def main():
    with tempfile.TemporaryDirectory() as tmp:
        check_quadrature()
        check_run_and_roundtrip(tmp)
        check_every_case(tmp)
        check_refusal(tmp)
    print("\n%s (%d failures)" % ("ALL PASS" if not FAIL else "FAILED", len(FAIL)))
    sys.exit(1 if FAIL else 0)


if __name__ == "__main__":
    main()
