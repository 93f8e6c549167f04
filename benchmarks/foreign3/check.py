#!/usr/bin/env python3
"""Self-checks of the foreign3 generator.

    python check.py                 # model checks + generate & check one run per format
    python check.py --model         # model checks only
    python check.py LOG TRUTH.json  # check a written log against its truth

Exit status 1 if any check fails.
"""
from __future__ import annotations

import json
import math
import os
import sys
import tempfile

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
import can  # noqa: E402
import cantools  # noqa: E402

from terra import (B_WHEEL, R_WHEEL, Physics, Soil, lab_soil, static_sinkage,  # noqa: E402
                   wheel_forces)

# the sensors' DBC files: the project's copies of ../shared/dbc (or FOREIGN3_DBC_DIR)
DBC_DIR = os.environ.get("FOREIGN3_DBC_DIR", os.path.join(os.path.dirname(os.path.dirname(HERE)), "dbc"))
FAILS: list[str] = []


def check(cond, msg):
    print(("  ok   " if cond else "  FAIL ") + msg)
    if not cond:
        FAILS.append(msg)


# --------------------------------------------------------------------------
def independent_dp(s, W, soil: Soil, r=R_WHEEL, b=B_WHEEL, npts=20001):
    """Plain Simpson rule on a theta grid refined towards theta1 (independent of quad)."""
    Z = static_sinkage(W, soil, r, b)
    t1 = math.acos(1 - Z / r)
    u = np.linspace(0, 1, npts)
    th = t1 * (1 - (1 - u) ** 3)          # clustering near theta1
    dth = 3 * t1 * (1 - u) ** 2            # d theta / du
    z = np.clip(r * (np.cos(th) - math.cos(t1)), 0, None)
    sig = (soil.kc / b + soil.kphi) * z ** soil.n
    j = r * ((t1 - th) - (1 - s) * (math.sin(t1) - np.sin(th)))
    tau = (soil.c + sig * math.tan(soil.phi)) * (1 - np.exp(-j / soil.K))

    def simpson(f):
        y = f * dth
        h = u[1] - u[0]
        return h / 3 * (y[0] + y[-1] + 4 * y[1:-1:2].sum() + 2 * y[2:-1:2].sum())
    Dp = r * b * (simpson(tau * np.cos(th)) - simpson(sig * np.sin(th)))
    T = r * r * b * simpson(tau)
    W7 = r * b * (simpson(sig * np.cos(th)) + simpson(tau * np.sin(th)))
    return Dp, T, W7


def model_checks():
    print("== model checks")
    lab = lab_soil()
    W = 11000.0
    # Eq. 10 inverse: Z0 reproduces W through the closed form
    Z0 = static_sinkage(W, lab, R_WHEEL, B_WHEEL)
    n = lab.n
    W_back = Z0 ** ((2 * n + 1) / 2) * math.sqrt(2 * R_WHEEL) * (lab.kc + B_WHEEL * lab.kphi) * (3 - n) / 3
    check(abs(W_back / W - 1) < 1e-12, f"Eq.10 closed form invertible: Z0 = {Z0*1000:.1f} mm at W = {W:.0f} N")
    check(0.10 < Z0 < 0.20, f"clay static sinkage plausible for a 0.47x0.32 m wheel at 11 kN ({Z0*1000:.0f} mm)")
    # vertical balance W from Eq. 7 vs the load, over slip and load
    worst = 0.0
    for Wl in (8000.0, 11000.0, 14000.0):
        for s in (0.0, 0.2, 0.5, 0.85):
            o = wheel_forces(s, Wl, lab)
            worst = max(worst, abs(o["W7"] / Wl - 1))
    check(worst < 0.05, f"Eq.7 vertical force within 5 % of the load that set Z0 via Eq.10 (worst {worst*100:.1f} %)")
    o0 = wheel_forces(0.0, W, lab)
    sig_only = o0["W7"]
    print(f"       (at s=0: W7={sig_only:.0f} N vs W={W:.0f} N; Eq.10 is the small-angle Bekker solution)")
    # corrected Eq. 2: sigma(theta=0) = (kc/b + kphi) Z0^n
    sig0 = (lab.kc / B_WHEEL + lab.kphi) * Z0 ** lab.n
    check(50e3 < sig0 < 250e3, f"peak normal stress (kc/b+kphi) Z0^n = {sig0/1e3:.0f} kPa (< 340 kPa inflation)")
    # independent integration
    for s in (0.05, 0.3, 0.5, 0.8):
        a = wheel_forces(s, W, lab)
        d, T, W7 = independent_dp(s, W, lab)
        check(abs(a["Dp"] - d) < 0.5 and abs(a["T"] - T) < 0.5 and abs(a["W7"] - W7) < 1.0,
              f"quad vs Simpson at s={s}: Dp {a['Dp']:.2f}/{d:.2f} N, T {a['T']:.2f}/{T:.2f} N m")
    # monotone Dp, T in slip for Janosi shear
    ss = np.linspace(0.02, 0.95, 20)
    dps = [wheel_forces(s, W, lab)["Dp"] for s in ss]
    Ts = [wheel_forces(s, W, lab)["T"] for s in ss]
    check(all(np.diff(dps) > 0) and all(np.diff(Ts) > 0), "Dp and T increase with slip (Janosi shear)")
    # limits: c = 0, phi = 0 -> no shear, Dp = -compaction resistance, T = 0
    nos = Soil(c=0.0, phi=0.0, K=lab.K, n=lab.n, kc=lab.kc, kphi=lab.kphi)
    o = wheel_forces(0.5, W, nos)
    check(abs(o["T"]) < 1e-9 and abs(o["Dp"] + o["Rc"]) < 1e-9, "no-shear soil: T = 0, Dp = -Rc")
    # K -> 0: full mobilisation, T = r^2 b int (c + sigma tan phi)
    o1 = wheel_forces(0.5, W, Soil(**{**lab.__dict__, "K": 1e-7}))
    o2 = wheel_forces(0.999, W, Soil(**{**lab.__dict__, "K": 1e-7}))
    check(abs(o1["T"] - o2["T"]) / o2["T"] < 1e-3, "K -> 0: torque independent of slip")
    # slip-sinkage models reduce to Wong at zero coefficients / zero slip
    base = wheel_forces(0.4, W, lab)
    for ph in (Physics(sinkage="vasilev", H=0.0), Physics(sinkage="lyasko"), Physics(sinkage="ding", n1=0.0),
               Physics(crab=0.0), Physics(visc_beta=0.0)):
        o = wheel_forces(0.4, W, lab, ph=ph)
        check(abs(o["Dp"] - base["Dp"]) < 1e-6, f"{ph.sinkage}/{ph.stress}/crab={ph.crab} reduces to Wong")
    for ph in (Physics(sinkage="vasilev", H=0.05), Physics(sinkage="lyasko", m1=0.3, m2=0.1),
               Physics(sinkage="ding", n1=0.4)):
        o = wheel_forces(0.0, W, lab, ph=ph)
        w0 = wheel_forces(0.0, W, lab)
        check(abs(o["Z"] - w0["Z"]) < 1e-12, f"{ph.sinkage}: Z(s=0) = Z0")
        o5 = wheel_forces(0.5, W, lab, ph=ph)
        check(o5["Z"] > w0["Z"], f"{ph.sinkage}: sinkage grows with slip ({w0['Z']*1000:.0f} -> {o5['Z']*1000:.0f} mm)")
    # Wong-Reece tends to... its front branch equals Bekker; tiny theta_m -> Wong
    o = wheel_forces(0.4, W, lab, ph=Physics(stress="wong_reece", a1=1e-4, a2=0.0))
    check(abs(o["Dp"] - base["Dp"]) < 2.0, f"Wong-Reece with theta_m -> 0 tends to Wong ({o['Dp']:.1f} vs {base['Dp']:.1f})")
    # hump shear peaks at j = Kw with tau_max (check the shape function)
    Kr, Kw = 0.8, 0.02
    f = lambda j: Kr * (1 + (1 / (Kr * (1 - 1 / math.e)) - 1) * math.exp(1 - j / Kw)) * (1 - math.exp(-j / Kw))  # noqa
    check(abs(f(Kw) - 1) < 1e-12 and abs(f(50 * Kw) - Kr) < 1e-6, "hump shear: 1 at j=Kw, Kr residual")
    # crab: lateral force to +y (left) for a rightward slide, Dp reduced
    oc = wheel_forces(0.3, W, lab, ph=Physics(crab=math.radians(8)))
    check(oc["Fy"] > 0 and oc["Dp"] < wheel_forces(0.3, W, lab)["Dp"], f"crab 8 deg: Fy={oc['Fy']:.0f} N > 0, Dp reduced")
    # self-propulsion check on this clay
    print("== can the vehicle self-propel on the clay?")
    for label, loads in (("four wheels at 11 kN", [11000] * 4),
                         ("front 8.8 kN x2, rear 11 kN x2", [8800, 8800, 11000, 11000])):
        best = -1e9
        pos = []
        for s in np.linspace(0.02, 0.95, 32):
            tot = sum(wheel_forces(s, Wl, lab, with_w7=False)["Dp"] for Wl in loads)
            best = max(best, tot)
            if tot > 0:
                pos.append(s)
        print(f"       {label}: max sum Dp = {best:.0f} N; positive for s in "
              f"{'[%.2f, %.2f]' % (min(pos), max(pos)) if pos else 'nowhere'}")
    s_all = [wheel_forces(s, 11000.0, lab, with_w7=False)["Dp"] for s in np.linspace(0.02, 0.95, 32)]
    check(max(s_all) < 0, "instrumented wheel at 11 kN: Dp < 0 at every slip (towed procedure needed)")


# --------------------------------------------------------------------------
def read_log(path, truth):
    msgs = list(can.LogReader(path))
    ts = np.array([m.timestamp for m in msgs])
    if ts.size and ts[0] < 1e9:       # ASC reader: relative times
        ts = ts + truth["run"]["host_start_unix"]
    return msgs, ts


def chan_name(m):
    c = m.channel
    if isinstance(c, str):
        return c
    return f"can{int(c)}"


def log_checks(path, truth):
    print(f"== log checks: {os.path.basename(path)}")
    db = cantools.database.Database()
    for f in ("wft.dbc", "wheel_speed.dbc", "gps_rt_speedbox.dbc"):
        db.add_dbc_file(os.path.join(DBC_DIR, f))
    msgs, ts = read_log(path, truth)
    D = truth["run"]["duration_s"]
    check(len(msgs) == truth["run"]["frames_total"], f"frame count {len(msgs)} = truth {truth['run']['frames_total']}")
    check(bool(np.all(np.diff(ts) >= 0)), "timestamps non-decreasing")
    per_bus: dict[str, list] = {"can0": [], "can1": []}
    bad_chan = 0
    dec = {}
    wft_ids = {0x120, 0x121, 0x122, 0x123}
    for m, t in zip(msgs, ts):
        cn = chan_name(m)
        if (m.arbitration_id in wft_ids) != (cn == "can0"):
            bad_chan += 1
        d = db.decode_message(m.arbitration_id, m.data, decode_choices=False)
        dec.setdefault(m.arbitration_id, []).append((t, d))
        per_bus.setdefault(cn, []).append(t)
    check(bad_chan == 0, "WFT frames on can0 (ASC/BLF channel 1), WSS+GNSS on can1 (channel 2)")
    for cn, tl in per_bus.items():
        if tl:
            check(bool(np.all(np.diff(tl) > 0)), f"{cn}: strictly increasing receive timestamps")
    rates = {0x120: 500, 0x121: 500, 0x122: 500, 0x123: 3, 0x300: 100, 0x301: 10,
             0x9567C22: 20, 0x9588322: 20, 0x9566D22: 20, 0x9566C22: 1}
    for aid, rt in rates.items():
        cnt = len(dec.get(aid, []))
        check(abs(cnt / D - rt) / rt < 0.03, f"0x{aid:X}: {cnt / D:.2f} Hz (expected {rt})")
    # WFT counter: shared, gaps reported
    F = {}
    for aid in (0x120, 0x121, 0x122):
        F[aid] = [(t, d) for (t, d) in dec[aid]]
    cF = np.array([d["Counter"] for _, d in F[0x120]])
    gaps = int(np.sum((np.diff(cF) % 256) != 1))
    check(gaps == truth["run"]["wft_force_counter_gaps"], f"force counter gaps {gaps} = truth")
    check(truth["run"]["wft_frames_lost"] == 0 or gaps > 0, "lost WFT frames show as counter gaps")
    # match triples of the same sample: consecutive frames on can0 with equal counter within 1 ms
    tF = np.array([t for t, _ in F[0x120]])
    tA = np.array([t for t, _ in F[0x122]])
    cA = np.array([d["Counter"] for _, d in F[0x122]])
    idx = np.searchsorted(tA, tF)
    idx = np.clip(idx, 0, tA.size - 1)
    ok = (np.abs(tA[idx] - tF) < 1.5e-3) & (cA[idx] == cF)
    check(ok.mean() > 0.995, f"force/angle frames of one sample share the Counter ({ok.mean()*100:.2f} %)")
    fx_w = np.array([d["Fx_w"] for _, d in F[0x120]])[ok]
    fz_w = np.array([d["Fz_w"] for _, d in F[0x120]])[ok]
    a = np.radians(np.array([d["WheelAngle"] for _, d in F[0x122]])[idx[ok]])
    tw = tF[ok] - truth["run"]["host_start_unix"]
    Fx = fx_w * np.cos(a) + fz_w * np.sin(a)
    Fz = -fx_w * np.sin(a) + fz_w * np.cos(a)
    tM = np.array([t for t, _ in F[0x121]]) - truth["run"]["host_start_unix"]
    My = np.array([d["My"] for _, d in F[0x121]])
    ser = truth["series_5Hz"]
    st = np.array(ser["t_s"])
    V = np.array(ser["V_mps"])
    mov = np.interp(tw, st, V) > 0.8
    # 1-s block means of hub Fx (+ m_w dV/dt) against the truth Dp
    Vt = np.interp(tw, st, V)
    dV = np.gradient(np.interp(tw, st, np.convolve(V, np.ones(3) / 3, "same")), tw)
    fx_corr = Fx + 80.0 * dV
    blocks = np.floor(tw).astype(int)
    errs, errz, errT = [], [], []
    for bk in np.unique(blocks[mov]):
        sel = (blocks == bk) & mov
        if sel.sum() < 400:
            continue
        tm = tw[sel].mean()
        errs.append(fx_corr[sel].mean() - np.interp(tm, st, ser["Dp_N"]))
        errz.append(Fz[sel].mean() - np.interp(tm, st, ser["W_soil_N"]))
        selm = (tM >= bk) & (tM < bk + 1)
        errT.append(My[selm].mean() - np.interp(tm, st, ser["T_Nm"]))
    errs, errz, errT = map(np.array, (errs, errz, errT))
    case = truth["case"]
    if case not in ("wft_crosstalk", "encoder_offset", "rope_surge"):
        check(abs(np.median(errs)) < 40 and np.percentile(np.abs(errs), 90) < 150,
              f"hub Fx + m_w dV/dt matches truth Dp (median {np.median(errs):+.1f} N, "
              f"p90 |err| {np.percentile(np.abs(errs), 90):.0f} N)")
    if case not in ("mud_buildup", "wft_crosstalk", "encoder_offset"):
        check(abs(np.median(errz)) < 40, f"hub Fz matches truth load (median {np.median(errz):+.1f} N)")
    if case not in ("torque_drift", "mud_buildup", "rope_surge"):
        check(abs(np.median(errT)) < 15, f"My matches truth T (median {np.median(errT):+.1f} N m, "
              f"includes I_w domega/dt)")
    if case == "wft_crosstalk":
        exp = truth["params"]["k"] * np.mean(Fz[mov]) / 2
        check(abs(np.median(errs) - exp) < 40, f"crosstalk offset {np.median(errs):.0f} N ~ k W/2 = {exp:.0f} N")
    if case == "encoder_offset":
        exp = math.sin(math.radians(truth["params"]["deg"])) * np.mean(Fz[mov])
        check(abs(np.median(errs) - exp) < 40, f"encoder offset {np.median(errs):.0f} N ~ W sin d = {exp:.0f} N")
    # wheel speed vs angle rate and slip vs truth
    tS = np.array([t for t, _ in dec[0x300]]) - truth["run"]["host_start_unix"]
    rl = np.array([d["WheelSpeed_RL"] for _, d in dec[0x300]]) * 2 * np.pi / 60
    au = np.unwrap(a)
    good = mov
    om_ang = np.gradient(au[good], tw[good])
    om_ang_s = np.convolve(om_ang, np.ones(50) / 50, "same")
    om_wss = np.interp(tw[good], tS, rl)
    rel = np.median(np.abs(om_wss - om_ang_s) / om_ang_s)
    check(rel < 0.02, f"WSS RL speed agrees with WFT angle rate (median rel diff {rel*100:.2f} %)")
    tG = np.array([t for t, _ in dec[0x9588322]]) - truth["run"]["host_start_unix"]
    vf = np.array([d["INS_Vel_Forwards_2D"] for _, d in dec[0x9588322]])
    L = truth["gnss_latency_s"]
    sel = np.interp(tG - L, st, V) > 0.8
    dv = vf[sel] - np.interp(tG[sel] - L, st, V)
    check(np.std(dv) < 0.05 and abs(np.mean(dv)) < 0.02, f"INS forward velocity, shifted by the latency, matches V "
          f"(mean {np.mean(dv):+.3f}, sd {np.std(dv):.3f} m/s)")
    dv0 = vf[sel] - np.interp(tG[sel], st, V)
    print(f"       (without latency correction sd {np.std(dv0):.3f} m/s; latency {L*1000:.0f} ms)")
    # slip from WSS + INS (latency corrected) vs truth slip
    r = truth["wheel_radius_m"]
    om_g = np.interp(tG[sel] - L, tS, rl)
    s_meas = (r * om_g - vf[sel]) / (r * om_g)
    s_tr = np.interp(tG[sel] - L, st, ser["slip_r047"])
    ds = s_meas - s_tr
    check(np.median(np.abs(ds)) < 0.02, f"slip from WSS+INS matches truth slip (median |ds| {np.median(np.abs(ds)):.4f})")
    check(min(s_tr) < 0.1 and max(s_tr) > 0.75, f"slip range covered {min(s_tr):.2f}..{max(s_tr):.2f}")
    # GPS time: monotone 50 ms epochs; offset host-GPS consistent with truth
    gt = np.array([d["GPS_Time"] + 604800 * d["GPS_Week"] for _, d in dec[0x9566D22]])
    tgt = np.array([t for t, _ in dec[0x9566D22]])
    step = np.round(np.diff(gt), 3)
    check(np.all(step >= 0.05 - 1e-6) and np.mean(step == 0.05) > 0.99, "GPS_Time epochs every 50 ms")
    off = np.median(gt - tgt)   # = gps - host - latency
    exp = truth["run"]["gps_minus_host_s_at_start"] - L
    check(abs(off - exp) < 0.01, f"GPS_Time - host = {off:.4f} s (truth {exp:.4f} s incl. latency)")
    # Diag mux
    mux = [d["DiagMux"] for _, d in dec[0x123]]
    check(set(mux) == {0, 1, 2}, "Diag mux values 0,1,2 present")
    temps = [d["BridgeTemp"] for _, d in dec[0x123] if d["DiagMux"] == 0]
    check(-40 < min(temps) and max(temps) < 125, f"BridgeTemp {min(temps):.1f}..{max(temps):.1f} C")
    # WSS status counter
    rc = np.array([d["RollingCounter"] for _, d in dec[0x301]])
    check(np.mean((np.diff(rc) % 16) == 1) > 0.99, "WSS_Status rolling counter increments")
    # ranges
    check(10000 < np.median(Fz[mov]) < 12000, f"hub Fz median {np.median(Fz[mov]):.0f} N (about 11 kN)")
    check(np.max(rl) * 60 / (2 * np.pi) < 650, f"max RL speed {np.max(rl)*60/(2*np.pi):.0f} rpm within DBC range")
    return


def main(argv):
    if len(argv) >= 2 and not argv[0].startswith("--"):
        truth = json.load(open(argv[1]))
        log_checks(argv[0], truth)
    else:
        model_checks()
        if "--model" not in argv:
            import gen
            d = tempfile.mkdtemp(prefix="foreign3_check_")
            for case, seed, fmt in (("none", 901, "asc"), ("vasilev", 902, "blf"), ("wft_crosstalk", 903, "log"),
                                    ("encoder_offset", 904, "log")):
                tr = gen.simulate(case, seed, {}, fmt, d, f"chk_{case}")
                log_checks(tr["_path"], json.load(open(os.path.join(d, f"chk_{case}_truth.json"))))
    print(f"\n{len(FAILS)} failure(s)")
    for f in FAILS:
        print("   -", f)
    return 1 if FAILS else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
