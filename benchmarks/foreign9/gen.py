#!/usr/bin/env python3
"""foreign9 generator: vehicle CAN logs of tow (dynamometer-vehicle) field runs of a 4x4
whose rear-left wheel carries a rotating wheel force transducer, with one hidden effect.

gen.py CASE --seed S --out NAME --outdir DIR [--p key=value ...]
"""
import argparse
import json
import os
import sys
from datetime import datetime

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
from physics import wheel_forces, static_sinkage  # noqa: E402

G = 9.81
DBC_DIR = os.path.join(HERE, "..", "..", "dbc")  # the project's copies of the shared DBC files

# ---- the wheel of this generator (not hardware.md's default) -------------------------
WHEEL = {"r": 0.455, "b": 0.33, "m_w": 68.0, "I_w": 8.9}

# ---- two lab soils (written as TOML by write_terrains) -------------------------------
LAB = {
    "loam": {"name": "foreign9 silty loam (lab)", "c_kpa": 2.8, "phi_deg": 27.0, "K_m": 0.019,
             "n": 0.92, "kc": 15.0, "kphi": 1450.0,
             "unc": {"k_eq_rel": 0.12, "n": 0.04, "c_kpa": 0.5, "phi_deg": 1.5, "K_m": 0.004},
             "source": "foreign9 synthetic lab: bevameter plates 0.10/0.20 m, annular shear ring"},
    "sand": {"name": "foreign9 loamy sand (lab)", "c_kpa": 0.7, "phi_deg": 31.5, "K_m": 0.014,
             "n": 1.08, "kc": 1.5, "kphi": 1900.0,
             "unc": {"k_eq_rel": 0.15, "n": 0.05, "c_kpa": 0.25, "phi_deg": 1.8, "K_m": 0.003},
             "source": "foreign9 synthetic lab: bevameter plates 0.10/0.20 m, shear box"},
}

IN_FAMILY = {"none": ["none"], "vasilev": ["slip_sinkage"], "lyasko": ["slip_sinkage"],
             "ding": ["slip_sinkage"], "mismatch": ["terrain_mismatch"],
             "wong_reece": ["stress_distribution"], "drift": ["terrain_drift"]}
OUT_FAMILY = ["steer", "rate", "lugs", "xtalk", "sticky", "hardpan", "bulldoze", "flextyre"]
CASES = list(IN_FAMILY) + OUT_FAMILY
DEFAULTS = {
    "vasilev": {"H": 0.04}, "lyasko": {"m1": 0.3, "m2": 0.2}, "ding": {"n1": 0.25},
    "mismatch": {"mismatch": {"c": 3.0}}, "wong_reece": {"a1": 0.3, "a2": 0.15},
    "drift": {"mode": "compaction", "rate": 0.25},
    "steer": {"alpha_deg": 6.0}, "rate": {"beta": 0.15}, "lugs": {"h": 0.03},
    "xtalk": {"kappa": 0.04}, "sticky": {"dr": 0.02}, "hardpan": {"depth_frac": 0.6},
    "bulldoze": {"kb": 2.0}, "flextyre": {"e": 0.3},
}


def lab_k_eq(lab, b):  # N/m^(n+2)
    return (lab["kc"] / b + lab["kphi"]) * 1000.0


def write_terrains():
    for key, L in LAB.items():
        p = os.path.join(HERE, f"lab_{key}.toml")
        u = L["unc"]
        txt = (f'name = "{L["name"]}"\nc_kpa = {L["c_kpa"]}\nphi_deg = {L["phi_deg"]}\n'
               f'K_m = {L["K_m"]}\nn = {L["n"]:.2f}\nkc = {L["kc"]}\nkphi = {L["kphi"]}\n\n'
               f'[uncertainty]\n# one standard deviation of the lab values\n'
               f'k_eq_rel = {u["k_eq_rel"]}   # fraction of (kc/b + kphi)\n'
               f'n = {u["n"]}\nc_kpa = {u["c_kpa"]}\nphi_deg = {u["phi_deg"]}\nK_m = {u["K_m"]}\n'
               f'source = "{L["source"]}"\n')
        if not os.path.exists(p) or open(p).read() != txt:
            with open(p, "w") as fh:
                fh.write(txt)


def parse_p(items):
    out = {}
    for it in items or []:
        key, _, val = it.partition("=")
        try:
            out[key] = json.loads(val)
        except json.JSONDecodeError:
            out[key] = val
    return out


def refuse(msg):
    print("REFUSED: " + msg, file=sys.stderr)
    print("REFUSED: " + msg)
    sys.exit(2)


def corr_field(rng, L, ell, amp, dx=0.05):
    """Periodic Gaussian-correlated random field (std = amp) on a loop of length L."""
    n = int(np.ceil(L / dx))
    x = np.arange(n) * dx
    white = rng.standard_normal(n)
    kf = np.fft.rfftfreq(n, dx) * 2 * np.pi
    filt = np.exp(-0.25 * (kf * ell) ** 2)
    f = np.fft.irfft(np.fft.rfft(white) * filt, n)
    f = f / (f.std() + 1e-12) * amp
    return x, f


def smooth_noise(rng, t, fc, amp):
    """Low-pass (first order, cutoff fc) noise of std ~amp on grid t."""
    dt = t[1] - t[0]
    a = np.exp(-2 * np.pi * fc * dt)
    w = rng.standard_normal(len(t))
    y = np.empty_like(w)
    acc = 0.0
    from scipy.signal import lfilter
    y = lfilter([1 - a], [1, -a], w)
    return y / (y.std() + 1e-12) * amp


def main(argv=None):
    ap = argparse.ArgumentParser()
    ap.add_argument("case", choices=CASES)
    ap.add_argument("--seed", type=int, required=True)
    ap.add_argument("--out", required=True)
    ap.add_argument("--outdir", required=True)
    ap.add_argument("--p", action="append", default=[])
    a = ap.parse_args(argv)
    P = dict(DEFAULTS.get(a.case, {}))
    P.update(parse_p(a.p))
    write_terrains()
    rng = np.random.default_rng([a.seed, 9009])
    case = a.case
    r, b, m_w, I_w = WHEEL["r"], WHEEL["b"], WHEEL["m_w"], WHEEL["I_w"]

    soil_name = P.get("soil", ["loam", "sand"][a.seed % 2])
    if soil_name not in LAB:
        refuse(f"unknown soil {soil_name!r}")
    lab = LAB[soil_name]
    u = lab["unc"]
    fmt = P.get("fmt", ["log", "blf", "asc"][a.seed % 3])
    duration = float(P.get("duration", 120 + 10 * rng.integers(0, 4)))  # 120..150 s

    # ---- true field soil: lab moved within its uncertainty (|z| <= 1) ---------------
    z = np.clip(rng.normal(0, 0.5, 5), -1, 1)
    zk = dict(zip(["k", "n", "c", "phi", "K"], z))
    mism = {}
    if case == "mismatch":
        alias = {"k_eq": "k", "c_kpa": "c", "phi_deg": "phi", "K_m": "K"}
        mism = {alias.get(kk, kk): vv for kk, vv in P["mismatch"].items()}
        for key, val in mism.items():
            if key not in zk:
                refuse(f"unknown mismatch key {key}")
            if abs(val) < 2.0:
                print(f"warning: mismatch {key}={val} sd is below 2 sd", file=sys.stderr)
            zk[key] = float(val)
    k_lab = lab_k_eq(lab, b)
    true = {"k_eq": k_lab * (1 + zk["k"] * u["k_eq_rel"]), "n": lab["n"] + zk["n"] * u["n"],
            "c": (lab["c_kpa"] + zk["c"] * u["c_kpa"]) * 1000.0,
            "phi_deg": lab["phi_deg"] + zk["phi"] * u["phi_deg"], "K": lab["K_m"] + zk["K"] * u["K_m"]}
    for key, v in P.get("true_override", {}).items():
        true[key] = float(v)
    if true["c"] < 0 or true["K"] <= 0 or true["k_eq"] <= 0:
        refuse("non-physical true soil")

    # ---- vehicle, loads, towed dynamometer vehicle ---------------------------------
    W_rl = float(P.get("load_kn", rng.uniform(9.5, 12.5))) * 1000.0
    W_front = float(P.get("front_kn", rng.uniform(8.0, 9.0))) * 1000.0
    W_static = np.array([W_front, W_front * rng.uniform(0.97, 1.03), W_rl, W_rl * rng.uniform(0.97, 1.03)])
    M_veh = W_static.sum() / G
    M_tow = float(P.get("tow_mass_kg", 4800.0))
    F_tow_min = float(P.get("tow_min_kn", rng.uniform(1.2, 2.0))) * 1000.0
    wheelbase, h_hitch, h_cg = 2.9, 0.55, 0.95
    M_tot = M_veh + M_tow + 4 * I_w / r ** 2

    # ---- effect parameters -------------------------------------------------------------
    eff = {"case": {"wong_reece": "stress_distribution"}.get(case, case)}
    for key in ("H", "m1", "m2", "n1", "a1", "a2", "alpha_deg", "beta", "h", "kb", "e"):
        if key in P:
            eff[key] = float(P[key])
    dr = float(P.get("dr", 0.0)) if case == "sticky" else 0.0
    kappa = float(P.get("kappa", 0.0)) if case == "xtalk" else 0.0

    lane_L = float(P.get("lane_m", rng.uniform(35.0, 60.0)))
    ell = float(rng.uniform(2.0, 6.0))
    amp_k, amp_c, amp_phi = rng.uniform(0.025, 0.045), rng.uniform(0.02, 0.04), rng.uniform(0.01, 0.02)
    fields = []
    for track in range(2):  # left track (FL, RL), right track (FR, RR)
        xg, fk = corr_field(rng, lane_L, ell, amp_k)
        _, fc = corr_field(rng, lane_L, ell, amp_c)
        _, fp = corr_field(rng, lane_L, ell, amp_phi)
        fields.append((fk, fc, fp))
    dxg = xg[1] - xg[0]

    drift = {}
    if case == "drift":
        drift = {"mode": P.get("mode", "compaction"), "rate": float(P.get("rate", 0.25))}
        if drift["mode"] == "patch":
            drift["start_m"] = float(P.get("start_m", 0.3 * lane_L))
            drift["length_m"] = float(P.get("length_m", 0.35 * lane_L))
            drift["k_factor"] = float(P.get("k_factor", 0.6))
            drift["c_factor"] = float(P.get("c_factor", 0.6))
            drift["dphi_deg"] = float(P.get("dphi_deg", -3.0))

    def soil_at(x, track_idx, t):
        """Field soil (dict of arrays) at travelled distance x (array) on a track."""
        xm = np.mod(x, lane_L)
        i = np.minimum((xm / dxg).astype(int), len(xg) - 1)
        fk, fc, fp = fields[track_idx]
        k = true["k_eq"] * (1 + fk[i])
        c = true["c"] * (1 + fc[i])
        tphi = np.tan(np.radians(true["phi_deg"])) * (1 + fp[i])
        if drift:
            if drift["mode"] == "compaction":  # stiffer/stronger with every pass
                passes = x / lane_L
                k = k * (1 + drift["rate"] * passes)
                c = c * (1 + 0.5 * drift["rate"] * passes)
            else:
                s0, ln = drift["start_m"], drift["length_m"]
                # smooth-edged patch (0.5 m transitions)
                w = 1 / (1 + np.exp(-(xm - s0) / 0.25)) * (1 - 1 / (1 + np.exp(-(xm - s0 - ln) / 0.25)))
                k = k * (1 + (drift["k_factor"] - 1) * w)
                c = c * (1 + (drift["c_factor"] - 1) * w)
                tphi = np.tan(np.arctan(tphi) + np.radians(drift["dphi_deg"]) * w)
        nn = np.full_like(k, true["n"])
        return {"k": k, "n": nn, "c": c, "tphi": tphi, "K": np.full_like(k, true["K"])}

    def eff_at(Wstat_mean):
        e = dict(eff)
        if case == "hardpan":
            Z0n = static_sinkage(Wstat_mean, r, b, true["k_eq"], true["n"])
            e["depth"] = float(P.get("depth_frac", 0.6)) * float(Z0n)
            eff["depth"] = e["depth"]
        return e

    eff_run = eff_at(W_rl)

    # ---- feasibility: can the vehicle move at all? --------------------------------------
    s_grid = np.linspace(0.0, 0.9, 46)
    Fsum = np.zeros_like(s_grid)
    for i in range(4):
        Zs = static_sinkage(W_static[i], r, b, true["k_eq"], true["n"])
        if not np.isfinite(Zs) or Zs > 0.6 * r:
            refuse(f"static sinkage {Zs:.3f} m of wheel {i} exceeds 0.6 r: the vehicle is stuck")
        sl = soil_at(np.zeros_like(s_grid), i % 2, 0.0)
        Fsum += wheel_forces(np.full_like(s_grid, W_static[i]), s_grid, sl, r, b, eff_run,
                             V=np.full_like(s_grid, 1.2))["Dp"]
    if not np.all(np.isfinite(Fsum)):
        refuse("non-finite drawbar pull")
    if Fsum.max() < 1.25 * F_tow_min:
        refuse(f"maximum drawbar pull of the four wheels {Fsum.max()/1000:.2f} kN does not overcome "
               f"the towed vehicle's rolling resistance {F_tow_min/1000:.2f} kN")
    s_top = 0.85
    # ---- operator (brake level) and driver (wheel speed) plans -------------------------
    dt = 0.01
    t = np.arange(0.0, duration, dt)
    nT = len(t)
    segs = []  # (t0, t1, kind)
    tc = 0.0
    s_plan_knots = [(0.0, 0.0)]
    tc = 4.0  # start-up
    s_plan_knots.append((tc, 0.03))
    pause_times = sorted(rng.uniform(0.3, 0.75, int(rng.integers(1, 3))) * duration)
    pauses = []
    level = 0.03
    while tc < duration:
        if pause_times and tc > pause_times[0]:
            pt = pause_times.pop(0)
            pd = rng.uniform(3.0, 6.0)
            pauses.append((tc, tc + 2.0 + pd + 3.0))
            s_plan_knots += [(tc + 1.5, 0.0), (tc + 2 + pd + 3.0, 0.0), (tc + 2 + pd + 4.0, 0.04)]
            tc = tc + 2 + pd + 4.0
            pause_times = [pp for pp in pause_times if pp > tc + 15.0]
            level = 0.04
            continue
        if rng.random() < 0.6:
            new = rng.uniform(0.05, 0.35) if rng.random() < 0.55 else rng.uniform(0.35, s_top)
        else:
            new = float(np.clip(level + rng.normal(0, 0.15), 0.05, s_top))
        if rng.random() < 0.5:  # step (operator switches the retarder quickly)
            tr = rng.uniform(0.3, 0.8)
        else:  # ramp
            tr = rng.uniform(3.0, 9.0)
        hold = rng.uniform(2.5, 8.0)
        s_plan_knots += [(tc + tr, new), (tc + tr + hold, new)]
        tc += tr + hold
        level = new
    kt, ks = np.array(s_plan_knots).T
    s_plan = np.interp(t, kt, ks)
    # towed load as the operator sets it: the dynamometer vehicle's retarder (eddy-current type)
    # pulls back with C(t) * V; the operator sets C so that s_plan would hold at static loads
    F_plan = np.interp(s_plan, s_grid, Fsum)
    F_plan = np.maximum(F_plan * (1 + smooth_noise(rng, t, 0.2, 0.02)), F_tow_min)
    # driver: wheel surface speed rises with the load the driver feels
    v_base = float(P.get("v_base", rng.uniform(1.0, 1.5)))
    vw_cmd = v_base / (1 - 0.55 * s_plan) * (1 + smooth_noise(rng, t, 0.5, 0.01))
    for (p0, p1) in pauses:  # stop: down 2 s, stand, up 3 s
        sd = p1 - p0 - 5.0
        fac = np.interp(t, [p0, p0 + 2, p0 + 2 + sd, p1], [1, 0, 0, 1], left=1, right=1)
        vw_cmd *= fac
    vw_cmd *= np.clip(t / 4.0, 0, 1) ** 1.5  # start-up from standstill
    C_ret = F_plan / np.maximum(vw_cmd * (1 - s_plan), 0.15)  # N s/m
    # driveline lag
    from scipy.signal import lfilter
    al = np.exp(-dt / 0.35)
    vw = lfilter([1 - al], [1, -al], vw_cmd, zi=[0.0])[0]
    r_t = r + dr * t / duration  # sticky soil: rolling radius grows
    omega = vw / r
    domega = np.gradient(omega, dt)
    bounce = [smooth_noise(rng, t, 2.5, rng.uniform(0.015, 0.03)) for _ in range(4)]

    # ---- Newton: vehicle speed from the four wheels' pull minus the towed load ----------
    V = np.zeros(nT)
    x = np.zeros(nT)
    Wt = np.zeros((nT, 4))
    st = np.zeros((nT, 4))
    g_op = 1.0
    F_tow_act = np.zeros(nT)
    acc = np.zeros(nT)
    offs = np.array([wheelbase, wheelbase, 0.0, 0.0])
    tracks = [0, 1, 0, 1]
    transfer = np.array([-1, -1, 1, 1]) * 0.5 / wheelbase
    dmass = 2 * np.pi * r * b * dr * 1400.0  # adhering soil mass at the end (sticky)
    for i in range(nT - 1):
        v = V[i]
        running = v > 0.02 or omega[i] > 0.05
        Ccur = C_ret[i] * g_op
        Ft = max(Ccur * v, F_tow_min) if running else 0.0
        W = W_static + transfer * (Ft * h_hitch + M_tot * acc[max(i - 1, 0)] * h_cg) + W_static * np.array(
            [bounce[j][i] for j in range(4)])
        W = W + dmass * G * t[i] / duration / 2 * np.array([0, 0, 1, 1])
        rw = r_t[i] * omega[i]
        if rw < 0.01 and v < 0.01:
            V[i + 1] = 0.0
            x[i + 1] = x[i]
            Wt[i] = W
            st[i] = 0.0
            F_tow_act[i] = Ft
            continue
        den = max(rw, 0.02)
        s0 = np.full(4, np.clip((rw - v) / den, -0.6, 0.99))
        ds = 1e-3
        sl = {kk: np.empty(8) for kk in ("k", "n", "c", "tphi", "K")}
        for j in range(4):
            sj = soil_at(np.array([x[i] + offs[j]]), tracks[j], t[i])
            for kk in sl:
                sl[kk][j] = sl[kk][j + 4] = sj[kk][0]
        res = wheel_forces(np.concatenate([W, W]), np.concatenate([s0, s0 + ds]), sl,
                           np.full(8, r_t[i]), b, eff_run, V=np.full(8, max(v, 0.0)))["Dp"]
        F0 = res[:4].sum()
        dFds = (res[4:].sum() - F0) / ds
        # linearised backward Euler in V: F(V') ~ F0 + dFds * (-(V'-v)/den)
        if Ccur * v > F_tow_min:  # retarder force C*V taken implicitly too
            Vn = (M_tot / dt * v + F0 + dFds * v / den) / (M_tot / dt + dFds / den + Ccur)
        else:
            Vn = (M_tot / dt * v + F0 - Ft + dFds * v / den) / (M_tot / dt + dFds / den)
        if Vn < 0:
            Vn = 0.0
        V[i + 1] = Vn
        acc[i] = (Vn - v) / dt
        x[i + 1] = x[i] + 0.5 * (v + Vn) * dt
        Wt[i] = W
        st[i] = s0
        F_tow_act[i] = Ft
        # operator relieves the retarder when the vehicle bogs down, restores it slowly
        if s0[2] > 0.9:
            g_op = max(0.3, g_op - 0.6 * dt)
        elif g_op < 1.0:
            g_op = min(1.0, g_op + 0.15 * dt)
    Wt[-1] = Wt[-2]
    st[-1] = st[-2]
    F_tow_act[-1] = F_tow_act[-2]
    if x[-1] < 10.0:
        refuse(f"the vehicle moved only {x[-1]:.1f} m")

    # ---- rear-left wheel signals at 500 Hz ---------------------------------------------
    fs = 500.0
    tw = np.arange(0.0, duration - 0.05, 1 / fs)
    Vw = np.interp(tw, t, V)
    om = np.interp(tw, t, omega)
    Ww = np.interp(tw, t, Wt[:, 2])
    xw = np.interp(tw, t, x)
    rtw = np.interp(tw, t, r_t)
    dV = np.interp(tw, t, np.gradient(V, dt))
    dom = np.interp(tw, t, domega)
    rww = rtw * om
    sw = np.where(rww > 0.02, (rww - Vw) / np.maximum(rww, 0.02), 0.0)
    sw = np.clip(sw, -0.6, 0.99)
    moving = (rww > 0.01) | (Vw > 0.01)
    Dp = np.zeros_like(tw)
    Tq = np.zeros_like(tw)
    Fy = np.zeros_like(tw)
    Zr = np.zeros_like(tw)
    idx = np.nonzero(moving)[0]
    for c0 in range(0, len(idx), 4000):
        ii = idx[c0:c0 + 4000]
        sl = soil_at(xw[ii], 0, tw[ii])
        res = wheel_forces(Ww[ii], sw[ii], sl, rtw[ii], b, eff_run, V=Vw[ii])
        Dp[ii], Tq[ii], Fy[ii], Zr[ii] = res["Dp"], res["T"], res["Fy"], res["Z"]
    m_eff = m_w + dmass * tw / duration
    I_eff = I_w + dmass * tw / duration * rtw ** 2
    Fx_hub = Dp - m_eff * dV
    My_hub = Tq + I_eff * dom
    Fz_hub = Ww - dmass * G * tw / duration  # adhering soil weight is not zeroed by the vendor
    ang = np.cumsum(om) / fs  # rad
    ang0 = rng.uniform(0, 2 * np.pi)
    a_rad = ang + ang0
    # rotating-transducer crosstalk of imperfect compensation (1/rev and 2/rev)
    xt = {"fx1": rng.uniform(0.012, 0.03), "fx2": rng.uniform(0.005, 0.015),
          "fz1": rng.uniform(0.012, 0.03), "fz2": rng.uniform(0.005, 0.015),
          "my1": rng.uniform(0.001, 0.003), "my2": rng.uniform(0.0005, 0.0015)}
    ph = rng.uniform(0, 2 * np.pi, 6)
    Fx_m = Fx_hub + Ww * (xt["fx1"] * np.sin(a_rad + ph[0]) + xt["fx2"] * np.sin(2 * a_rad + ph[1]))
    Fz_m = Fz_hub + Ww * (xt["fz1"] * np.sin(a_rad + ph[2]) + xt["fz2"] * np.sin(2 * a_rad + ph[3]))
    My_m = My_hub + Ww * r * (xt["my1"] * np.sin(a_rad + ph[4]) + xt["my2"] * np.sin(2 * a_rad + ph[5]))
    My_m = My_m + kappa * Fx_hub  # xtalk effect: Fx leaks into My
    nw = len(tw)
    Fx_m += rng.normal(0, 25.0, nw)
    Fz_m += rng.normal(0, 45.0, nw)
    My_m += rng.normal(0, 6.0, nw)
    Fy_m = Fy + rng.normal(0, 20.0, nw)
    Mx_h = -Fy * (r - Zr) * 0.5 + rng.normal(0, 5.0, nw)
    Mz_h = rng.normal(0, 4.0, nw) + 0.02 * Fx_hub
    ca, sa = np.cos(a_rad), np.sin(a_rad)
    Fx_w = ca * Fx_m - sa * Fz_m
    Fz_w = sa * Fx_m + ca * Fz_m
    Mx_w = ca * Mx_h - sa * Mz_h
    Mz_w = sa * Mx_h + ca * Mz_h
    ang_deg = np.mod(np.degrees(a_rad) + rng.normal(0, 0.01, nw), 360.0)
    ang_deg = np.where(ang_deg >= 359.99, 0.0, ang_deg)

    # ---- frames ---------------------------------------------------------------------------
    import cantools
    import can
    dbw = cantools.database.load_file(os.path.join(DBC_DIR, "wft.dbc"))
    dbs = cantools.database.load_file(os.path.join(DBC_DIR, "wheel_speed.dbc"))
    dbg = cantools.database.load_file(os.path.join(DBC_DIR, "gps_rt_speedbox.dbc"))
    mF, mM, mA, mD = (dbw.get_message_by_name(n) for n in ("WFT_RL_Force", "WFT_RL_Moment", "WFT_RL_Angle", "WFT_RL_Diag"))
    mWS, mWSt = dbs.get_message_by_name("WSS_WheelSpeeds"), dbs.get_message_by_name("WSS_Status")
    mGS, mGV, mGT, mGSt = (dbg.get_message_by_name(n) for n in ("RT_SB_GPS_Speed", "RT_SB_INS_Vel_Body_Axes",
                                                                  "RT_SB_GPS_Time", "RT_SB_GPS_Status"))
    T0 = 1718000000.0 + (a.seed % 997) * 3600.0 + 0.123456
    frames = []  # (host_time, bus, msg, data dict)

    # spikes (EMI) on single WFT frames
    n_sp = int(rng.integers(3, 8))
    sp_idx = set(rng.choice(np.arange(500, nw - 500), n_sp, replace=False).tolist())
    spikes = []
    clip = lambda v, lo, hi: float(min(max(v, lo), hi))
    q = lambda v, sc: round(v / sc) * sc
    drift_clk = rng.uniform(-20e-6, 20e-6)
    for k in range(nw):
        th = T0 + tw[k] * (1 + drift_clk) + 0.0012
        df = {"Fx_w": clip(q(Fx_w[k], 0.5), -16384, 16383.5), "Fy_w": clip(q(Fy_m[k], 0.5), -16384, 16383.5),
              "Fz_w": clip(q(Fz_w[k], 1), -32768, 32767), "Counter": k % 256, "Status": 0}
        dm = {"Mx_w": clip(q(Mx_w[k], 0.25), -8192, 8191.75), "My": clip(q(My_m[k], 0.25), -8192, 8191.75),
              "Mz_w": clip(q(Mz_w[k], 0.25), -8192, 8191.75), "Counter": k % 256, "Status": 0}
        if k in sp_idx:
            which = ["Fx_w", "Fz_w", "My"][k % 3]
            mag = float(rng.choice([-1, 1]) * rng.uniform(2000, 5000)) if which != "My" else float(
                rng.choice([-1, 1]) * rng.uniform(400, 1200))
            tgt = dm if which == "My" else df
            lim = {"Fx_w": (-16384, 16383.5), "Fz_w": (-32768, 32767), "My": (-8192, 8191.75)}[which]
            tgt[which] = clip(q(tgt[which] + mag, 0.25 if which == "My" else (0.5 if which == "Fx_w" else 1)), *lim)
            spikes.append({"t_s": round(float(tw[k]), 4), "signal": which, "delta": round(mag, 1)})
        da = {"WheelAngle": clip(q(ang_deg[k], 0.0054931640625), 0, 359.9945), "Counter": k % 256, "Status": 0}
        frames.append((th, 0, mF, df))
        frames.append((th + 0.00013, 0, mM, dm))
        frames.append((th + 0.00025, 0, mA, da))
    for i in range(int(duration) - 1):
        temp = 24.0 + 6.0 * i / duration + rng.normal(0, 0.05)
        frames.append((T0 + i + 0.1, 0, mD, {"DiagMux": 0, "BridgeTemp": q(temp, 0.01), "SupplyVoltage": q(12.2 + rng.normal(0, 0.02), 0.001)}))
        frames.append((T0 + i + 0.4, 0, mD, {"DiagMux": 1, "SerialNumber": 90210417}))
        frames.append((T0 + i + 0.7, 0, mD, {"DiagMux": 2, "FirmwareMajor": 3, "FirmwareMinor": 7, "CalibrationId": 4711}))
    # wheel speeds 100 Hz
    t_ws = np.arange(0.0, duration - 0.05, 0.01)
    rpm_rl = np.interp(t_ws - 0.004, t, omega) * 60 / (2 * np.pi)
    fac = np.array([1.0 + rng.normal(0, 0.003) for _ in range(4)])
    fac[2] = 1.0
    for k, tk in enumerate(t_ws):
        vals = {}
        for j, nm in enumerate(("WheelSpeed_FL", "WheelSpeed_FR", "WheelSpeed_RL", "WheelSpeed_RR")):
            vals[nm] = clip(q(abs(rpm_rl[k] * fac[j] + rng.normal(0, 0.04)), 0.01), 0, 655.35)
        frames.append((T0 + tk + 0.0031, 1, mWS, vals))
        if k % 10 == 0:
            frames.append((T0 + tk + 0.0036, 1, mWSt, {"RollingCounter": (k // 10) % 16, "SensorFault_FL": 0,
                                                      "SensorFault_FR": 0, "SensorFault_RL": 0, "SensorFault_RR": 0}))
    # GNSS 20 Hz, late by latency, outages
    lat = float(P.get("gnss_latency_s", rng.uniform(0.03, 0.18)))
    outages = []
    tcur = 8.0
    for _ in range(int(rng.integers(1, 4))):
        st0 = float(rng.uniform(tcur, tcur + duration / 3))
        if st0 > duration - 10:
            break
        d = float(rng.uniform(1.0, 4.0))
        outages.append((round(st0, 3), round(st0 + d, 3)))
        tcur = st0 + d + 5
    in_out = lambda tt: any(o0 <= tt < o1 for o0, o1 in outages)
    gps_week = 2316 + (a.seed % 5)
    tow0 = 200000.0 + (a.seed % 1000) * 37.0 + 0.05 * int(rng.integers(0, 20))
    tan_a = np.tan(np.radians(eff.get("alpha_deg", 0.0))) if case == "steer" else 0.0
    t_g = np.arange(0.0, duration - 0.3, 0.05)
    Vg = np.interp(t_g, t, V)
    for k, te in enumerate(t_g):
        if in_out(te):
            continue
        th = T0 + te + lat + abs(rng.normal(0, 0.002))
        v = Vg[k] + rng.normal(0, 0.012)
        v2 = abs(v)
        frames.append((th, 1, mGS, {"GPS_Speed_3D": clip(q(np.hypot(v2, rng.normal(0, 0.01)), 1e-4), 0, 1675),
                                    "GPS_Speed_2D": clip(q(v2, 1e-4), 0, 1675), "Accuracy_GPS_Speed": 2,
                                    "Validity_GPS_Speed_3D": 1, "Validity_GPS_Speed_2D": 1}))
        frames.append((th + 0.00031, 1, mGV, {"INS_Vel_Sideways_2D": q(Vg[k] * tan_a + rng.normal(0, 0.01), 1e-4),
                                             "INS_Vel_Forwards_2D": q(Vg[k] + rng.normal(0, 0.01), 1e-4),
                                             "Accuracy_INS_Vel_Body": 3, "Validity_INS_Vel_Sideways": 1,
                                             "Validity_INS_Vel_Forwards": 1}))
        frames.append((th + 0.00062, 1, mGT, {"GPS_Week": gps_week, "GPS_Time": q(tow0 + te, 0.001),
                                             "Accuracy_GPS_Time": 1, "Validity_GPS_Week": 1, "Validity_GPS_Time": 1}))
        if k % 20 == 0:
            frames.append((th + 0.0009, 1, mGSt, {"RTK_Status": 0, "GPS_nSv_RTK": 0, "GPS_nSv_2": 0,
                                                  "GPS_nSv": int(rng.integers(11, 16)), "Firmware_Version_Minor": 2,
                                                  "Firmware_Version_Intermediate": 4, "Firmware_Version_Major": 1,
                                                  "GPS_Status": 11}))
    # bursts of lost frames per bus
    bursts = []
    for bus in (0, 1):
        for _ in range(int(rng.integers(1, 4))):
            b0 = float(rng.uniform(5, duration - 5))
            bursts.append((bus, round(b0, 3), round(b0 + float(rng.uniform(0.1, 0.5)), 3)))
    jit = rng.normal(0, 6e-5, len(frames))
    msgs = []
    for (th, bus, m, d), jj in zip(frames, jit):
        rel = th - T0
        if any(bb == bus and b0 <= rel < b1 for bb, b0, b1 in bursts):
            continue
        msgs.append((th + abs(jj), bus, m, d))
    msgs.sort(key=lambda z_: z_[0])

    os.makedirs(a.outdir, exist_ok=True)
    path = os.path.join(a.outdir, f"{a.out}.{fmt}")
    if os.path.exists(path):
        os.remove(path)
    writer = can.Logger(path)
    for th, bus, m, d in msgs:
        data = m.encode(d, scaling=True, strict=True)
        writer.on_message_received(can.Message(timestamp=round(th, 6), arbitration_id=m.frame_id,
                                               is_extended_id=m.is_extended_frame, data=data,
                                               channel=f"can{bus}", is_rx=True))
    writer.stop()
    if os.environ.get("F9_DUMP"):  # check.py: the first encoded frames, for a decode round trip
        with open(os.environ["F9_DUMP"], "w") as fh:
            json.dump([{"t": round(th, 6), "id": m.frame_id, "bus": bus, "sig": d} for th, bus, m, d in msgs[:80]], fh)
    if fmt == "asc":  # the writer stamps the wall-clock date in the header: make it deterministic
        with open(path) as fh:
            lines = fh.readlines()
        for i, ln in enumerate(lines[:3]):
            if ln.startswith("date "):
                lines[i] = "date " + datetime.utcfromtimestamp(T0).strftime("%a %b %d %I:%M:%S.000 %p %Y") + "\n"
        with open(path, "w") as fh:
            fh.writelines(lines)

    # ---- truth ------------------------------------------------------------------------------
    fam = "in" if case in IN_FAMILY else "out"
    acc_v = IN_FAMILY.get(case, ["unexplained"])
    if fam == "out" and P.get("small", False):
        acc_v = ["unexplained", "none"]
    fam_case = {"vasilev": "slip_sinkage", "lyasko": "slip_sinkage", "ding": "slip_sinkage",
                "mismatch": "terrain_mismatch", "wong_reece": "stress_distribution", "drift": "terrain_drift"}
    rel = os.path.join("benchmarks", "foreign9", f"lab_{soil_name}.toml")  # relative to the project root
    fit_args = [f"{a.out}.{fmt}", "--terrain", rel, "--wheel-radius", f"{r}", "--wheel-width", f"{b}",
                "--wheel-mass", f"{m_w}", "--wheel-inertia", f"{I_w}"]
    mov = rww > 0.3
    s_mov = sw[mov]
    eff_params = {kk: vv for kk, vv in P.items() if kk not in ("soil", "fmt", "duration", "small")}
    if case == "hardpan":
        eff_params["depth_m"] = round(eff["depth"], 4)
    if case == "sticky":
        eff_params["added_mass_end_kg"] = round(dmass, 2)
    truth = {
        "name": a.out, "case": case, "family": fam, "acceptable_verdicts": acc_v,
        "params": {
            "seed": a.seed, "effect": eff_params, "soil": soil_name,
            "true_soil": {"k_eq_kN_m_n2": round(true["k_eq"] / 1000, 3), "n": round(true["n"], 4),
                          "c_kpa": round(true["c"] / 1000, 4), "phi_deg": round(true["phi_deg"], 3),
                          "K_m": round(true["K"], 5), "z_sd": {kk: round(float(v), 3) for kk, v in zk.items()}},
            "lab_soil": {kk: lab[kk] for kk in ("c_kpa", "phi_deg", "K_m", "n", "kc", "kphi")} | {
                "k_eq_kN_m_n2": round(k_lab / 1000, 3), "uncertainty": lab["unc"], "toml": rel},
            "gnss_latency_s": round(lat, 4),
            "wheel": dict(WHEEL),
            "vehicle": {"static_loads_N": [round(float(v), 1) for v in W_static], "mass_kg": round(M_veh, 1),
                        "tow_mass_kg": M_tow, "tow_min_N": round(F_tow_min, 1)},
            "procedure": {"kind": "tow: dynamometer vehicle retarding force in steps/ramps, driver holds throttle",
                          "duration_s": duration, "lane_length_m": round(lane_L, 2),
                          "distance_m": round(float(x[-1]), 2), "passes": round(float(x[-1] / lane_L), 2),
                          "pauses_s": [[round(p0, 2), round(p1, 2)] for p0, p1 in pauses],
                          "v_base_mps": round(v_base, 3), "slip_plan_top": round(s_top, 3),
                          "slip_quantiles_moving": [round(float(v), 3) for v in np.quantile(s_mov, [0.05, 0.25, 0.5, 0.75, 0.95])] if len(s_mov) else [],
                          "format": fmt},
            "realism": {"soil_field": {"corr_length_m": round(ell, 2), "sd_k": round(amp_k, 4),
                                       "sd_c": round(amp_c, 4), "sd_tanphi": round(amp_phi, 4)},
                        "wft_crosstalk": {kk: round(v, 4) for kk, v in xt.items()},
                        "gnss_outages_s": outages, "lost_frame_bursts": [list(bb) for bb in bursts],
                        "wft_spikes": spikes, "timestamp_jitter_sd_s": 6e-5, "host_t0": T0},
        },
        "fit_args": fit_args,
    }
    if case in ("vasilev", "lyasko", "ding"):
        truth["form"] = case
    if case == "drift":
        truth["params"]["effect"].update(drift)
    with open(os.path.join(a.outdir, f"{a.out}_truth.json"), "w") as fh:
        json.dump(truth, fh, indent=1, sort_keys=False)
    print(f"wrote {path} ({os.path.getsize(path)/1e6:.2f} MB, {len(msgs)} frames)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
