#!/usr/bin/env python3
"""foreign11 blind test-data generator (see README.md).

gen.py CASE --seed S --out NAME --outdir DIR [--p key=value ...]
"""
import argparse, json, os, sys, struct
import numpy as np
from scipy.interpolate import CubicSpline
from scipy.signal import lfilter

HERE = os.path.dirname(os.path.abspath(__file__))
G = 9.81
IN_CASES = ["none", "vasilev", "lyasko", "ding", "terrain_mismatch", "stress_distribution", "terrain_drift"]
OUT_CASES = ["tyre_deflation", "root_mat", "shear_rate", "cross_slope", "mud_buildup", "hardpan", "wft_thermal"]
CASES = IN_CASES + OUT_CASES

# lab values (SI: Pa, deg, m, N/m^(n+1), N/m^(n+2)); sd = one lab standard deviation
SOILS = {
    "loam": dict(c=2600.0, phi=27.5, K=0.018, n=0.72, kc=14.0e3, kphi=1650e3,
                 sd=dict(c=400.0, phi=1.5, K=0.004, n=0.04, keq=0.15)),
    "wetsand": dict(c=900.0, phi=31.0, K=0.012, n=0.95, kc=2.8e3, kphi=2600e3,
                    sd=dict(c=200.0, phi=1.2, K=0.003, n=0.04, keq=0.15)),
}
WHEELS = {  # rigid-wheel radius, width, rim+tyre mass, polar inertia
    "A": dict(r=0.445, b=0.305, m=62.0, I=7.9),   # 35x12.5R17 on steel rim
    "B": dict(r=0.410, b=0.270, m=48.0, I=5.2),   # 32x11.5R15
}
VEH = dict(M0=2900.0, L=2.80, h=0.85, rear_share=0.58, T_max=5500.0, rpm_max=600.0)

# ---------------------------------------------------------------- quadrature
_U, _WU = np.polynomial.legendre.leggauss(64)
_U = 0.5 * (_U + 1.0); _WU = 0.5 * _WU
Q = 3.0  # power transform clustering nodes at the singular end of sigma ~ z^n


def _nodes_end(a, b):
    """nodes on [a,b] clustered at b: theta = b-(b-a)(1-u)^Q. a,b shape (N,1)."""
    th = b - (b - a) * (1 - _U) ** Q
    w = _WU * Q * (b - a) * (1 - _U) ** (Q - 1)
    return th, w


def _nodes_start(a, b):
    """nodes on [a,b] clustered at a."""
    th = a + (b - a) * _U ** Q
    w = _WU * Q * (b - a) * _U ** (Q - 1)
    return th, w


def sinkage(W, r, b, n, kc, kphi, s, eff):
    sp = np.maximum(s, 0.0)
    N = n + eff.get("n1", 0.0) * sp
    base = 3 * W / (np.sqrt(2 * r) * (kc + b * kphi) * (3 - N))
    Z0 = base ** (2 / (2 * N + 1))                       # Eq. (10)
    Z = Z0 + eff.get("H", 0.0) * sp                       # Eq. (11)
    Z = Z * (1 + eff.get("m1", 0.0) * sp) / (1 - eff.get("m2", 0.0) * sp)  # Eq. (12)
    if "pan_depth" in eff:
        d = eff["pan_depth"]; Z = d * (1 - np.exp(-Z / d))
    return np.minimum(Z, 0.9 * r), N


def integrals(s, th1, r, b, c, phi, K, N, kc, kphi, eff, V=None):
    """returns (I_tc, I_ss, I_t, I_ty, I_sc, I_ts): integrals of tau cos, sigma sin, tau, tau_y, sigma cos, tau sin."""
    col = lambda x: np.asarray(x, float).reshape(-1, 1) if np.ndim(x) else float(x)
    s, th1, r, b, c, phi, K, N, kc, kphi = map(col, (s, th1, r, b, c, phi, K, N, kc, kphi))
    k = kc / b + kphi                                      # Eq. (2), corrected
    parts = []
    if "a1" in eff:                                        # Wong-Reece
        thm = (eff["a1"] + eff["a2"] * np.maximum(s, 0)) * th1
        thf, wf = _nodes_end(thm, th1)
        sf = k * np.maximum(r * (np.cos(thf) - np.cos(th1)), 0) ** N
        thr, wr = _nodes_start(0.0 * th1, thm)
        arg = th1 - thr / thm * (th1 - thm)
        sr = k * np.maximum(r * (np.cos(arg) - np.cos(th1)), 0) ** N
        parts = [(thf, wf, sf), (thr, wr, sr)]
    else:
        th, w = _nodes_end(0.0 * th1, th1)
        sg = k * np.maximum(r * (np.cos(th) - np.cos(th1)), 0) ** N   # Eq. (3), corrected
        parts = [(th, w, sg)]
    out = np.zeros((6,) + np.broadcast(s, th1).shape[:1])
    tphi = np.tan(np.radians(phi))
    for th, w, sg in parts:
        jx = r * (th1 - th - (1 - s) * (np.sin(th1) - np.sin(th)))     # Eq. (5)
        jy = r * (1 - s) * (th1 - th) * np.tan(np.radians(eff.get("alpha_deg", 0.0)))
        j = np.sqrt(jx ** 2 + jy ** 2) + 1e-15
        cc = c
        if "c_mat" in eff:
            cc = c + eff["c_mat"] * eff["_mat_on"] * np.exp(-j / eff["j_tear"])
        tau = (cc + sg * tphi) * (1 - np.exp(-j / K))                    # Eq. (4)
        if "beta_rate" in eff:
            vj = np.abs(eff["_romega"] * (1 - (1 - s) * np.cos(th)))
            tau = tau * (1 + eff["beta_rate"] * np.log1p(vj / 0.2))
        tx = tau * jx / j; ty = tau * jy / j
        for i, f in enumerate((tx * np.cos(th), sg * np.sin(th), tx, ty, sg * np.cos(th), tx * np.sin(th))):
            out[i] += np.sum(f * w, axis=-1)
    return out


def wheel_forces(s, W, r, b, soil, eff, rc=None):
    """Dp, T, Fy, Z, th1 (Eqs. 1,4-10). soil values may be arrays. rc: moment arm (rolling radius)."""
    n, kc, kphi = soil["n"], soil["kc"], soil["kphi"]
    Z, N = sinkage(W, r, b, n, kc, kphi, s, eff)
    th1 = np.arccos(1 - Z / r)                             # Eq. (1)
    I = integrals(s, th1, r, b, soil["c"], soil["phi"], soil["K"], N, kc, kphi, eff)
    Dp = r * b * (I[0] - I[1])                             # Eq. (8)
    T = r * r * b * I[2]                                   # Eq. (9)
    if rc is not None:
        T = T * rc / r
    Fy = r * b * I[3]
    return Dp, T, Fy, Z, th1


# ---------------------------------------------------------------- run design
def design(case, seed, over):
    rng = np.random.default_rng(seed * 7919 + 11)
    p = {}
    p["soil"] = ["loam", "wetsand"][int(rng.integers(2))]
    p["wheel"] = ["A", "B"][int(rng.integers(2))]
    p["ballast_kg"] = float(rng.uniform(0, 400))
    p["gnss_latency_s"] = float(rng.uniform(0.03, 0.2))
    p["n_cycles"] = int(rng.integers(11, 14))
    p["s_max"] = float(rng.uniform(0.8, 0.88))
    p["s_min"] = float(rng.uniform(0.02, 0.04))
    p["s_brake"] = float(rng.uniform(-0.2, -0.1))
    p["v_crawl"] = float(rng.uniform(1.0, 1.6))
    p["gnss_outage"] = bool(rng.random() < 0.5)
    p["field_dev_sd"] = {k: float(rng.uniform(-0.3, 0.3)) for k in ("c", "phi", "K", "n", "keq")}
    eff = {}
    if case == "vasilev":
        eff["H"] = float(rng.uniform(0.012, 0.03))
    elif case == "lyasko":
        eff["m1"] = float(rng.uniform(0.15, 0.45)); eff["m2"] = float(rng.uniform(0.02, 0.06))
    elif case == "ding":
        eff["n1"] = float(rng.uniform(0.2, 0.45))
    elif case == "terrain_mismatch":
        keys = list(rng.choice(["c", "phi", "K", "n", "keq"], size=int(rng.integers(1, 3)), replace=False))
        for k in keys:
            p["field_dev_sd"][str(k)] = float(rng.choice([-1, 1]) * rng.uniform(2.5, 4.0))
        eff["shifted"] = [str(k) for k in keys]
    elif case == "stress_distribution":
        eff["a1"] = float(rng.uniform(0.15, 0.3)); eff["a2"] = float(rng.uniform(0.1, 0.25))
    elif case == "terrain_drift":
        eff["drift_end_sd"] = {"keq": float(rng.choice([-1, 1]) * rng.uniform(3.0, 4.5)),
                               "phi": float(rng.choice([-1, 1]) * rng.uniform(2.0, 3.5))}
        eff["drift_shape"] = "sigmoid along distance, centre at 40-60 % of the run"
        eff["drift_centre_frac"] = float(rng.uniform(0.4, 0.6))
    elif case == "tyre_deflation":
        eff["p0_kpa"] = float(rng.uniform(220, 260)); eff["p_end_kpa"] = float(rng.uniform(80, 120))
    elif case == "root_mat":
        eff["c_mat"] = float(rng.uniform(3000, 6000)); eff["j_tear"] = float(rng.uniform(0.02, 0.05))
        eff["mat_depth"] = None  # set from static sinkage below
    elif case == "shear_rate":
        eff["beta_rate"] = float(rng.uniform(0.04, 0.07))
    elif case == "cross_slope":
        eff["slope_deg"] = float(rng.uniform(8, 14)); eff["alpha_deg"] = float(rng.uniform(3, 6))
        eff["left_downhill"] = bool(rng.random() < 0.5)
    elif case == "mud_buildup":
        eff["mud_max_kg"] = float(rng.uniform(15, 30)); eff["mud_rate_kg_per_m"] = float(rng.uniform(0.15, 0.4))
    elif case == "hardpan":
        eff["pan_depth_frac"] = float(rng.uniform(0.45, 0.65))
    elif case == "wft_thermal":
        eff["dT_K"] = float(rng.uniform(30, 45)); eff["my_zero_drift_Nm_per_K"] = float(rng.uniform(3, 5)) * float(rng.choice([-1, 1]))
        eff["gain_drift_per_K"] = -0.0015
    for kv in over:
        k, v = kv.split("=", 1)
        try:
            v = json.loads(v)
        except Exception:
            pass
        if k in eff or k.startswith("eff."):
            eff[k.replace("eff.", "")] = v
        else:
            p[k] = v
    p["effect"] = eff
    return p, rng


def field_soil(p, sdev=None):
    lab = SOILS[p["soil"]]; sd = lab["sd"]; d = sdev or p["field_dev_sd"]
    w = WHEELS[p["wheel"]]
    keq_lab = lab["kc"] / w["b"] + lab["kphi"]
    f = 1 + d["keq"] * sd["keq"]
    return dict(c=max(lab["c"] + d["c"] * sd["c"], 50.0), phi=lab["phi"] + d["phi"] * sd["phi"],
                K=max(lab["K"] + d["K"] * sd["K"], 0.003), n=lab["n"] + d["n"] * sd["n"],
                kc=lab["kc"] * f, kphi=lab["kphi"] * f, keq=keq_lab * f)


class Refused(Exception):
    pass


# ---------------------------------------------------------------- simulation
def simulate(case, p, rng):
    wh = WHEELS[p["wheel"]]; r, b = wh["r"], wh["b"]
    eff = dict(p["effect"])
    soil0 = field_soil(p)
    M = VEH["M0"] + p["ballast_kg"]
    Wr0 = (VEH["M0"] * G * VEH["rear_share"] + p["ballast_kg"] * G * 0.8) / 2
    Wf0 = (M * G - 2 * Wr0) / 2
    slope = np.radians(eff.get("slope_deg", 0.0))
    if case == "cross_slope":
        sgn = 1 if eff["left_downhill"] else -1
        Wr0 = Wr0 * np.cos(slope) + sgn * Wr0 * 2 * VEH["h"] / 1.65 * np.sin(slope)
    if case == "root_mat":
        Zs, _ = sinkage(Wr0, r, b, soil0["n"], soil0["kc"], soil0["kphi"], 0.0, {})
        eff["mat_depth"] = float(Zs * rng.uniform(1.05, 1.2)); p["effect"]["mat_depth"] = eff["mat_depth"]
    if case == "hardpan":
        Zs, _ = sinkage(Wr0, r, b, soil0["n"], soil0["kc"], soil0["kphi"], 0.0, {})
        eff["pan_depth"] = float(Zs * eff["pan_depth_frac"] * 1.6); p["effect"]["pan_depth_m"] = eff["pan_depth"]
    # schedule durations
    dt = 0.02
    # state machine
    V = p["v_crawl"]; s_ref = 0.05; x = 0.0
    cyc = 0; phase = "crawl"; tph = 0.0
    dur_crawl = lambda: float(rng.uniform(4.0, 6.5))
    Tc = dur_crawl(); Tsweep = float(rng.uniform(2.8, 4.2)); s0 = p["s_max"]
    log = []
    t = 0.0; mud = 0.0; total_est = None
    cyc_start = []
    tyre_t_end = None

    def soil_at(frac):
        if case != "terrain_drift":
            return soil0
        e = eff["drift_end_sd"]; w_ = 1 / (1 + np.exp(-(frac - eff["drift_centre_frac"]) / 0.06))
        d = dict(p["field_dev_sd"]); d["keq"] = d["keq"] + w_ * e["keq"]; d["phi"] = d["phi"] + w_ * e["phi"]
        return field_soil(p, d)

    def geom(tt, mudkg, W):
        """contact radius, rolling radius, extra mass/inertia"""
        rc = r; rr = r; dm = 0.0; dI = 0.0
        if case == "tyre_deflation":
            frac = np.minimum(tt / 150.0, 1.0)
            pk = eff["p0_kpa"] + (eff["p_end_kpa"] - eff["p0_kpa"]) * frac
            kt = 60e3 + 800.0 * pk           # N/m, tyre vertical stiffness
            dl = W / kt
            rc = r + 2.5 * (dl - Wr0 / (60e3 + 800.0 * eff["p0_kpa"]))
            rr = r - (dl - Wr0 / (60e3 + 800.0 * eff["p0_kpa"])) / 3
        if case == "mud_buildup":
            h = mudkg / (1700.0 * 2 * np.pi * r * b)
            rc = rr = r + h; dm = mudkg; dI = mudkg * (r + h / 2) ** 2
        return rc, rr, dm, dI

    total_dist_guess = 150.0 * 4.0
    while True:
        # phase logic
        if phase == "crawl":
            tgt = np.clip(0.06 + 0.25 * (p["v_crawl"] - V), -0.1, 0.4)
            if tph >= Tc:
                if cyc >= p["n_cycles"]:
                    break
                phase = "launch"; tph = 0.0; cyc_start.append(t)
        if phase == "launch":
            tgt = s0
            if s_ref > s0 - 0.01 or tph > 2.0:
                phase = "sweep"; tph = 0.0; s_start = s_ref
        if phase == "sweep":
            tgt = s_start + (p["s_min"] - s_start) * min(tph / Tsweep, 1.0)
            if tph >= Tsweep + 0.6 or V > 10.0:
                phase = "brake"; tph = 0.0
        if phase == "brake":
            tgt = p["s_brake"]
            if V <= p["v_crawl"] + 0.05:
                phase = "crawl"; tph = 0.0; Tc = dur_crawl(); cyc += 1
                Tsweep = float(rng.uniform(2.8, 4.2))
        tau_f = 0.25 if phase == "launch" else 0.12
        s_ref += (tgt - s_ref) * dt / tau_f
        s_ref = min(s_ref, 1 - V / (r * 520 * 2 * np.pi / 60))   # motor speed governor, 520 rpm
        # forces
        a_prev = log[-1][3] if log else 0.0
        dW = M * a_prev * VEH["h"] / VEH["L"] / 2
        W = Wr0 + dW
        rc, rr, dm, dI = geom(t, mud, W)
        s_true = 1 - (1 - s_ref) * r / rr
        romega = V / (1 - s_ref)
        e2 = dict(eff)
        if case == "root_mat":
            Zs, _ = sinkage(W, rc, b, soil0["n"], soil0["kc"], soil0["kphi"], s_true, {})
            e2["_mat_on"] = 1 / (1 + np.exp((Zs - eff["mat_depth"]) / 0.003))
        if case == "shear_rate":
            e2["_romega"] = romega
        so = soil_at(x / total_dist_guess)
        Dp, T, Fy, Z, th1 = wheel_forces(np.array([s_true]), np.array([W]), rc, b, so, e2, rc=rr)
        Dp = float(Dp[0]); T = float(T[0])
        Wf = Wf0 - dW
        Zf, _ = sinkage(Wf, r, b, so["n"], so["kc"], so["kphi"], 0.0, {k: v for k, v in eff.items() if k == "pan_depth"})
        Rf = b * (so["kc"] / b + so["kphi"]) * Zf ** (so["n"] + 1) / (so["n"] + 1)
        a = (2 * Dp - 2 * Rf - 40.0 - 0.4 * V * V) / M
        log.append((t, V, s_ref, a, x, W, mud))
        V = max(V + a * dt, 0.05); x += V * dt
        if case == "mud_buildup":
            mud = min(mud + eff["mud_rate_kg_per_m"] * max(s_true, 0) * V * dt, eff["mud_max_kg"])
            if rng.random() < dt / 12.0 and mud > 5:
                mud *= rng.uniform(0.2, 0.5)
        t += dt; tph += dt
        if t > 260:
            raise Refused("run does not finish (vehicle cannot complete the sweeps)")
        if phase == "sweep" and tph > Tsweep + 0.5 and V < p["v_crawl"] + 0.6:
            raise Refused("vehicle cannot accelerate: drawbar pull below front-axle motion resistance")
        if V > 16:
            raise Refused("speed above 16 m/s")
    tail = 1.5
    L = np.array(log)
    return dict(L=L, M=M, Wr0=Wr0, geom=geom, soil_at=soil_at, soil0=soil0, eff=eff, r=r, b=b, wh=wh,
                cycle_starts=cyc_start, dist=x, duration=float(L[-1, 0]))


def build(case, seed, over):
    p, rng = design(case, seed, over)
    sim = simulate(case, p, rng)
    L = sim["L"]; r, b, wh, eff = sim["r"], sim["b"], sim["wh"], sim["eff"]
    if not (100 <= sim["duration"] <= 200):
        raise Refused(f"run length {sim['duration']:.0f}s outside 100-200 s")
    fs = 500.0
    t = np.arange(0, L[-1, 0], 1 / fs)
    csV = CubicSpline(L[:, 0], L[:, 1]); cS = CubicSpline(L[:, 0], L[:, 2])
    V = csV(t); s_ref = cS(t); dV = csV(t, 1)
    x = np.interp(t, L[:, 0], L[:, 4]); mud = np.interp(t, L[:, 0], L[:, 6])
    omega = V / (r * (1 - s_ref))
    dom = np.gradient(omega, 1 / fs)
    a_s = np.interp(t, L[:, 0], L[:, 3])
    ang = np.cumsum(omega) / fs + rng.uniform(0, 2 * np.pi)
    # loads: static + load transfer + ground roughness + tyre first harmonic
    rough = lfilter([0.02], [1, -0.98], rng.normal(0, 1, t.size)); rough *= 0.035 / (rough.std() + 1e-9)
    W = sim["Wr0"] + sim["M"] * a_s * VEH["h"] / VEH["L"] / 2
    W = W * (1 + rough + 0.012 * np.sin(ang + 0.7))
    rc, rr, dm, dI = sim["geom"](t, mud, W)
    rc = np.broadcast_to(rc, t.shape); rr = np.broadcast_to(rr, t.shape)
    dm = np.broadcast_to(dm, t.shape); dI = np.broadcast_to(dI, t.shape)
    s_true = 1 - (1 - s_ref) * r / rr
    so = sim["soil_at"](x / 600.0)
    e2 = dict(eff)
    if case == "root_mat":
        Zs, _ = sinkage(W, rc, b, so["n"], so["kc"], so["kphi"], s_true, {})
        e2["_mat_on"] = (1 / (1 + np.exp((Zs - eff["mat_depth"]) / 0.003)))[:, None]
    if case == "shear_rate":
        e2["_romega"] = (V / (1 - s_ref))[:, None]
    Dp = np.empty_like(t); T = np.empty_like(t); Fy = np.empty_like(t); Z = np.empty_like(t)
    CH = 20000
    for i in range(0, t.size, CH):
        sl = slice(i, i + CH)
        sub = {k: (v[sl] if np.ndim(v) else v) for k, v in so.items()}
        ee = {k: (v[sl] if np.ndim(v) == 2 else v) for k, v in e2.items()}
        Dp[sl], T[sl], Fy[sl], Z[sl], _ = wheel_forces(s_true[sl], W[sl], rc[sl], b, sub, ee, rc=rr[sl])
    Tmot = T + (wh["I"] + dI) * dom
    if np.percentile(Tmot, 99.9) > VEH["T_max"]:
        raise Refused(f"hub motor torque {np.percentile(Tmot, 99.9):.0f} N m exceeds {VEH['T_max']:.0f} N m")
    if omega.max() * 60 / (2 * np.pi) > VEH["rpm_max"]:
        raise Refused("wheel speed above sensor/motor range")
    if case == "cross_slope":
        Fy = Fy * (1 if eff["left_downhill"] else -1)
    # hub-frame WFT quantities (inertia terms per hardware.md)
    Fx = Dp - (wh["m"] + dm) * dV
    My = T + (wh["I"] + dI) * dom
    Fz = W.copy()
    temp = 18 + rng.uniform(-3, 3) + 6 * (1 - np.exp(-t / 120))
    gain = np.ones_like(t)
    if case == "wft_thermal":
        heat = np.cumsum(np.maximum(Tmot, 0) ** 2) / fs
        temp = temp + eff["dT_K"] * heat / heat[-1]
        gain = 1 + eff["gain_drift_per_K"] * (temp - temp[0])
        My = My + eff["my_zero_drift_Nm_per_K"] * (temp - temp[0])
    Fx = gain * Fx + rng.normal(0, 12, t.size); Fz = gain * Fz + rng.normal(0, 20, t.size)
    My = gain * My + rng.normal(0, 3, t.size); Fy = gain * Fy + rng.normal(0, 10, t.size)
    a = np.mod(ang, 2 * np.pi)
    off = dict(Fx_w=rng.normal(0, 25), Fz_w=rng.normal(0, 40), My=rng.normal(0, 4))
    Fx_w = Fx * np.cos(a) - Fz * np.sin(a) + off["Fx_w"]
    Fz_w = Fx * np.sin(a) + Fz * np.cos(a) + off["Fz_w"]
    My = My + off["My"]
    Mx_w = -Fy * (r - Z) * np.cos(a) + rng.normal(0, 3, t.size)
    Mz_w = Fy * (r - Z) * np.sin(a) + rng.normal(0, 3, t.size)
    truth_extra = dict(duration_s=float(t[-1]), distance_m=float(sim["dist"]), cycle_start_s=sim["cycle_starts"],
                       static_load_N=float(sim["Wr0"]), vehicle_mass_kg=float(sim["M"]),
                       field_soil={k: float(np.mean(v)) for k, v in so.items()},
                       wft_zero_offsets=off, slip_range=[float(s_true.min()), float(s_true.max())])
    return p, dict(t=t, V=V, omega=omega, ang=ang, Fx_w=Fx_w, Fz_w=Fz_w, Fy=Fy, Mx_w=Mx_w, Mz_w=Mz_w, My=My,
                   temp=temp, rng=rng, r=r, s_true=s_true), truth_extra


# ---------------------------------------------------------------- CAN frames
def frames(case, p, d):
    import cantools
    rng = d["rng"]; t = d["t"]; n = t.size
    host0 = 1.79e9 + rng.uniform(0, 1e7)
    out = []  # (host_time, bus, id, ext, bytes)
    # WFT 500 Hz, own clock with drift; lost frames
    tw = t * (1 + rng.normal(0, 20e-6))
    cnt = (np.arange(n) + int(rng.integers(256))) % 256
    i16 = lambda v, sc: np.clip(np.round(v / sc), -32768, 32767).astype("<i2")
    ff = np.zeros((n, 8), np.uint8)
    ff[:, 0:2] = i16(d["Fx_w"], 0.5).view(np.uint8).reshape(n, 2)
    ff[:, 2:4] = i16(d["Fy"], 0.5).view(np.uint8).reshape(n, 2)
    ff[:, 4:6] = i16(d["Fz_w"], 1.0).view(np.uint8).reshape(n, 2)
    ff[:, 6] = cnt
    fm = np.zeros((n, 8), np.uint8)
    fm[:, 0:2] = i16(d["Mx_w"], 0.25).view(np.uint8).reshape(n, 2)
    fm[:, 2:4] = i16(d["My"], 0.25).view(np.uint8).reshape(n, 2)
    fm[:, 4:6] = i16(d["Mz_w"], 0.25).view(np.uint8).reshape(n, 2)
    fm[:, 6] = cnt
    fa = np.zeros((n, 4), np.uint8)
    angr = np.round(np.degrees(np.mod(d["ang"], 2 * np.pi)) / 0.0054931640625).astype(np.int64) % 65536
    fa[:, 0:2] = angr.astype("<u2").view(np.uint8).reshape(n, 2); fa[:, 2] = cnt
    lost = rng.random(n) < 0.0008
    for k in rng.integers(0, n - 50, 3):          # a few lost bursts
        lost[k:k + rng.integers(3, 15)] = True
    # host receive time on can0: USB adapter batches at 1 ms + jitter
    hb = host0 + tw + 0.0006
    hb = np.ceil(hb * 1000) / 1000 + rng.exponential(0.00015, n)
    for i in np.nonzero(~lost)[0]:
        h = hb[i]
        out.append((h, 0, 0x120, False, ff[i].tobytes()))
        out.append((h + 0.00013, 0, 0x121, False, fm[i].tobytes()))
        out.append((h + 0.00026, 0, 0x122, False, fa[i].tobytes()))
    db = cantools.database.load_file(os.path.join(HERE, "dbc", "wft.dbc"))
    diag = db.get_message_by_name("WFT_RL_Diag")
    serial = int(rng.integers(100000, 999999))
    for k in range(int(t[-1])):
        ti = k + 0.1
        T_ = float(np.interp(ti, t, d["temp"]))
        out.append((host0 + ti, 0, 0x123, False, diag.encode({"DiagMux": 0, "BridgeTemp": round(T_, 2), "SupplyVoltage": round(12.1 + rng.normal(0, 0.02), 3)})))
        out.append((host0 + ti + 0.333, 0, 0x123, False, diag.encode({"DiagMux": 1, "SerialNumber": serial})))
        out.append((host0 + ti + 0.666, 0, 0x123, False, diag.encode({"DiagMux": 2, "FirmwareMajor": 3, "FirmwareMinor": 7, "CalibrationId": 4121})))
    # wheel speed module: 48-tooth Hall ring, period over last 4 edges
    dbw = cantools.database.load_file(os.path.join(HERE, "dbc", "wheel_speed.dbc"))
    mws = dbw.get_message_by_name("WSS_WheelSpeeds"); mst = dbw.get_message_by_name("WSS_Status")
    NT = 48
    ang = d["ang"] - d["ang"][0]
    edges_a = np.cumsum(2 * np.pi / NT * (1 + rng.normal(0, 0.002, int(ang[-1] / (2 * np.pi) * NT) + 2)))
    edges_a = edges_a[edges_a < ang[-1]]
    te = np.interp(edges_a, ang, t)
    tw2 = np.arange(0.005, t[-1], 0.01) * (1 + rng.normal(0, 30e-6))
    k = np.searchsorted(te, tw2) - 1
    ok = k >= 4
    om_rl = np.zeros_like(tw2)
    om_rl[ok] = 4 * (2 * np.pi / NT) / (te[k[ok]] - te[k[ok] - 4])
    Vw = np.interp(tw2, t, d["V"])
    om_rr = om_rl * (1 + rng.normal(0, 0.003, tw2.size))
    om_f = Vw / d["r"] * 1.01 * (1 + rng.normal(0, 0.002, tw2.size))
    rpm = lambda o: np.clip(o * 60 / (2 * np.pi), 0, 655.35)
    hw = host0 + tw2 + 0.0015 + rng.exponential(0.0004, tw2.size)
    for i in range(tw2.size):
        if rng.random() < 0.001:
            continue
        out.append((hw[i], 1, 0x300, False, mws.encode({"WheelSpeed_FL": round(rpm(om_f[i]), 2), "WheelSpeed_FR": round(rpm(om_f[i] * 1.001), 2),
                                                        "WheelSpeed_RL": round(rpm(om_rl[i]), 2), "WheelSpeed_RR": round(rpm(om_rr[i]), 2)})))
        if i % 10 == 0:
            out.append((hw[i] + 0.0004, 1, 0x301, False, mst.encode({"RollingCounter": (i // 10) % 16, "SensorFault_FL": 0, "SensorFault_FR": 0, "SensorFault_RL": 0, "SensorFault_RR": 0})))
    # GNSS/INS 20 Hz; receiver clock = GPS time; velocity arrives late by latency
    dbg = cantools.database.load_file(os.path.join(HERE, "dbc", "gps_rt_speedbox.dbc"))
    mt = dbg.get_message_by_name("RT_SB_GPS_Time"); msp = dbg.get_message_by_name("RT_SB_GPS_Speed")
    mv = dbg.get_message_by_name("RT_SB_INS_Vel_Body_Axes"); mss = dbg.get_message_by_name("RT_SB_GPS_Status")
    week = int(rng.integers(2400, 2460)); tow0 = float(rng.integers(1000, 590000)) + 0.05 * rng.integers(0, 20)
    lat = p["gnss_latency_s"]
    te_g = np.arange(0.0, t[-1] - lat - 0.1, 0.05) + rng.uniform(0, 0.05)
    Vg = np.interp(te_g, t, d["V"]) + rng.normal(0, 0.012, te_g.size)
    side = np.zeros_like(Vg)
    if case == "cross_slope":
        side = Vg * np.tan(np.radians(p["effect"]["alpha_deg"])) * (1 if p["effect"]["left_downhill"] else -1)
    side = side + rng.normal(0, 0.01, te_g.size)
    outage = np.zeros(te_g.size, bool)
    if p["gnss_outage"]:
        o0 = rng.uniform(30, t[-1] - 30); outage = (te_g > o0) & (te_g < o0 + rng.uniform(0.6, 1.5))
        p["gnss_outage_window_s"] = [float(o0), float(te_g[outage][-1]) if outage.any() else float(o0)]
    for i, tg in enumerate(te_g):
        if outage[i]:
            continue
        h = host0 + tg + lat + rng.exponential(0.002)
        tow = (tow0 + tg) % 604800
        sp = float(np.clip(abs(Vg[i]), 0, 1600)); vs = float(side[i])
        out.append((h, 1, mt.frame_id, True, mt.encode({"GPS_Week": week, "GPS_Time": round(tow, 3), "Accuracy_GPS_Time": 10, "Validity_GPS_Week": 1, "Validity_GPS_Time": 1})))
        out.append((h + 0.00025, 1, msp.frame_id, True, msp.encode({"GPS_Speed_3D": round(np.hypot(sp, vs), 4), "GPS_Speed_2D": round(np.hypot(sp, vs), 4), "Accuracy_GPS_Speed": 12, "Validity_GPS_Speed_3D": 1, "Validity_GPS_Speed_2D": 1})))
        out.append((h + 0.0005, 1, mv.frame_id, True, mv.encode({"INS_Vel_Sideways_2D": round(vs, 4), "INS_Vel_Forwards_2D": round(float(Vg[i]), 4), "Accuracy_INS_Vel_Body": 15, "Validity_INS_Vel_Sideways": 1, "Validity_INS_Vel_Forwards": 1})))
    for k in range(int(t[-1])):
        out.append((host0 + k + 0.42, 1, mss.frame_id, True, mss.encode({"RTK_Status": 0, "GPS_nSv_RTK": 0, "GPS_nSv_2": 0, "GPS_nSv": int(rng.integers(10, 15)), "Firmware_Version_Minor": 2, "Firmware_Version_Intermediate": 5, "Firmware_Version_Major": 2, "GPS_Status": 12})))
    out.sort(key=lambda z: z[0])
    return out


def write_log(path, fr, ext):
    import can
    if ext == ".log":
        w = can.CanutilsLogWriter(path, channel="can0")
    elif ext == ".asc":
        w = can.ASCWriter(path)
    elif ext == ".blf":
        w = can.BLFWriter(path)
    else:
        w = can.TRCWriter(path)
    for h, bus, aid, ext_, data in fr:
        ch = ("can0", "can1")[bus] if ext == ".log" else bus   # 0 -> channel 1, 1 -> channel 2
        w.on_message_received(can.Message(timestamp=h, arbitration_id=aid, is_extended_id=ext_, data=data, channel=ch))
    w.stop()


def main(argv=None):
    ap = argparse.ArgumentParser()
    ap.add_argument("case", choices=CASES)
    ap.add_argument("--seed", type=int, required=True)
    ap.add_argument("--out", required=True)
    ap.add_argument("--outdir", default=".")
    ap.add_argument("--p", action="append", default=[])
    a = ap.parse_args(argv)
    try:
        p, d, extra = build(a.case, a.seed, a.p)
    except Refused as e:
        print(f"REFUSED: {e}")
        return 2
    fr = frames(a.case, p, d)
    ext = [".log", ".asc", ".blf", ".trc"][a.seed % 4]
    os.makedirs(a.outdir, exist_ok=True)
    fn = a.out + ext
    write_log(os.path.join(a.outdir, fn), fr, ext)
    wh = WHEELS[p["wheel"]]
    p.update(extra); p["wheel_params"] = wh
    acc = {"none": ["none"], "vasilev": ["slip_sinkage"], "lyasko": ["slip_sinkage"], "ding": ["slip_sinkage"],
           "terrain_mismatch": ["terrain_mismatch"], "stress_distribution": ["stress_distribution"],
           "terrain_drift": ["terrain_drift"], "hardpan": ["unexplained", "terrain_mismatch"]}.get(a.case, ["unexplained"])
    if a.case in IN_CASES and "unexplained" not in acc:
        acc = acc + ["unexplained"] if a.case != "none" else acc
    truth = dict(name=a.out, case=a.case, family="in" if a.case in IN_CASES else "out", acceptable_verdicts=acc,
                 params=p, fit_args=[fn, "--terrain", f"benchmarks/foreign11/lab_{p['soil']}.toml",
                                     "--wheel-radius", str(wh["r"]), "--wheel-width", str(wh["b"]),
                                     "--wheel-mass", str(wh["m"]), "--wheel-inertia", str(wh["I"])],
                 form=a.case if a.case in ("vasilev", "lyasko", "ding") else None)
    with open(os.path.join(a.outdir, a.out + "_truth.json"), "w") as f:
        json.dump(truth, f, indent=1, default=float)
    return 0


if __name__ == "__main__":
    sys.exit(main())
