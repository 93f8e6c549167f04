#!/usr/bin/env python3
"""foreign12 blind generator: weight-transfer sled pulls of a 4x4 utility truck.

    gen.py CASE --seed S --out NAME --outdir DIR [--p key=value ...]

Writes DIR/NAME.<log|asc|blf|trc> and DIR/NAME_truth.json (exit 0), or prints
"REFUSED: reason" and exits 2 when the vehicle cannot move the sled.
See README.md for the procedure, the vehicle, the soils and the causes.
"""
import argparse
import json
import math
import os
import sys

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
import wongmodel as wm  # noqa: E402

G = 9.81

# ---------------------------------------------------------------- lab soils
LAB = {
    "loess": {"c_kpa": 4.2, "phi_deg": 24.0, "K_m": 0.019, "n": 0.78, "kc": 18.5, "kphi": 1120.0,
              "unc": {"k_eq_rel": 0.15, "n": 0.05, "c_kpa": 0.6, "phi_deg": 1.5, "K_m": 0.004}},
    "dunesand": {"c_kpa": 0.6, "phi_deg": 31.5, "K_m": 0.030, "n": 1.08, "kc": 1.2, "kphi": 1750.0,
                 "unc": {"k_eq_rel": 0.18, "n": 0.06, "c_kpa": 0.25, "phi_deg": 1.5, "K_m": 0.006}},
}
SOIL_KEYS = ["c_kpa", "phi_deg", "K_m", "n", "kc", "kphi"]

# ---------------------------------------------------------------- vehicle / wheel
TYRE_NOM = {"name": "365/80R20", "r": 0.546, "b": 0.365, "m_w": 105.0, "I_w": 16.5}
TYRE_SWAPS = [{"name": "320/90R20", "r": 0.542, "b": 0.320, "m_w": 96.0, "I_w": 14.6},
              {"name": "400/70R20", "r": 0.534, "b": 0.400, "m_w": 112.0, "I_w": 17.4}]
VEH = {"mass_kg": 4200.0, "wheelbase_m": 3.25, "front_share": 0.54, "h_cg_m": 1.05,
       "h_hitch_m": 0.55, "driveline_inertia_kgm2": 12.0}
SLED = {"mu_pan": 0.45, "crr_sled_wheels": 0.06, "f_start": 0.05, "f_end": 0.90}

CASES_IN = {"none": None, "slip_sinkage_vasilev": "vasilev", "slip_sinkage_lyasko": "lyasko",
            "slip_sinkage_ding": "ding", "terrain_mismatch": None, "stress_distribution": None,
            "terrain_drift": None}
CASES_OUT = ["soil_rebound", "tread_creep", "wft_calibration", "liquid_ballast", "tyre_swap",
             "curved_envelope", "encoder_latch"]
VERDICT = {"none": ["none"], "slip_sinkage_vasilev": ["slip_sinkage"], "slip_sinkage_lyasko": ["slip_sinkage"],
           "slip_sinkage_ding": ["slip_sinkage"], "terrain_mismatch": ["terrain_mismatch"],
           "stress_distribution": ["stress_distribution"], "terrain_drift": ["terrain_drift"]}


class Refused(Exception):
    pass


# ---------------------------------------------------------------- helpers
def keq(soil, b):
    return soil["kc"] / b + soil["kphi"]


def set_keq(soil, b, factor):
    """scale kc and kphi together: k_eq = kc/b + kphi scales by factor"""
    out = dict(soil)
    out["kc"] = soil["kc"] * factor
    out["kphi"] = soil["kphi"] * factor
    return out


def perturb(soil, key, nsd, unc):
    out = dict(soil)
    if key == "k_eq":
        f = 1.0 + nsd * unc["k_eq_rel"]
        out["kc"] *= f
        out["kphi"] *= f
    else:
        out[key] = soil[key] + nsd * unc[key]
    return out


class Draw:
    """parameter drawing with --p overrides taking precedence (JSON values)"""

    def __init__(self, rng, overrides):
        self.rng = rng
        self.ov = dict(overrides)
        self.P = {}

    def __call__(self, key, fn):
        v = self.ov.pop(key) if key in self.ov else fn()
        if isinstance(v, np.generic):
            v = v.item()
        self.P[key] = v
        return v


def eff_for(case, P):
    k = case
    if k == "slip_sinkage_vasilev":
        return {"kind": "vasilev", "H": P["H"]}
    if k == "slip_sinkage_lyasko":
        return {"kind": "lyasko", "m1": P["m1"], "m2": P["m2"]}
    if k == "slip_sinkage_ding":
        return {"kind": "ding", "n1": P["n1"]}
    if k == "stress_distribution":
        return {"kind": "stress_distribution", "a1": P["a1"], "a2": P["a2"]}
    if k == "soil_rebound":
        return {"kind": "soil_rebound", "rebound_ratio": P["rebound_ratio"]}
    if k == "curved_envelope":
        return {"kind": "curved_envelope", "dphi_per_decade": P["dphi_per_decade"],
                "sigma_ref_kpa": P["sigma_ref_kpa"]}
    return {"kind": "none"}


# ---------------------------------------------------------------- parameters
def draw_params(case, seed, overrides):
    rng = np.random.default_rng(1_000_003 * seed + 12)
    d = Draw(rng, overrides)
    u = rng.uniform
    soil_name = d("soil", lambda: ["loess", "dunesand"][seed % 2])
    if soil_name not in LAB:
        raise SystemExit("unknown soil %r" % soil_name)
    lab = {k: LAB[soil_name][k] for k in SOIL_KEYS}
    unc = LAB[soil_name]["unc"]
    b = TYRE_NOM["b"]
    # field soil: within the lab uncertainty (|dev| <= 1 sd) unless the case says otherwise
    devs = {}
    for k in ["k_eq", "n", "c_kpa", "phi_deg", "K_m"]:
        devs[k] = float(np.clip(rng.normal(0.0, 0.5), -1.0, 1.0))
    mism = {}
    if case == "terrain_mismatch":
        nkeys = d("mismatch_count", lambda: int(rng.choice([1, 2])))
        keys = d("mismatch_keys", lambda: [str(x) for x in rng.choice(["k_eq", "n", "c_kpa", "phi_deg", "K_m"],
                                                                      size=nkeys, replace=False)])
        for k in keys:
            sd = d("mismatch_sd_" + k, lambda: float(u(2.5, 4.0) * rng.choice([-1, 1])))
            # keep physically meaningful values (K, c > 0): flip the sign if needed
            if k in ("K_m", "c_kpa") and lab[k] + sd * unc[k] < 0.3 * lab[k]:
                sd = abs(sd)
                d.P["mismatch_sd_" + k] = sd
            devs[k] = sd
            mism[k] = sd
    field = dict(lab)
    for k, sd in devs.items():
        field = perturb(field, k, sd, unc)
    field = {k: d("field_" + k, lambda k=k: round(float(field[k]), 6)) for k in SOIL_KEYS}
    d.P["field_dev_sd"] = {k: round(v, 4) for k, v in devs.items()}
    d.P["field_k_eq"] = keq(field, b)
    d.P["lab_k_eq"] = keq(lab, b)

    # in-family effect parameters
    if case == "slip_sinkage_vasilev":
        d("H", lambda: u(0.025, 0.05))
    elif case == "slip_sinkage_lyasko":
        d("m1", lambda: u(0.2, 0.45))
        d("m2", lambda: u(0.02, 0.05))
    elif case == "slip_sinkage_ding":
        d("n1", lambda: u(0.30, 0.55))
    elif case == "stress_distribution":
        d("a1", lambda: u(0.40, 0.47))
        d("a2", lambda: u(0.15, 0.35))
    elif case == "terrain_drift":
        nk = d("drift_count", lambda: int(rng.choice([1, 2])))
        keys = d("drift_keys", lambda: [str(x) for x in rng.choice(["k_eq", "c_kpa", "phi_deg", "K_m", "n"],
                                                                   size=nk, replace=False)])
        for k in keys:
            d("drift_total_sd_" + k, lambda: float(u(3.0, 4.5) * rng.choice([-1, 1])))
        d("drift_basis", lambda: "distance")
        d("drift_shape", lambda: str(rng.choice(["linear", "step"])))
    # out-of-family effect parameters
    elif case == "soil_rebound":
        d("rebound_ratio", lambda: u(0.02, 0.04))
    elif case == "tread_creep":
        d("tread_long_stiffness_N", lambda: u(40e3, 65e3))
    elif case == "wft_calibration":
        d("gain_Fx_w", lambda: float(1 + u(0.06, 0.11) * rng.choice([-1, 1])))
        d("gain_Fz_w", lambda: float(1 + u(0.06, 0.11) * rng.choice([-1, 1])))
        d("gain_My", lambda: float(1 + u(0.06, 0.11) * rng.choice([-1, 1])))
        d("calibration_id_in_use", lambda: int(rng.integers(100, 400)))
    elif case == "liquid_ballast":
        d("liquid_mass_per_tyre_kg", lambda: u(130.0, 185.0))
        d("liquid_cg_lead_m", lambda: u(0.02, 0.05))
    elif case == "tyre_swap":
        d("rl_tyre", lambda: dict(TYRE_SWAPS[int(rng.integers(0, 2))]))
    elif case == "curved_envelope":
        d("dphi_per_decade", lambda: u(5.0, 8.0))
        d("sigma_ref_kpa", lambda: 25.0)
    elif case == "encoder_latch":
        d("angle_latch_delay_s", lambda: u(0.008, 0.016))

    # procedure: three pulls
    npull = d("n_pulls", lambda: 3)
    d("pull_speed_mps", lambda: [round(float(u(1.3, 2.1)), 3) for _ in range(npull)])
    d("sled_ratio", lambda: [round(float(u(1.10, 1.35)), 3) for _ in range(npull)])
    d("transfer_length_m", lambda: [round(float(u(20.0, 32.0)), 2) for _ in range(npull)])
    d("governor_droop", lambda: u(0.08, 0.14))
    d("engine_lag_s", lambda: u(0.10, 0.18))
    d("clutch_ramp_s", lambda: u(0.8, 1.6))
    d("idle_between_s", lambda: u(7.0, 10.0))

    # measurement imperfections
    d("gnss_latency_s", lambda: u(0.03, 0.18))
    d("gnss_speed_noise_mps", lambda: u(0.008, 0.02))
    d("ins_vel_noise_mps", lambda: u(0.005, 0.012))
    d("gnss_clock_offset_s", lambda: u(-0.9, 0.9))
    d("can0_adapter_offset_s", lambda: u(-0.002, 0.003))
    d("can1_adapter_offset_s", lambda: u(0.0, 0.001))
    d("wft_clock_ppm", lambda: u(-60, 60))
    d("wss_clock_ppm", lambda: u(-80, 80))
    d("wft_noise_N", lambda: u(8.0, 20.0))
    d("wft_noise_Nm", lambda: u(2.0, 6.0))
    d("wft_zero_offset_N", lambda: [round(float(rng.normal(0, 12)), 2) for _ in range(3)])
    d("wss_noise_rpm", lambda: u(0.02, 0.06))
    d("soil_force_noise_rel", lambda: u(0.015, 0.035))
    d("bounce_N", lambda: u(80.0, 220.0))
    d("frame_loss_prob", lambda: u(0.0005, 0.003))
    d("loss_bursts", lambda: int(rng.integers(0, 3)))
    d("host_start_unix", lambda: round(float(u(1.70e9, 1.76e9)), 3))
    d("wft_angle0_deg", lambda: u(0, 360))
    d("format", lambda: ["log", "asc", "blf", "trc"][int(rng.integers(0, 4))])
    d("sinkage", lambda: "eq10")
    d("dt_sim_s", lambda: 0.005)
    if d.ov:
        d.P.update(d.ov)   # unknown keys: stored, harmless
    return d.P, lab, rng


# ---------------------------------------------------------------- soil along the run
def soil_at(P, x, case, x_span):
    """field soil (dict of arrays) at global distance(s) x"""
    x = np.atleast_1d(np.asarray(x, float))
    base = {k: np.full(x.shape, float(P["field_" + k])) for k in SOIL_KEYS}
    if case != "terrain_drift":
        return base
    unc = LAB[P["soil"]]["unc"]
    xi = np.clip(x / x_span, 0.0, 1.0)
    if P["drift_shape"] == "step":
        lo, hi = math.tanh(-0.5 / 0.12), math.tanh(0.5 / 0.12)
        prog = (np.tanh((xi - 0.5) / 0.12) - lo) / (hi - lo)
    else:
        prog = xi
    for k in P["drift_keys"]:
        tot = P["drift_total_sd_" + k]
        dev = tot * (prog - 0.5)
        if k == "k_eq":
            f = np.maximum(1.0 + dev * unc["k_eq_rel"], 0.25)
            base["kc"] = base["kc"] * f
            base["kphi"] = base["kphi"] * f
        else:
            v = base[k] + dev * unc[k]
            if k in ("K_m", "c_kpa"):
                v = np.maximum(v, 0.3 * base[k])
            base[k] = v
    return base


# ---------------------------------------------------------------- wheel groups
def slip_of(r, w, V):
    rw = r * w
    if rw >= V:
        return (rw - V) / rw if rw > 1e-9 else 0.0
    return (rw - V) / V


def slip_vec(r, w, V):
    rw = r * w
    out = np.zeros_like(rw)
    drv = rw >= V
    m = drv & (rw > 1e-9)
    out[m] = (rw[m] - V[m]) / rw[m]
    sk = ~drv
    out[sk] = (rw[sk] - V[sk]) / V[sk]
    return out


def blend_low_speed(r, w, V):
    return np.clip(np.maximum(r * w, V) / 0.08, 0.0, 1.0)


def creep_solve(s_rim, W, r, b, soil, eff, Cx, nq, iters=8):
    """tread creep: the tread (soil-side) speed is lower than the rim speed by the
    circumferential strain eps = F_t / Cx (F_t = T / r)."""
    s_soil = np.array(s_rim, float)
    for _ in range(iters):
        m = wm.wheel(s_soil, W, r, b, soil, eff, nq=nq)
        eps = np.clip(m["T"] / (r * Cx), -0.3, 0.3)
        s_new = 1.0 - (1.0 - s_rim) / (1.0 - eps)
        s_new = np.where(s_rim < 0, s_rim, s_new)   # not applied in skid
        s_soil = np.clip(s_new, -1.0, 1.0)
    m = wm.wheel(s_soil, W, r, b, soil, eff, nq=nq)
    m["s_soil"] = s_soil
    return m


class Table:
    """Dp(s), T(s) of one wheel group on grids of soil state (x), W (soil load) and rim slip"""

    def __init__(self, tyre, soil_fn, xs, Wg, eff, case, P):
        self.r, self.b = tyre["r"], tyre["b"]
        self.xs, self.Wg = np.asarray(xs, float), np.asarray(Wg, float)
        self.sg = np.unique(np.concatenate([np.linspace(-1, 1, 81), np.linspace(-0.2, 0.2, 81)]))
        nx, nw, ns = len(self.xs), len(self.Wg), len(self.sg)
        X, Wm, S = np.meshgrid(self.xs, self.Wg, self.sg, indexing="ij")
        soil = soil_fn(X.ravel())
        if case == "tread_creep":
            m = creep_solve(S.ravel(), Wm.ravel(), self.r, self.b, soil, eff, P["tread_long_stiffness_N"], nq=32)
        else:
            m = wm.wheel(S.ravel(), Wm.ravel(), self.r, self.b, soil, eff, nq=32)
        self.Dp = m["Dp"].reshape(nx, nw, ns)
        self.T = m["T"].reshape(nx, nw, ns)

    def curves(self, x, W):
        if len(self.xs) > 1:
            i = int(np.clip(np.searchsorted(self.xs, x) - 1, 0, len(self.xs) - 2))
            fx = float(np.clip((x - self.xs[i]) / (self.xs[i + 1] - self.xs[i]), 0, 1))
        else:
            i, fx = 0, 0.0
        j = int(np.clip(np.searchsorted(self.Wg, W) - 1, 0, len(self.Wg) - 2))
        fw = (W - self.Wg[j]) / (self.Wg[j + 1] - self.Wg[j])
        def bl(A):
            a = A[i, j] * (1 - fw) + A[i, j + 1] * fw
            if fx > 0:
                a2 = A[i + 1, j] * (1 - fw) + A[i + 1, j + 1] * fw
                a = a * (1 - fx) + a2 * fx
            return a
        return bl(self.Dp), bl(self.T)


# ---------------------------------------------------------------- simulation
def simulate(case, P):
    rng = np.random.default_rng(int(P.get("_seed", 0)) * 7919 + 5)
    eff = eff_for(case, P)
    rl_tyre = dict(P["rl_tyre"]) if case == "tyre_swap" else dict(TYRE_NOM)
    m_liq = P["liquid_mass_per_tyre_kg"] if case == "liquid_ballast" else 0.0
    M_veh = VEH["mass_kg"] + 4 * m_liq
    L, h_h, h_cg = VEH["wheelbase_m"], VEH["h_hitch_m"], VEH["h_cg_m"]
    W_F0 = VEH["front_share"] * VEH["mass_kg"] * G / 2 + m_liq * G
    W_R0 = (1 - VEH["front_share"]) * VEH["mass_kg"] * G / 2 + m_liq * G
    I_eff = 3 * TYRE_NOM["I_w"] + rl_tyre["I_w"] + VEH["driveline_inertia_kgm2"]
    x_span = 0.8 * float(np.sum(P["transfer_length_m"]))
    P["drift_span_m"] = x_span if case == "terrain_drift" else None
    sfn = lambda x: soil_at(P, x, case, x_span)
    xs = np.linspace(0, x_span, 9) if case == "terrain_drift" else np.array([0.0])
    # groups: (name, count, tyre, axle)
    groups = [("front", 2, TYRE_NOM, "F"), ("RR", 1, TYRE_NOM, "R"), ("RL", 1, rl_tyre, "R")]
    Wnom = W_R0
    Wg = np.linspace(0.55 * Wnom, 1.45 * Wnom, 9)
    tables = [Table(g[2], sfn, xs, Wg, eff, case, P) for g in groups]
    # nominal capacity (what the crew estimates from the lab soil, Wong's model, nominal tyres)
    lab = {k: LAB[P["soil"]][k] for k in SOIL_KEYS}
    r0, b0 = TYRE_NOM["r"], TYRE_NOM["b"]
    capF = wm.wheel(np.array([0.75, 0.95]), W_F0 - m_liq * G, r0, b0, lab)
    capR = wm.wheel(np.array([0.75, 0.95]), W_R0 - m_liq * G, r0, b0, lab)
    P["nominal_pull_capacity_lab_N"] = float(2 * capF["Dp"][0] + 2 * capR["Dp"][0])

    def site_capacity(xpos):
        """what the crew's trial pull shows: max total pull for slip 0.5..0.95, and
        the total soil torque at slip 0.95 (static loads, the soil at xpos)"""
        dp = 0.0
        tq = 0.0
        for gi, (gname, cnt, ty, ax) in enumerate(groups):
            Dpc, Tc = tables[gi].curves(xpos, W_F0 if ax == "F" else W_R0)
            sg = tables[gi].sg
            dp = dp + cnt * Dpc
            tq += cnt * float(np.max(Tc[(sg >= 0.0) & (sg <= 1.0)]))
        sg = tables[0].sg
        return float(np.max(dp[(sg >= 0.15) & (sg <= 0.95)])), tq

    cap0, tq0 = site_capacity(0.0)
    T_max = 1.6 * tq0
    P["engine_wheel_torque_max_Nm"] = float(T_max)
    sled_W = []
    P["site_pull_capacity_N"] = []

    def drag(Ws, xp):
        f = SLED["f_start"] + (SLED["f_end"] - SLED["f_start"]) * min(max(xp, 0.0) / Ltr, 1.0)
        return Ws * (SLED["mu_pan"] * f + SLED["crr_sled_wheels"] * (1 - f))

    dt = float(P["dt_sim_s"])
    rec = {k: [] for k in ("t", "w", "V", "x", "WF", "WR", "phase", "pull")}
    t = 0.0
    w = V = x = 0.0
    a_prev = 0.0
    Te = 0.0
    drag_noise = 0.0

    def record(phase, ip, WF, WR):
        rec["t"].append(t); rec["w"].append(w); rec["V"].append(V); rec["x"].append(x)
        rec["WF"].append(WF); rec["WR"].append(WR); rec["phase"].append(phase); rec["pull"].append(ip)

    def idle(dur, ip):
        nonlocal t
        n = int(round(dur / dt))
        for _ in range(n):
            record(0, ip, W_F0, W_R0)
            t += dt

    idle(4.0, -1)
    from scipy.optimize import brentq
    pull_stats = []
    for ip in range(int(P["n_pulls"])):
        Ltr = float(P["transfer_length_m"][ip])
        capx, _ = site_capacity(x)
        P["site_pull_capacity_N"].append(round(capx, 1))
        Ws = float(P["sled_ratio"][ip]) * capx / (SLED["mu_pan"] * SLED["f_end"]
                                                  + SLED["crr_sled_wheels"] * (1 - SLED["f_end"]))
        sled_W.append(Ws)
        P["sled_weight_N"] = [round(v, 1) for v in sled_W]
        M_sled = Ws / G
        w_set = float(P["pull_speed_mps"][ip]) / (TYRE_NOM["r"] * (1 - 0.08))
        # can the vehicle start the sled at all?
        F0 = 1.15 * drag(Ws, 0.0)
        best = 0.0
        for gi, (gname, cnt, ty, ax) in enumerate(groups):
            Dpc, _ = tables[gi].curves(x, W_F0 if ax == "F" else W_R0)
            best += cnt * float(np.interp(1.0, tables[gi].sg, Dpc))
        if best <= F0:
            raise Refused("vehicle cannot move: drawbar pull of the four wheels spinning from rest %.0f N <= "
                          "sled breakaway drag %.0f N (pull %d)" % (best, F0, ip + 1))
        xp = 0.0
        t_pull = 0.0
        phase = 1
        stop_t = 0.0
        vmax = 0.0
        smax = 0.0
        while True:
            ramp = min(t_pull / float(P["clutch_ramp_s"]), 1.0) if phase == 1 else 0.0
            Fd = drag(Ws, xp) * (1 + 0.04 * drag_noise)
            drag_noise = 0.995 * drag_noise + math.sqrt(1 - 0.995 ** 2) * rng.normal()
            F_hitch = Fd + M_sled * a_prev
            dW = (F_hitch * h_h + M_veh * a_prev * h_cg) / (2 * L)
            WF, WR = W_F0 - dW, W_R0 + dW
            cur = []
            for gi, (gname, cnt, ty, ax) in enumerate(groups):
                Dpc, Tc = tables[gi].curves(x, WF if ax == "F" else WR)
                cur.append((cnt, ty["r"], Dpc, Tc, tables[gi].sg))
            T_extra = 4 * (m_liq * G * P["liquid_cg_lead_m"]) if m_liq > 0 else 0.0
            k_e = dt / float(P["engine_lag_s"])
            droop = float(P["governor_droop"]) * w_set

            def Ttgt(om):
                return ramp * T_max * min(max((w_set - om) / droop, 0.0), 1.0)

            def soil_torque(om):
                tot = 0.0
                for cnt, r_, Dpc, Tc, sg in cur:
                    s_ = slip_of(r_, om, V)
                    gb = min(max(max(r_ * om, V) / 0.08, 0.0), 1.0)
                    tot += cnt * gb * float(np.interp(s_, sg, Tc))
                return tot

            braking = phase == 2 and V < 0.05
            if braking:
                w_new = w * math.exp(-dt / 0.15)
                if w_new < 0.02:
                    w_new = 0.0
                Te_new = 0.0
            else:
                def R(om):
                    te = (Te + k_e * Ttgt(om)) / (1 + k_e)
                    ext = T_extra * min(max(r0 * om / 0.08, 0.0), 1.0)
                    return te - soil_torque(om) - ext - I_eff * (om - w) / dt
                hi = max(w_set * 1.3, w + 5.0, V / r0 * 2 + 1)
                if R(0.0) <= 0:
                    w_new = 0.0
                else:
                    w_new = brentq(R, 0.0, hi, xtol=1e-9, rtol=1e-12)
                Te_new = (Te + k_e * Ttgt(w_new)) / (1 + k_e)
            # vehicle (Newton's law with the wheels' drawbar pull)
            sumDp = 0.0
            for cnt, r_, Dpc, Tc, sg in cur:
                s_ = slip_of(r_, w_new, V)
                gb = min(max(max(r_ * w_new, V) / 0.08, 0.0), 1.0)
                sumDp += cnt * gb * float(np.interp(s_, sg, Dpc))
            M_tot = M_veh + M_sled
            if V <= 0.0 and sumDp <= 1.15 * Fd:
                a = 0.0
                V_new = 0.0
            else:
                a = (sumDp - Fd) / M_tot
                V_new = V + a * dt
                if V_new < 0.0:
                    V_new = 0.0
                    a = -V / dt
            w, Te, V = w_new, Te_new, V_new
            x += V * dt
            xp += V * dt
            a_prev = a
            record(phase, ip, WF, WR)
            t += dt
            t_pull += dt
            vmax = max(vmax, V)
            s_now = slip_of(r0, w, V)
            if phase == 1:
                smax = max(smax, s_now) if t_pull > 3.0 else smax
                end = (t_pull > 4.0 and V < 0.12 and s_now > 0.75) or xp > Ltr + 4.0 or t_pull > 70.0
                if end:
                    phase = 2
                    stop_t = 0.0
                    Te = 0.0
            else:
                stop_t += dt
                if (w == 0.0 and V == 0.0) or stop_t > 8.0:
                    w = 0.0
                    V = 0.0
                    break
        if vmax < 0.25:
            raise Refused("vehicle could not move the sled in pull %d (max speed %.2f m/s)" % (ip + 1, vmax))
        pull_stats.append({"pull": ip + 1, "duration_s": round(t_pull, 2), "distance_m": round(xp, 2),
                           "max_speed_mps": round(vmax, 3), "max_slip_after_3s": round(smax, 3)})
        a_prev = 0.0
        idle(float(P["idle_between_s"]) if ip < int(P["n_pulls"]) - 1 else 3.0, ip)
    P["pulls"] = pull_stats
    P["total_distance_m"] = round(x, 2)
    out = {k: np.asarray(v) for k, v in rec.items()}
    out.update({"rl_tyre": rl_tyre, "m_liq": m_liq, "eff": eff, "sfn": sfn})
    return out


# ---------------------------------------------------------------- measurements
def measure(case, P, sim):
    from scipy.interpolate import PchipInterpolator
    rng = np.random.default_rng(int(P.get("_seed", 0)) * 104729 + 77)
    t = sim["t"]
    T_end = t[-1]
    wI = PchipInterpolator(t, sim["w"])
    VI = PchipInterpolator(t, sim["V"])
    angI = wI.antiderivative()
    tyre = sim["rl_tyre"]
    r, b = tyre["r"], tyre["b"]
    m_liq = sim["m_liq"]
    eff = sim["eff"]
    frames = []   # (ts, channel, name, dict)

    # ---------------- WFT @ 500 Hz on its own clock
    per = 0.002 * (1 + P["wft_clock_ppm"] * 1e-6)
    tw = np.arange(0.01, T_end - 0.01, per)
    n = len(tw)
    w = np.maximum(wI(tw), 0.0)
    alpha = wI.derivative()(tw)
    V = np.maximum(VI(tw), 0.0)
    acc = VI.derivative()(tw)
    xg = np.interp(tw, t, sim["x"])
    WR = np.interp(tw, t, sim["WR"])
    # vertical bounce of the rear axle while moving (band-limited noise, ~2-3 Hz)
    e = rng.normal(size=n)
    bounce = np.zeros(n)
    a1, a2 = 2 * 0.985 * math.cos(2 * math.pi * 2.4 * 0.002), -0.985 ** 2
    for i in range(2, n):
        bounce[i] = a1 * bounce[i - 1] + a2 * bounce[i - 2] + e[i]
    bounce *= P["bounce_N"] / (np.std(bounce) + 1e-9)
    bounce *= np.clip(V / 0.5, 0, 1)
    W_soil = WR + bounce
    s = slip_vec(r, w, V)
    gb = blend_low_speed(r, w, V)
    soil = sim["sfn"](xg)
    Dp = np.zeros(n); T = np.zeros(n)
    mv = gb > 0
    if np.any(mv):
        sl = {k: v[mv] for k, v in soil.items()}
        if case == "tread_creep":
            m = creep_solve(s[mv], W_soil[mv], r, b, sl, eff, P["tread_long_stiffness_N"], nq=64)
        else:
            m = wm.wheel(s[mv], W_soil[mv], r, b, sl, eff, nq=64)
        Dp[mv] = m["Dp"]; T[mv] = m["T"]
    # soil-heterogeneity fluctuation of the soil forces (mean zero, ~50 ms correlation)
    ar = np.zeros(n); e2 = rng.normal(size=n); q = math.exp(-0.002 / 0.05)
    for i in range(1, n):
        ar[i] = q * ar[i - 1] + math.sqrt(1 - q * q) * e2[i]
    Dp = Dp * (1 + P["soil_force_noise_rel"] * ar)
    T = T * (1 + P["soil_force_noise_rel"] * ar)
    m_w, I_w = tyre["m_w"], tyre["I_w"]
    Fx = gb * Dp - (m_w + m_liq) * acc
    Fz = W_soil - m_liq * G
    My = gb * T + I_w * alpha
    if m_liq > 0:
        My = My + gb * m_liq * G * P["liquid_cg_lead_m"]
    # lateral force / moments (small, physical)
    fy = np.zeros(n); e3 = rng.normal(size=n); q2 = math.exp(-0.002 / 0.8)
    for i in range(1, n):
        fy[i] = q2 * fy[i - 1] + math.sqrt(1 - q2 * q2) * e3[i]
    Fy = 60.0 * fy * np.clip(V / 0.3, 0, 1)
    Mx = -0.012 * Fz + 0.3 * Fy
    Mz = 0.02 * Fx + 6.0 * fy
    ang = np.radians(P["wft_angle0_deg"]) + angI(tw) - angI(tw[0])
    ca, sa = np.cos(ang), np.sin(ang)
    noiseF = P["wft_noise_N"]
    off = P["wft_zero_offset_N"]
    Fx_w = Fx * ca - Fz * sa + off[0] + rng.normal(0, noiseF, n)
    Fz_w = Fx * sa + Fz * ca + off[2] + rng.normal(0, noiseF, n)
    Fy_w = Fy + off[1] + rng.normal(0, noiseF, n)
    Mx_w = Mx * ca - Mz * sa + rng.normal(0, P["wft_noise_Nm"], n)
    Mz_w = Mx * sa + Mz * ca + rng.normal(0, P["wft_noise_Nm"], n)
    My_m = My + rng.normal(0, P["wft_noise_Nm"], n)
    if case == "wft_calibration":
        Fx_w = Fx_w * P["gain_Fx_w"]; Fz_w = Fz_w * P["gain_Fz_w"]; My_m = My_m * P["gain_My"]
    ang_rep = ang
    if case == "encoder_latch":
        ang_rep = ang - w * P["angle_latch_delay_s"]
    ang_deg = np.mod(np.degrees(ang_rep), 360.0)
    ang_deg = np.where(ang_deg >= 359.9945, 0.0, ang_deg)
    host0 = P["can0_adapter_offset_s"]
    ts0 = tw + host0 + np.abs(rng.normal(0, 0.00008, n))
    lost = rng.random((n, 3)) < P["frame_loss_prob"]
    for _ in range(int(P["loss_bursts"])):
        i0 = int(rng.integers(0, max(n - 50, 1)))
        lost[i0:i0 + int(rng.integers(5, 25)), :] = True
    cl = lambda v, lo, hi: float(min(max(v, lo), hi))
    ovl = ((np.abs(Fx_w) > 16383) | (np.abs(Fy_w) > 16383) | (np.abs(Fz_w) > 32767) | (np.abs(My_m) > 8191)
           | (np.abs(Mx_w) > 8191) | (np.abs(Mz_w) > 8191)).astype(int)   # Status bit 0: overload
    for i in range(n):
        cnt = i % 256
        st = int(ovl[i])
        if not lost[i, 0]:
            frames.append((ts0[i], 0, "WFT_RL_Force", {"Fx_w": cl(Fx_w[i], -16384, 16383.5), "Fy_w": cl(Fy_w[i], -16384, 16383.5),
                                                       "Fz_w": cl(Fz_w[i], -32768, 32767), "Counter": cnt, "Status": st}))
        if not lost[i, 1]:
            frames.append((ts0[i] + 0.00013, 0, "WFT_RL_Moment", {"Mx_w": cl(Mx_w[i], -8192, 8191.75), "My": cl(My_m[i], -8192, 8191.75),
                                                                 "Mz_w": cl(Mz_w[i], -8192, 8191.75), "Counter": cnt, "Status": st}))
        if not lost[i, 2]:
            frames.append((ts0[i] + 0.00026, 0, "WFT_RL_Angle", {"WheelAngle": float(ang_deg[i]), "Counter": cnt, "Status": st}))
    # diagnostics, 1 Hz per mux value
    calid = P.get("calibration_id_in_use", 512) if case == "wft_calibration" else 512
    serial = 20170000 + int(P.get("_seed", 0)) % 1000
    for k, td in enumerate(np.arange(0.3, T_end - 0.1, 1.0)):
        temp = 14.0 + 6.0 * td / max(T_end, 1) + rng.normal(0, 0.05)
        frames.append((td + host0, 0, "WFT_RL_Diag", {"DiagMux": 0, "BridgeTemp": temp, "SupplyVoltage": 12.1 + rng.normal(0, 0.01)}))
        frames.append((td + 0.333 + host0, 0, "WFT_RL_Diag", {"DiagMux": 1, "SerialNumber": serial}))
        frames.append((td + 0.666 + host0, 0, "WFT_RL_Diag", {"DiagMux": 2, "FirmwareMajor": 3, "FirmwareMinor": 4, "CalibrationId": calid}))

    # ---------------- wheel speed module @ 100 Hz (average speed over the last 10 ms)
    perw = 0.01 * (1 + P["wss_clock_ppm"] * 1e-6)
    tss = np.arange(0.015, T_end - 0.01, perw)
    om = np.maximum((angI(tss) - angI(tss - 0.01)) / 0.01, 0.0)
    rpm = om * 60 / (2 * np.pi)
    h1 = P["can1_adapter_offset_s"]
    lostw = rng.random(len(tss)) < P["frame_loss_prob"]
    for i, tt in enumerate(tss):
        if lostw[i]:
            continue
        vals = {}
        for nm in ("FL", "FR", "RL", "RR"):
            v = rpm[i] * (1 + rng.normal(0, 0.001)) + rng.normal(0, P["wss_noise_rpm"])
            vals["WheelSpeed_" + nm] = cl(v if rpm[i] > 0.5 else 0.0, 0, 655.35)
        frames.append((tt + 0.0004 + h1 + abs(rng.normal(0, 0.00005)), 1, "WSS_WheelSpeeds", vals))
    for k, tt in enumerate(np.arange(0.05, T_end - 0.01, 0.1 * (1 + P["wss_clock_ppm"] * 1e-6))):
        frames.append((tt + 0.0006 + h1, 1, "WSS_Status", {"RollingCounter": k % 16, "SensorFault_FL": 0, "SensorFault_FR": 0,
                                                           "SensorFault_RL": 0, "SensorFault_RR": 0}))

    # ---------------- GNSS/INS @ 20 Hz, fixes on GPS time, delivered late by the latency
    host_start = P["host_start_unix"]
    gps_off = 315964800.0 - 18.0 - P["gnss_clock_offset_s"]   # host unix -> gps seconds
    g0 = host_start - gps_off
    first = math.ceil((g0 + 0.02) * 20) / 20.0
    tfix = np.arange(first, g0 + T_end - P["gnss_latency_s"] - 0.05, 0.05) - g0   # sim time of fixes
    Vf = np.maximum(VI(tfix), 0.0)
    lat = P["gnss_latency_s"]
    lostg = rng.random(len(tfix)) < P["frame_loss_prob"]
    for i, tf in enumerate(tfix):
        if lostg[i]:
            continue
        th = tf + lat + h1 + abs(rng.normal(0, 0.0015))
        gsec = tf + g0
        week = int(gsec // 604800)
        tow = gsec - week * 604800
        v2 = max(Vf[i] + rng.normal(0, P["gnss_speed_noise_mps"]), 0.0)
        vz = rng.normal(0, 0.015)
        frames.append((th, 1, "RT_SB_GPS_Time", {"GPS_Week": week, "GPS_Time": round(tow, 3), "Accuracy_GPS_Time": 2,
                                                 "Validity_GPS_Week": 1, "Validity_GPS_Time": 1}))
        frames.append((th + 0.00025, 1, "RT_SB_GPS_Speed", {"GPS_Speed_3D": math.hypot(v2, vz), "GPS_Speed_2D": v2,
                                                            "Accuracy_GPS_Speed": 4, "Validity_GPS_Speed_3D": 1,
                                                            "Validity_GPS_Speed_2D": 1}))
        frames.append((th + 0.0005, 1, "RT_SB_INS_Vel_Body_Axes", {
            "INS_Vel_Forwards_2D": Vf[i] + rng.normal(0, P["ins_vel_noise_mps"]),
            "INS_Vel_Sideways_2D": rng.normal(0, P["ins_vel_noise_mps"]), "Accuracy_INS_Vel_Body": 3,
            "Validity_INS_Vel_Forwards": 1, "Validity_INS_Vel_Sideways": 1}))
    for k, tt in enumerate(np.arange(0.7, T_end - 0.05, 1.0)):
        frames.append((tt + h1, 1, "RT_SB_GPS_Status", {"GPS_Status": 12, "GPS_nSv": 13 + (k // 17) % 3, "GPS_nSv_2": 0,
                                                        "GPS_nSv_RTK": 0, "RTK_Status": 0, "Firmware_Version_Major": 2,
                                                        "Firmware_Version_Intermediate": 5, "Firmware_Version_Minor": 1}))
    stats = {"wft_samples": n, "wft_overload_samples": int(ovl.sum()), "wft_frames_lost": int(lost.sum()), "log_duration_s": round(float(T_end), 2)}
    return frames, stats


def write_log(frames, P, path):
    import can
    import cantools
    dbs = [cantools.database.load_file(os.path.join(HERE, "dbc", f))
           for f in ("wft.dbc", "wheel_speed.dbc", "gps_rt_speedbox.dbc")]
    msgs = {}
    for db in dbs:
        for m in db.messages:
            msgs[m.name] = m
    frames.sort(key=lambda f: f[0])
    fmt = P["format"]
    t0 = P["host_start_unix"]
    last = -1.0
    with can.Logger(path) as wr:
        for ts, ch, name, sig in frames:
            m = msgs[name]
            data = m.encode(sig)
            tt = max(t0 + ts, last + 1e-6)
            last = tt
            chan = ("can0" if ch == 0 else "can1") if fmt == "log" else ch
            wr.on_message_received(can.Message(timestamp=tt, arbitration_id=m.frame_id,
                                               is_extended_id=m.is_extended_frame, data=data,
                                               dlc=m.length, channel=chan))


# ---------------------------------------------------------------- main
def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("case", choices=list(CASES_IN) + CASES_OUT)
    ap.add_argument("--seed", type=int, required=True)
    ap.add_argument("--out", required=True)
    ap.add_argument("--outdir", required=True)
    ap.add_argument("--p", action="append", default=[], metavar="key=value")
    a = ap.parse_args(argv)
    ov = {}
    for kv in a.p:
        k, _, v = kv.partition("=")
        try:
            ov[k] = json.loads(v)
        except json.JSONDecodeError:
            ov[k] = v
    P, lab, _ = draw_params(a.case, a.seed, ov)
    P["_seed"] = a.seed
    try:
        sim = simulate(a.case, P)
    except Refused as e:
        print("REFUSED: %s" % e)
        return 2
    frames, stats = measure(a.case, P, sim)
    P["measurement_stats"] = stats
    os.makedirs(a.outdir, exist_ok=True)
    fname = "%s.%s" % (a.out, P["format"])
    write_log(frames, P, os.path.join(a.outdir, fname))
    fam = "in" if a.case in CASES_IN else "out"
    truth = {
        "name": a.out,
        "case": a.case,
        "family": fam,
        "acceptable_verdicts": VERDICT[a.case] if fam == "in" else ["unexplained"],
        "form": CASES_IN.get(a.case) if fam == "in" else None,
        "params": P,
        "fit_args": [fname, "--terrain", "benchmarks/foreign12/lab_%s.toml" % P["soil"],
                     "--wheel-radius", str(TYRE_NOM["r"]), "--wheel-width", str(TYRE_NOM["b"]),
                     "--wheel-mass", str(TYRE_NOM["m_w"]), "--wheel-inertia", str(TYRE_NOM["I_w"])],
        "design": {"vehicle": VEH, "sled": SLED, "tyre_nominal": TYRE_NOM,
                   "lab_soil": {k: LAB[P["soil"]][k] for k in SOIL_KEYS}, "lab_uncertainty": LAB[P["soil"]]["unc"],
                   "model": "Wong Eqs. 1-10 (Bekker kc/b+kphi, z=r(cos th - cos th1)), sinkage Eq. 10",
                   "dbc": "benchmarks/foreign12/dbc/"},
    }
    P.pop("_seed", None)
    truth["params"]["seed"] = a.seed
    with open(os.path.join(a.outdir, a.out + "_truth.json"), "w") as f:
        json.dump(truth, f, indent=1, default=lambda o: o.item() if isinstance(o, np.generic) else str(o))
    return 0


if __name__ == "__main__":
    sys.exit(main())
