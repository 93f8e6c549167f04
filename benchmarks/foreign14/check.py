#!/usr/bin/env python
"""foreign14 self-checks: quadrature vs scipy quad, determinism, every case generates, refusal,
CAN round trip (decode the log back with cantools and compare with the truth signals)."""
import json
import math
import os
import subprocess
import sys
import tempfile

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
import gen  # noqa: E402
from physics import wheel_forces, wheel_forces_quad, soil_si  # noqa: E402

PY = sys.executable
FAIL = []


def ok(cond, what):
    print(("ok   " if cond else "FAIL ") + what)
    if not cond:
        FAIL.append(what)


def check_quadrature():
    r, b = gen.WHEEL["r"], gen.WHEEL["b"]
    worst = 0.0
    for soil in ("loam", "sand"):
        lab, _ = gen.load_lab(soil)
        so = soil_si(lab)
        for model, mp in [("wong", {}), ("vasilev", {"H": 0.04}), ("lyasko", {"m1": 0.6, "m2": 0.06}),
                          ("ding", {"n1": 0.5}), ("stress", {"a1": 0.42, "a2": 0.2}),
                          ("moisture", {"beta": 0.55, "sig_d": 30e3})]:
            for W in (6000.0, 9500.0, 13000.0):
                for s in (-0.05, 0.02, 0.1, 0.3, 0.6, 0.9):
                    Dp, T = wheel_forces(s, W, r, b, so, model, mp)
                    Dq, Tq = wheel_forces_quad(s, W, r, b, so, model, mp)
                    e = max(abs(Dp[0] - Dq) / max(abs(Dq), 100.0), abs(T[0] - Tq) / max(abs(Tq), 100.0))
                    worst = max(worst, e)
    ok(worst < 2e-4, f"quadrature (48-node Gauss-Legendre) vs scipy quad: worst relative error {worst:.2e}")


def run_gen(case, seed, out, outdir, extra=()):
    cmd = [PY, os.path.join(HERE, "gen.py"), case, "--seed", str(seed), "--out", out, "--outdir", outdir]
    for e in extra:
        cmd += ["--p", e]
    return subprocess.run(cmd, capture_output=True, text=True)


def check_determinism(tmp):
    for fmt in ("log", "asc", "blf"):
        ra = run_gen("lyasko", 42, "a", os.path.join(tmp, "d1"), [f"fmt={fmt}", "duration_s=70"])
        rb = run_gen("lyasko", 42, "a", os.path.join(tmp, "d2"), [f"fmt={fmt}", "duration_s=70"])
        fa = open(os.path.join(tmp, "d1", f"a.{fmt}"), "rb").read()
        fb = open(os.path.join(tmp, "d2", f"a.{fmt}"), "rb").read()
        ta = json.load(open(os.path.join(tmp, "d1", "a_truth.json")))
        tb = json.load(open(os.path.join(tmp, "d2", "a_truth.json")))
        ta.pop("runtime_s"); tb.pop("runtime_s")
        ok(ra.returncode == 0 and fa == fb and ta == tb, f"determinism ({fmt}): same seed, same bytes and truth")


def check_cases(tmp):
    for i, case in enumerate(gen.CASES):
        r = run_gen(case, 300 + i, f"c_{case}", os.path.join(tmp, "cases"))
        good = r.returncode == 0
        if good:
            t = json.load(open(os.path.join(tmp, "cases", f"c_{case}_truth.json")))
            good = (t["case"] == case and "seed" in t["params"] and "gnss_latency_s" in t["params"]
                    and 0.03 <= t["params"]["gnss_latency_s"] <= 0.2 and t["generator"] == "foreign14"
                    and os.path.exists(os.path.join(tmp, "cases", t["fit_args"][0]))
                    and os.path.exists(os.path.join(os.path.dirname(os.path.dirname(HERE)), t["fit_args"][2]))
                    and t["runtime_s"] < 60)
        ok(good, f"case {case} generates ({r.stdout.strip() or r.stderr.strip()[-300:]})")


def check_refusal(tmp):
    for extra, why in ([["peak_pull_kN=40"], "winch pull beyond traction"],
                       [["peak_slip=[0.98]"], "peak slip 0.98"],
                       [["duration_s=240", "speed_set_mps=[2.6]"], "run longer than the cable"]):
        r = run_gen("none", 5, "ref", os.path.join(tmp, "ref"), extra)
        ok(r.returncode == 2 and r.stdout.startswith("REFUSED:"), f"refusal: {why} -> {r.stdout.strip()}")
    ok(not os.path.exists(os.path.join(tmp, "ref", "ref_truth.json")), "refused run writes no truth")


def decode_log(path):
    import can
    import cantools
    dbs = [cantools.database.load_file(os.path.join(HERE, "dbc", f))
           for f in ("wft.dbc", "wheel_speed.dbc", "gps_rt_speedbox.dbc")]
    out = {}
    for msg in can.LogReader(path):
        for db in dbs:
            try:
                m = db.get_message_by_frame_id(msg.arbitration_id)
            except KeyError:
                continue
            if m.is_extended_frame != msg.is_extended_id:
                continue
            d = m.decode(bytes(msg.data), decode_choices=False)
            out.setdefault(m.name, []).append((msg.timestamp, str(msg.channel), d))
            break
    return out


def check_roundtrip(tmp):
    for fmt, case in (("log", "none"), ("asc", "eccentric_rim"), ("blf", "vegetation_drag")):
        run = gen.Run(case, 77, {"fmt": fmt, "duration_s": 80})
        run.ang0 = float(run.rng.uniform(0, 2 * math.pi))
        run.lane_len = 0.0
        run.build_tables(); run.schedule(); run.plan_pulls(); run.dyn = None
        run.simulate_vehicle()
        path = os.path.join(tmp, f"rt.{fmt}")
        sig, tw, t0 = gen.encode_and_write(run, path)
        dec = decode_log(path)
        f = dec["WFT_RL_Force"]; m = dec["WFT_RL_Moment"]; a = dec["WFT_RL_Angle"]
        n = len(tw)
        ok(len(f) == n and len(m) == n and len(a) == n, f"{fmt}: {n} WFT samples of each frame")
        cnt_ok = all(f[i][2]["Counter"] == i % 256 == m[i][2]["Counter"] == a[i][2]["Counter"] for i in range(n))
        ok(cnt_ok, f"{fmt}: WFT counters shared and gap-free")
        chan_ok = all(x[1] in ("can0", "0") for x in f) or all(x[1] in ("0", 0) for x in f)
        ok(chan_ok or fmt != "log", f"{fmt}: WFT on can0 ({f[0][1]})")
        Fxw = np.array([x[2]["Fx_w"] for x in f]); Fzw = np.array([x[2]["Fz_w"] for x in f])
        My = np.array([x[2]["My"] for x in m])
        ang = np.radians(np.array([x[2]["WheelAngle"] for x in a]))
        Fx = Fxw * np.cos(ang) + Fzw * np.sin(ang)
        Fz = -Fxw * np.sin(ang) + Fzw * np.cos(ang)
        ex, ez, em = np.std(Fx - sig["Fx"]), np.std(Fz - sig["Fz"]), np.std(My - sig["My"])
        ok(ex < 20 and ez < 30 and em < 4 and abs(np.mean(Fx - sig["Fx"])) < 2,
           f"{fmt}: hub Fx/Fz/My decoded vs truth: sd {ex:.1f} N, {ez:.1f} N, {em:.2f} N m (noise 12/20/2.5)")
        tf = np.array([x[0] for x in f]) - t0
        # python-can's ASC reader returns timestamps relative to the first frame: remove that offset
        off = float(np.median(tf - tw)) if fmt == "asc" else 0.0
        tf = tf - off
        ok(np.max(np.abs(tf - tw)) < 1e-3, f"{fmt}: WFT timestamps within 1 ms of the sample clock "
                                            f"(reader offset {off:.3f} s)")
        w = dec["WSS_WheelSpeeds"]
        tws = np.array([x[0] for x in w]) - t0 - off
        rl = np.array([x[2]["WheelSpeed_RL"] for x in w]) * 2 * np.pi / 60
        om_true = np.interp(tws, run.dyn["t"], run.dyn["rw"]) / gen.WHEEL["r"]
        ok(np.std(rl - om_true) < 0.01 and abs(len(w) / 80 - 100) < 2,
           f"{fmt}: WSS RL omega vs truth sd {np.std(rl - om_true):.4f} rad/s, {len(w) / 80:.1f} Hz")
        v = dec["RT_SB_INS_Vel_Body_Axes"]
        tv = np.array([x[0] for x in v]) - t0 - off
        vf = np.array([x[2]["INS_Vel_Forwards_2D"] for x in v])
        lat = run.p["gnss_latency_s"]
        Vt = np.interp(tv - lat, run.dyn["t"], run.dyn["V"])
        V0 = np.interp(tv, run.dyn["t"], run.dyn["V"])
        ok(np.std(vf - Vt) < 0.015 and np.std(vf - Vt) < np.std(vf - V0) + 1e-9 and abs(len(v) / 80 - 20) < 1,
           f"{fmt}: INS forward speed = V(t - {lat:.3f} s): sd {np.std(vf - Vt):.4f} m/s "
           f"(without the latency {np.std(vf - V0):.4f}), {len(v) / 80:.1f} Hz")
        ok(len(dec.get("RT_SB_GPS_Speed", [])) == len(v) and len(dec.get("RT_SB_GPS_Time", [])) == len(v)
           and len(dec.get("RT_SB_GPS_Status", [])) >= 79 and len(dec.get("WSS_Status", [])) >= 799
           and len(dec.get("WFT_RL_Diag", [])) >= 237, f"{fmt}: GNSS, WSS_Status and diag frames present")
        allts = [x[0] for k in dec for x in dec[k]]
        ok(True, f"{fmt}: {len(allts)} frames decoded")


def main():
    tmp = tempfile.mkdtemp(prefix="f14check_")
    check_quadrature()
    check_roundtrip(tmp)
    check_determinism(tmp)
    check_refusal(tmp)
    check_cases(tmp)
    print(f"\n{len(FAIL)} failure(s)" if FAIL else "\nall checks passed")
    return 1 if FAIL else 0


if __name__ == "__main__":
    sys.exit(main())
