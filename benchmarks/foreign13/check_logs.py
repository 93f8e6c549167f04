#!/usr/bin/env python3
"""Read foreign13 logs back with python-can + cantools: decode every frame,
check the message rates and the WFT counters, rebuild the hub-frame signals
(wheel angle rotation, wheel inertia removed), and print a slip-binned
comparison of the recorded drawbar pull / torque with Wong's model.

usage: check_logs.py LOG [LOG ...]      (each LOG next to its NAME_truth.json)
"""
import json
import math
import os
import sys

import can
import cantools
import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
import gen  # noqa: E402
import wong13 as wm  # noqa: E402

RATES = {"WFT_RL_Force": 500, "WFT_RL_Moment": 500, "WFT_RL_Angle": 500, "WSS_WheelSpeeds": 100,
         "WSS_Status": 10, "RT_SB_GPS_Speed": 20, "RT_SB_INS_Vel_Body_Axes": 20, "RT_SB_GPS_Time": 20,
         "RT_SB_GPS_Status": 1}
BUS = {"WFT": 0, "WSS": 1, "RT_": 1}


def read(path):
    dbs = gen.load_dbs()
    by_id = {}
    for db in dbs.values():
        for m in db.messages:
            by_id[(m.frame_id, m.is_extended_frame)] = m
    out = {}
    nbad = 0
    chans = {}
    for msg in can.LogReader(path):
        key = (msg.arbitration_id, msg.is_extended_id)
        m = by_id.get(key)
        if m is None:
            nbad += 1
            continue
        ch = msg.channel
        if isinstance(ch, str):
            ch = int(ch.replace("can", ""))
        elif path.endswith(".trc"):
            ch -= 1         # python-can's TRC reader reports the file's 1-based bus number
        chans.setdefault(m.name, set()).add(ch)
        d = m.decode(bytes(msg.data), decode_choices=False)
        rec = out.setdefault(m.name, {"t": []})
        rec["t"].append(msg.timestamp)
        for k, v in d.items():
            rec.setdefault(k, []).append(v)
    for name, rec in out.items():
        n = len(rec["t"])
        for k in list(rec):
            if len(rec[k]) == n:
                rec[k] = np.asarray(rec[k], float)
            else:       # multiplexed signals
                rec[k] = np.asarray(rec[k], float)
    return out, nbad, chans


def unwrap_counter(t, c, t0, c0):
    est = (t - t0) * 500.0 + c0
    return (c + 256 * np.round((est - c) / 256.0)).astype(np.int64)


def check(path):
    base = os.path.splitext(path)[0]
    truth = json.load(open(base + "_truth.json"))
    P_ = truth["params"]
    wh = P_["wheel"]
    r, b, mw, Iw = wh["r"], wh["b"], wh["m_w"], wh["I_w"]
    d, nbad, chans = read(path)
    print("=" * 100)
    print("%s  case=%s (%s)  soil=%s  format=%s  latency=%.3f s" % (
        os.path.basename(path), truth["case"], truth["family"], P_["soil"], P_["imperfections"]["format"],
        P_["gnss_latency_s"]))
    ok = nbad == 0
    for name, hz in RATES.items():
        t = d[name]["t"]
        med = float(np.median(np.diff(t)))
        bus = BUS[name[:3]]
        cs = chans[name]
        good = abs(1.0 / med - hz) < 0.02 * hz and cs == {bus}
        ok &= good
        print("  %-24s n=%6d  median rate %7.2f Hz (want %3d)  bus %s %s" % (name, t.size, 1 / med, hz, sorted(cs),
                                                                       "" if good else "<-- BAD"))
    # WFT samples: join the three frames of one sample by counter
    F, Mo, A = d["WFT_RL_Force"], d["WFT_RL_Moment"], d["WFT_RL_Angle"]
    t0 = min(F["t"][0], Mo["t"][0], A["t"][0])
    c0 = [F, Mo, A][int(np.argmin([F["t"][0], Mo["t"][0], A["t"][0]]))]["Counter"][0]
    idx = [unwrap_counter(x["t"], x["Counter"], t0, c0) for x in (F, Mo, A)]
    gaps = [int(np.sum(np.diff(i) - 1)) for i in idx]
    print("  WFT counter gaps (lost frames) force/moment/angle: %s; truth lost %d frames" % (
        gaps, P_["imperfections"]["lost"]["wft_frames"]))
    ok &= all(np.all(np.diff(i) >= 1) for i in idx)
    common = np.intersect1d(np.intersect1d(idx[0], idx[1]), idx[2])
    sel = [np.searchsorted(i, common) for i in idx]
    tw = F["t"][sel[0]]
    a = np.deg2rad(A["WheelAngle"][sel[2]])
    Fxw, Fzw = F["Fx_w"][sel[0]], F["Fz_w"][sel[0]]
    Fx = Fxw * np.cos(a) + Fzw * np.sin(a)
    Fz = -Fxw * np.sin(a) + Fzw * np.cos(a)
    My = Mo["My"][sel[1]]
    # speeds
    ws = d["WSS_WheelSpeeds"]
    om = ws["WheelSpeed_RL"] * 2 * math.pi / 60
    ins = d["RT_SB_INS_Vel_Body_Axes"]
    L = P_["gnss_latency_s"]
    tg = ins["t"] - L
    # common 100 Hz grid, 0.1 s moving average
    tt = np.arange(max(tw[0], ws["t"][0], tg[0]) + 0.2, min(tw[-1], ws["t"][-1], tg[-1]) - 0.2, 0.01)

    def smooth(tsrc, x, win=0.10):
        y = np.interp(tt, tsrc, x)
        k = max(1, int(round(win / 0.01)))
        return np.convolve(y, np.ones(k) / k, mode="same")
    Fx_g, Fz_g, My_g = smooth(tw, Fx), smooth(tw, Fz), smooth(tw, My)
    om_g = smooth(ws["t"], om)
    V_g = smooth(tg, ins["INS_Vel_Forwards_2D"], 0.2)
    Dp = Fx_g + mw * np.gradient(V_g, 0.01)
    T = My_g - Iw * np.gradient(om_g, 0.01)
    rw = np.maximum(r * om_g, 1e-6)
    s = 1 - V_g / rw
    mov = (om_g > 2.0) & (V_g > 0.2)
    # models
    lab = gen.load_lab(P_["soil"])
    Plab = gen.soil_dict(lab, {k: 0.0 for k in gen.KEYS}, b)
    ts = P_["true_soil"]
    Ptrue = dict(c=ts["c_kpa"] * 1e3, phi=math.radians(ts["phi_deg"]), K=ts["K_m"], n=ts["n"],
                 keq=ts["k_eq_kn"] * 1e3)
    law = {}
    lw = P_["law"]
    if "ss" in lw:
        law["ss"] = tuple(lw["ss"])
    if "wr" in lw:
        law["wr"] = tuple(lw["wr"])
    if "smooth" in lw:
        law["smooth"] = tuple(lw["smooth"])
    if "crust" in lw:
        law["crust"] = tuple(lw["crust"])
    edges = np.array([0.02, 0.06, 0.10, 0.15, 0.20, 0.27, 0.35, 0.45, 0.55, 0.65, 0.75, 0.85])
    print("  %-11s %5s %6s | %7s %7s %7s %7s | %6s %6s %6s %6s" % (
        "slip bin", "n", "W", "Dp", "Wg_lab", "Wg_true", "truth", "T", "Wg_lab", "Wg_true", "truth"))
    for lo, hi in zip(edges[:-1], edges[1:]):
        m = mov & (s >= lo) & (s < hi)
        if m.sum() < 30:
            continue
        sb, Wb = float(s[m].mean()), float(Fz_g[m].mean())
        ml = wm.wheel([Wb], [sb], Plab, {}, r, b)
        mt = wm.wheel([Wb], [sb], Ptrue, {}, r, b)
        me = wm.wheel([Wb], [sb], Ptrue, law, r, b) if law else None
        print("  %.2f-%.2f %6d %6.0f | %7.0f %7.0f %7.0f %7s | %6.0f %6.0f %6.0f %6s" % (
            lo, hi, m.sum(), Wb, Dp[m].mean(), ml["Dp"][0], mt["Dp"][0],
            "%.0f" % me["Dp"][0] if me else "-", T[m].mean(), ml["T"][0], mt["T"][0],
            "%.0f" % me["T"][0] if me else "-"))
    print("  (Wg_lab: Wong, lab soil; Wg_true: Wong, true field soil (drift cases: its centre);"
          " truth: with the case's own law where it is a closed form)")
    print("  decode/rate/counter checks: %s" % ("OK" if ok else "FAILED"))
    return ok


def main(argv):
    if not argv:
        print(__doc__)
        return 2
    ok = True
    for p in argv:
        ok &= check(p)
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
