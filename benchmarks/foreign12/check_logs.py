#!/usr/bin/env python3
"""Read foreign12 logs back with python-can, decode with cantools, print rates,
ranges and a slip-binned comparison of the measured hub forces with the truth
model (field soil, Wong Eqs. 1-10).  Usage: check_logs.py LOG [LOG ...]"""
import json, os, sys
import numpy as np
import can, cantools
HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
import wongmodel as wm

dbs = [cantools.database.load_file(os.path.join(HERE, "dbc", f)) for f in ("wft.dbc", "wheel_speed.dbc", "gps_rt_speedbox.dbc")]
byid = {}
for db in dbs:
    for m in db.messages:
        byid[m.frame_id] = m

for path in sys.argv[1:]:
    truth = json.load(open(os.path.splitext(path)[0] + "_truth.json"))
    P = truth["params"]
    rows = {}
    chans = {}
    n = 0
    for msg in can.LogReader(path):
        n += 1
        m = byid.get(msg.arbitration_id)
        if m is None:
            print("  unknown id", hex(msg.arbitration_id)); continue
        d = m.decode(msg.data)
        rows.setdefault(m.name, []).append((msg.timestamp, d))
        chans.setdefault(m.name, set()).add(msg.channel)
    T = max(r[-1][0] for r in rows.values()) - min(r[0][0] for r in rows.values())
    print("==", os.path.basename(path), truth["case"], P["soil"], "frames", n, "duration %.1f s" % T)
    for k, v in sorted(rows.items()):
        print("   %-24s %6d frames %7.2f Hz channel %s" % (k, len(v), len(v) / T, sorted(map(str, chans[k]))))
    # WFT: join by counter within sequence
    F = rows["WFT_RL_Force"]; A = rows["WFT_RL_Angle"]; M = rows["WFT_RL_Moment"]
    def seqkey(lst):
        out = {}
        blk = 0; prev = None
        for ts, d in lst:
            c = d["Counter"]
            if prev is not None and c < prev and prev - c > 128:
                blk += 1
            # resync block with timestamp (2 ms per count)
            key = int(round((ts - lst[0][0]) / 0.002 / 256 - (c / 256.0)))
            out[(key, c)] = (ts, d); prev = c
        return out
    fk, ak, mk = seqkey(F), seqkey(A), seqkey(M)
    t0 = min(F[0][0], A[0][0], M[0][0])
    keys = sorted(set(fk) & set(ak) & set(mk))
    ts = np.array([fk[k][0] for k in keys]) - t0
    a = np.radians([ak[k][1]["WheelAngle"] for k in keys])
    fx = np.array([fk[k][1]["Fx_w"] for k in keys]); fz = np.array([fk[k][1]["Fz_w"] for k in keys])
    my = np.array([mk[k][1]["My"] for k in keys])
    Fx = fx * np.cos(a) + fz * np.sin(a); Fz = -fx * np.sin(a) + fz * np.cos(a)
    print("   WFT samples joined %d of %d; Fz range %.0f..%.0f N, Fx %.0f..%.0f N, My %.0f..%.0f N.m" % (
        len(keys), len(F), np.percentile(Fz, 1), np.percentile(Fz, 99), np.percentile(Fx, 1), np.percentile(Fx, 99),
        np.percentile(my, 1), np.percentile(my, 99)))
    ws = rows["WSS_WheelSpeeds"]
    tw = np.array([r[0] for r in ws]) - t0
    om = np.array([r[1]["WheelSpeed_RL"] for r in ws]) * 2 * np.pi / 60
    gv = rows["RT_SB_INS_Vel_Body_Axes"]
    tg = np.array([r[0] for r in gv]) - t0 - P["gnss_latency_s"]
    vg = np.array([r[1]["INS_Vel_Forwards_2D"] for r in gv])
    print("   wheel speed max %.2f rad/s, INS forward speed max %.2f m/s, GPS_Time tow %.3f.." % (
        om.max(), vg.max(), rows["RT_SB_GPS_Time"][0][1]["GPS_Time"]))
    # smoothed signals at 100 Hz
    tt = np.arange(1, ts[-1] - 1, 0.01)
    k = np.ones(25) / 25
    sm = lambda x, y: np.convolve(np.interp(tt, x, y), k, "same")
    Om, V = sm(tw, om), sm(tg, vg)
    fz_, fx_, my_ = sm(ts, Fz), sm(ts, Fx), sm(ts, my)
    r, b = 0.546, 0.365
    acc = np.gradient(V, tt); alp = np.gradient(Om, tt)
    Dp = fx_ + 105 * acc; Tq = my_ - 16.5 * alp
    mv = (r * Om > 0.3) & (V > 0.05)
    s = np.where(mv, (r * Om - V) / np.maximum(r * Om, 1e-6), np.nan)
    soil = {k2: P["field_" + k2] for k2 in ["c_kpa", "phi_deg", "K_m", "n", "kc", "kphi"]}
    print("   slip bin   n   Dp_meas  Dp_wong   T_meas   T_wong   W_meas")
    for lo in np.arange(0.0, 1.0, 0.1):
        sel = mv & (s >= lo) & (s < lo + 0.1) & (np.abs(acc) < 0.3)
        if sel.sum() < 20:
            continue
        W = np.median(fz_[sel])
        mdl = wm.wheel(np.array([lo + 0.05]), W, r, b, soil)
        print("   %.1f-%.1f %5d %8.0f %8.0f %8.0f %8.0f %8.0f" % (lo, lo + 0.1, sel.sum(), np.median(Dp[sel]), mdl["Dp"][0],
                                                            np.median(Tq[sel]), mdl["T"][0], W))
