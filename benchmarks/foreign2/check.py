#!/usr/bin/env python3
"""Checks of the foreign2 Wong model and of generated logs.

    python check.py                 # model checks only
    python check.py DIR/NAME.log    # + log checks (NAME_truth.json next to it)
Exit status 1 if a hard check fails.
"""
from __future__ import annotations

import json
import math
import os
import sys

import numpy as np
from scipy.integrate import quad

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
import gen  # noqa: E402
import wong2 as wm  # noqa: E402

FAIL = []


def check(cond, msg):
    print(("  ok   " if cond else "  FAIL ") + msg)
    if not cond:
        FAIL.append(msg)


def model_checks():
    print("== Wong model (lab sand, r=0.47, b=0.32)")
    wh = wm.Wheel()
    # 1. Eq. (10) vs the vertical integral (Eq. 7) at zero slip
    for W in (8000.0, 13000.0, 16000.0):
        d = wm.forces(0.0, W, wm.SAND, wh, full=True)
        # sinkage that would satisfy Eq. (7) exactly (force balance), for comparison
        lo, hi = 0.01, 0.45
        for _ in range(60):
            z = 0.5 * (lo + hi)
            sig, tau, th1, _ = wm.make_stresses(z, 0.0, wm.SAND, wh, wm.SAND.n)
            Wi = wh.r * wh.b * (quad(lambda t: sig(t) * math.cos(t), 0, th1)[0]
                                + quad(lambda t: tau(t) * math.sin(t), 0, th1)[0])
            lo, hi = (z, hi) if Wi < W else (lo, z)
        mis = (d["Wint"] - W) / W
        print("  W=%5.0f N: Eq.10 Z0=%.4f m theta1=%.1f deg; Eq.7 integral=%.0f N (%+.1f %%);"
              " balance sinkage would be %.4f m" % (W, d["Z"], math.degrees(d["theta1"]), d["Wint"],
                                                      100 * mis, z))
        check(abs(mis) < 0.15, "Eq.7 vs load within 15%% at W=%.0f (documented mismatch: Eq.10 "
              "is the small-angle/parabola approximation and ignores tau sin(theta))" % W)
    # 2. Dp increases with slip, torque positive
    s = np.linspace(0.0, 0.95, 20)
    F = np.array([wm.forces(x, 13000.0)[:2] for x in s])
    check(np.all(np.diff(F[:, 0]) > 0), "Dp increases with slip on sand (s 0..0.95): %s"
          % np.round(F[::4, 0]).astype(int).tolist())
    check(np.all(F[:, 1] > 0), "torque positive for s >= 0")
    # 3. quad convergence: tighter tolerance and an independent fixed rule
    old = dict(wm.QUAD_KW)
    ref = []
    for x in (0.05, 0.5, 0.9):
        d1 = wm.forces(x, 13000.0, full=True)
        wm.QUAD_KW.update(epsabs=1e-9, epsrel=1e-11)
        d2 = wm.forces(x, 13000.0, full=True)
        wm.QUAD_KW.clear(); wm.QUAD_KW.update(old)
        # composite Simpson with 4001 points
        Z, n = wm.sinkage(13000.0, x, wm.SAND, wm.Wheel())
        sig, tau, th1, _ = wm.make_stresses(Z, x, wm.SAND, wm.Wheel(), n)
        th = np.linspace(0, th1, 4001)
        sg = np.array([sig(t) for t in th]); tu = np.array([tau(t) for t in th])
        from scipy.integrate import simpson
        Dp_s = 0.47 * 0.32 * (simpson(tu * np.cos(th), x=th) - simpson(sg * np.sin(th), x=th))
        ref.append((x, d1["Dp"], d2["Dp"], Dp_s, d1["err"]))
        check(abs(d1["Dp"] - d2["Dp"]) < 0.01 and abs(d1["Dp"] - Dp_s) < 0.5,
              "quad converged at s=%.2f: Dp %.4f / tight %.4f / Simpson %.4f N (quad err est %.1e)"
              % (x, d1["Dp"], d2["Dp"], Dp_s, d1["err"]))
    # 4. slip-sinkage forms reduce to Wong at s=0 and raise sinkage with slip
    for sm, p in (("vasilev", {"H": 0.03}), ("lyasko", {"m1": 0.1, "m2": 0.02}), ("ding", {"n1": 0.15})):
        z0 = wm.sinkage(13000.0, 0.0, wm.SAND, wh, sm, p)[0]
        z5 = wm.sinkage(13000.0, 0.5, wm.SAND, wh, sm, p)[0]
        check(abs(z0 - wm.static_sinkage(13000.0, wm.SAND, wh)) < 1e-12 and z5 > z0,
              "%s: Z(s=0)=Z0=%.4f, Z(s=0.5)=%.4f m" % (sm, z0, z5))
    # 5. Wong-Reece: continuity at theta_m, zero at both ends
    sig, _, th1, thm = wm.make_stresses(0.2385, 0.5, wm.SAND, wh, wm.SAND.n, "wong_reece", 0.3, 0.3)
    check(abs(sig(thm - 1e-9) - sig(thm + 1e-9)) < 1e-3 * sig(thm) and sig(0.0) < 1e-6 and sig(th1) < 1e-6,
          "Wong-Reece sigma continuous at theta_m=%.3f, zero at 0 and theta1" % thm)
    # 6. interpolation table accuracy (the generator's grid)
    phys = gen.CasePhysics("none", {})
    Dpi, Ti = gen.build_table(phys, (0.95, 1.05), (0.99, 1.01))
    rng = np.random.default_rng(3)
    for lo, hi, tol in ((-0.15, 0.97, 10.0), (-0.5, -0.15, 40.0)):
        errs = []
        for _ in range(60):
            q = (rng.uniform(lo, hi), rng.uniform(6000, 16000), rng.uniform(0.96, 1.04), rng.uniform(0.992, 1.008))
            d = phys.point(*q)
            errs.append((abs(Dpi([q])[0] - d[0]), abs(Ti([q])[0] - d[1])))
        errs = np.array(errs)
        check(errs[:, 0].max() < tol and errs[:, 1].max() < tol,
              "table interpolation error for s in [%.2f, %.2f]: Dp max %.1f N (median %.1f), T max %.1f N m"
              % (lo, hi, errs[:, 0].max(), np.median(errs[:, 0]), errs[:, 1].max()))


def log_checks(logp):
    print("== log", logp)
    truth = json.load(open(logp[:-4] + "_truth.json"))
    db = gen.load_db()
    ids = {m.frame_id: m for m in db.messages}
    rows = {}
    nbad = 0
    last_ts = -1.0
    ordered = True
    with open(logp) as f:
        for ln in f:
            ts_s, bus, fr = ln.split()
            ts = float(ts_s[1:-1])
            ordered &= ts >= last_ts
            last_ts = ts
            hid, data = fr.split("#")
            ext = len(hid) == 8
            fid = int(hid, 16)
            m = ids.get(fid)
            if m is None or m.is_extended_frame != ext or (ext and len(hid) != 8) or (not ext and len(hid) != 3):
                nbad += 1
                continue
            exp_bus = "can0" if m.name.startswith("WFT") else "can1"
            if bus != exp_bus:
                nbad += 1
            rows.setdefault(m.name, []).append((ts, bytes.fromhex(data)))
    check(nbad == 0, "all ids known, 3/8 hex digits as standard/extended, right bus")
    check(ordered, "timestamps non-decreasing")
    dec = {}
    for name, lst in rows.items():
        m = db.get_message_by_name(name)
        out = []
        for ts, d in lst:
            v = m.decode(d, decode_choices=False)
            v["_t"] = ts
            out.append(v)
        dec[name] = out
    T = dec["WFT_RL_Force"][-1]["_t"] - dec["WFT_RL_Force"][0]["_t"]
    for name, rate in (("WFT_RL_Force", 500), ("WFT_RL_Moment", 500), ("WFT_RL_Angle", 500),
                       ("WSS_WheelSpeeds", 100), ("WSS_Status", 10), ("RT_SB_GPS_Time", 20),
                       ("RT_SB_GPS_Speed", 20), ("RT_SB_INS_Vel_Body_Axes", 20), ("RT_SB_GPS_Status", 1),
                       ("WFT_RL_Diag", 3)):
        r = len(dec.get(name, [])) / T
        check(abs(r - rate) / rate < 0.05, "%-24s %7d frames, %.2f Hz (expect %d)" % (name, len(dec.get(name, [])), r, rate))
    # shared counters
    cF = np.array([x["Counter"] for x in dec["WFT_RL_Force"]])
    cM = np.array([x["Counter"] for x in dec["WFT_RL_Moment"]])
    cA = np.array([x["Counter"] for x in dec["WFT_RL_Angle"]])
    check(np.array_equal(cF, cM) and np.array_equal(cF, cA) and np.all(np.diff(cF) % 256 == 1),
          "WFT counters shared and contiguous")
    # reconstruct hub frame and compare with the lab model (case none only meaningful)
    t = np.array([x["_t"] for x in dec["WFT_RL_Force"]])
    Fxw = np.array([x["Fx_w"] for x in dec["WFT_RL_Force"]])
    Fzw = np.array([x["Fz_w"] for x in dec["WFT_RL_Force"]])
    My = np.array([x["My"] for x in dec["WFT_RL_Moment"]])
    a = np.radians([x["WheelAngle"] for x in dec["WFT_RL_Angle"]])
    Fx = Fxw * np.cos(a) + Fzw * np.sin(a)
    Fz = -Fxw * np.sin(a) + Fzw * np.cos(a)
    tw = np.array([x["_t"] for x in dec["WSS_WheelSpeeds"]])
    om = np.array([x["WheelSpeed_RL"] for x in dec["WSS_WheelSpeeds"]]) * 2 * np.pi / 60
    tg = np.array([x["_t"] for x in dec["RT_SB_INS_Vel_Body_Axes"]]) - truth["gnss_latency_s"]
    vg = np.array([x["INS_Vel_Forwards_2D"] for x in dec["RT_SB_INS_Vel_Body_Axes"]])
    V = np.interp(t, tg, vg)
    omi = np.interp(t, tw, om)
    r = truth["wheel_radius_m"]
    s = (r * omi - V) / (r * omi)
    # smooth V for dV/dt
    k = np.ones(25) / 25
    dV = np.gradient(np.convolve(V, k, mode="same"), t)
    dom = np.gradient(np.convolve(omi, k, mode="same"), t)
    Dp = Fx + gen.M_W * dV
    Tq = My - gen.I_W * dom
    print("  Fz mean %.0f N (range %.0f..%.0f), slip range %.2f..%.2f, My max %.0f N m"
          % (Fz.mean(), np.percentile(Fz, 1), np.percentile(Fz, 99), s.min(), s.max(), My.max()))
    sel = (s > 0.2) & (s < 0.85)
    sel[np.arange(len(sel)) % 20 != 0] = False
    lab = gen.CasePhysics("none", {})
    pred = np.array([lab.point(float(si), float(wi))[0] for si, wi in zip(s[sel], Fz[sel])])
    resid = Dp[sel] - pred
    print("  Dp (s 0.2..0.85): measured median %.0f N, lab-model median %.0f N, median residual %+.0f N (%+.1f %%)"
          % (np.median(Dp[sel]), np.median(pred), np.median(resid), 100 * np.median(resid) / np.median(pred)))
    if truth["case"] == "none":
        check(abs(np.median(resid)) < 0.05 * abs(np.median(pred)), "case none: measured Dp agrees with the lab model (<5%)")
    gt = np.array([x["GPS_Time"] for x in dec["RT_SB_GPS_Time"]])
    check(np.allclose(np.round(gt / 0.05) * 0.05, gt, atol=1.5e-3) and np.all(np.diff(gt) > 0),
          "GPS_Time on the 50 ms grid and increasing")
    return dict(resid=float(np.median(resid)), pred=float(np.median(pred)))


if __name__ == "__main__":
    model_checks()
    for lp in sys.argv[1:]:
        log_checks(lp)
    print("FAILED: %d" % len(FAIL) if FAIL else "all checks passed")
    sys.exit(1 if FAIL else 0)
