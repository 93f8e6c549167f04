#!/usr/bin/env python3
"""foreign8: blind generator of vehicle CAN recordings with a hidden effect.

gen.py CASE --seed S --out NAME --outdir DIR [--p key=value ...]
writes DIR/NAME.<log|asc|blf> and DIR/NAME_truth.json.  See README.md.
"""
import argparse
import json
import math
import os
import sys
import tomllib

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
import terra  # noqa: E402

G = 9.81
DBC_DIRS = [os.path.join(HERE, "..", "..", "dbc"), "/work/shared/dbc"]

# ---------------------------------------------------------------- wheel / vehicle
WHEEL = dict(r=0.52, b=0.36, m_w=92.0, I_w=13.8)   # our own wheel (not hardware.md's default)
VEHICLE = dict(mass_kg=3600.0, wheelbase_m=2.8, cg_height_m=0.95,
               static_rear_wheel_n=8000.0)          # static load per rear wheel without ballast

SOILS = {"loam": "lab_loam.toml", "sand": "lab_sand.toml"}
UNC_KEYS = {"k_eq": "k_eq_rel", "n": "n", "c": "c_kpa", "phi": "phi_deg", "K": "K_m"}

IN_FAMILY = {
    "none": ["none"],
    "vasilev": ["slip_sinkage"],
    "lyasko": ["slip_sinkage"],
    "ding": ["slip_sinkage"],
    "mismatch": ["terrain_mismatch"],
    "wong_reece": ["stress_distribution"],
    "drift": ["terrain_drift"],
}
OUT_FAMILY = {
    "wft_angle_offset": ["unexplained"],   # WFT encoder zero offset (deg)
    "torque_gain": ["unexplained"],        # WFT My calibration gain error
    "my_zero_drift": ["unexplained"],      # WFT My zero drifts with bridge temperature
    "wss_scale": ["unexplained"],          # wheel-speed module scale (tooth count / config)
    "strain_softening": ["unexplained"],   # brittle soil: hump-shaped shear curve
    "rate_shear": ["unexplained"],         # viscous soil: shear strength grows with shear rate
    "flexible_tyre": ["unexplained"],      # deflected tyre: larger equivalent rigid radius
    "hardpan": ["unexplained"],            # hard layer below: sinkage saturates
    "bulldozing": ["unexplained"],         # soil wedge pushed ahead of the wheel
}
CASES = {**{k: "in" for k in IN_FAMILY}, **{k: "out" for k in OUT_FAMILY}}

DEFAULTS = {
    "none": {},
    "vasilev": {"H": 0.05},
    "lyasko": {"m1": 0.4, "m2": 0.05},
    "ding": {"n1": 0.4},
    "mismatch": {"mismatch": {"k_eq": 1.4}},
    "wong_reece": {"a1": 0.35, "a2": 0.3},
    "drift": {"drift_mode": "compaction", "drift": {"k_eq": 1.5, "n": -0.05}},
    "wft_angle_offset": {"offset_deg": 2.0},
    "torque_gain": {"gain": 0.1},
    "my_zero_drift": {"drift_nm": 80.0},
    "wss_scale": {"scale": 0.03},
    "strain_softening": {"Kr": 0.6},
    "rate_shear": {"beta": 0.2},
    "flexible_tyre": {"r_factor": 1.3},
    "hardpan": {"h_frac": 0.7},
    "bulldozing": {"factor": 1.0},
}


class Refused(SystemExit):
    pass


def refuse(msg):
    sys.stderr.write("gen.py: REFUSED: " + msg + "\n")
    raise Refused(2)


def load_lab(soil):
    with open(os.path.join(HERE, SOILS[soil]), "rb") as f:
        return tomllib.load(f)


def transform_soil(lab, f=None, keq_f=1.0, b=WHEEL["b"]):
    """Apply factors/offsets (k_eq factor scales kc and kphi together)."""
    s = {k: lab[k] for k in ("c_kpa", "phi_deg", "K_m", "n", "kc", "kphi")}
    f = f or {}
    kf = f.get("k_eq", 1.0) * keq_f
    s["kc"] *= kf
    s["kphi"] *= kf
    s["n"] += f.get("n", 0.0)
    s["c_kpa"] *= f.get("c", 1.0)
    s["phi_deg"] += f.get("phi", 0.0)
    s["K_m"] *= f.get("K", 1.0)
    return s


def keq(s, b=WHEEL["b"]):
    return s["kc"] / b + s["kphi"]


# ---------------------------------------------------------------- noise helpers
def lowpass_noise(rng, n, dt, tau, sigma):
    w = rng.standard_normal(n)
    a = math.exp(-dt / tau)
    y = np.empty(n)
    acc = 0.0
    k = math.sqrt(1 - a * a)
    for i in range(n):            # AR(1), unit variance
        acc = a * acc + k * w[i]
        y[i] = acc
    return sigma * y


def lowpass_noise_fast(rng, n, dt, tau, sigma):
    from scipy.signal import lfilter
    a = math.exp(-dt / tau)
    w = rng.standard_normal(n) * math.sqrt(1 - a * a)
    y = lfilter([1.0], [1.0, -a], w)
    return sigma * y


# ---------------------------------------------------------------- simulation
def build_run(case, seed, p):
    rng = np.random.default_rng(seed)
    soil_name = p.get("soil", "loam")
    lab = load_lab(soil_name)
    unc = lab["uncertainty"]
    # base true soil: lab values with a jitter within the lab uncertainty
    jit_sig = float(p.get("jitter_sigma", 0.5))
    jitter = {}
    for k, uk in UNC_KEYS.items():
        z = float(np.clip(rng.normal(0, jit_sig), -1.0, 1.0)) if jit_sig > 0 else 0.0
        jitter[k] = z
    mis = dict(p.get("mismatch", {})) if case == "mismatch" else {}
    fac = {}
    for k, z in jitter.items():
        if k in mis:
            continue               # a mismatched value is set exactly by the case
        if k == "k_eq":
            fac["k_eq"] = 1.0 + z * unc["k_eq_rel"]
        elif k in ("c", "K"):
            fac[k] = 1.0 + z * unc[UNC_KEYS[k]] / lab[{"c": "c_kpa", "K": "K_m"}[k]]
        else:
            fac[k] = z * unc[UNC_KEYS[k]]
    fac.update(mis)
    true_soil = transform_soil(lab, fac)
    dev_sigma = {
        "k_eq": (keq(true_soil) / keq(lab) - 1) / unc["k_eq_rel"],
        "n": (true_soil["n"] - lab["n"]) / unc["n"],
        "c": (true_soil["c_kpa"] - lab["c_kpa"]) / unc["c_kpa"],
        "phi": (true_soil["phi_deg"] - lab["phi_deg"]) / unc["phi_deg"],
        "K": (true_soil["K_m"] - lab["K_m"]) / unc["K_m"],
    }

    # effect options for the soil model
    eff = {}
    meas = {}
    if case == "vasilev":
        eff = {"sinkage": "vasilev", "H": float(p["H"])}
    elif case == "lyasko":
        eff = {"sinkage": "lyasko", "m1": float(p["m1"]), "m2": float(p["m2"])}
    elif case == "ding":
        eff = {"sinkage": "ding", "n1": float(p["n1"])}
    elif case == "wong_reece":
        eff = {"stress": "wong_reece", "a1": float(p["a1"]), "a2": float(p["a2"])}
    elif case == "strain_softening":
        eff = {"shear": "softening", "Kr": float(p["Kr"]), "Kw": true_soil["K_m"]}
    elif case == "rate_shear":
        eff = {"shear": "rate", "beta": float(p["beta"]), "v0": float(p.get("v0", 0.05))}
    elif case == "flexible_tyre":
        eff = {"r_soil_factor": float(p["r_factor"])}
    elif case == "bulldozing":
        eff = {"bulldoze": float(p["factor"])}
    elif case in ("wft_angle_offset", "torque_gain", "my_zero_drift", "wss_scale"):
        meas = {case: float(p[{"wft_angle_offset": "offset_deg", "torque_gain": "gain",
                                "my_zero_drift": "drift_nm", "wss_scale": "scale"}[case]])}

    # vehicle and procedure (seeded choices unless given)
    added = float(p.get("added_load_n", rng.choice([2000.0, 3000.0, 4000.0, 5000.0])))
    M = VEHICLE["mass_kg"] + 2 * added / G
    L, hcg = VEHICLE["wheelbase_m"], VEHICLE["cg_height_m"]
    W_rear = VEHICLE["static_rear_wheel_n"] + added
    W_front = (M * G - 2 * W_rear) / 2
    v_base = float(p.get("v_base", rng.uniform(1.0, 1.4)))
    s_max = float(p.get("s_max", rng.uniform(0.85, 0.92)))
    s_brake = float(p.get("s_brake", -rng.uniform(0.05, 0.12)))
    a_up = float(p.get("a_up", rng.uniform(0.12, 0.18)))
    duration = float(p.get("duration_s", rng.uniform(150, 200)))
    latency = float(p.get("gnss_latency_s", rng.uniform(0.04, 0.15)))
    fmt = p.get("format", "log")

    wheel = dict(r=WHEEL["r"], b=WHEEL["b"])
    lab_si = terra.soil_si(true_soil)
    if case == "hardpan":
        z_stat = float(terra.sinkage_eq10(W_rear, wheel["r"], wheel["b"], lab_si["kc"], lab_si["kphi"], lab_si["n"]))
        eff = {"hardpan_h": float(p["h_frac"]) * z_stat}

    # soil along the run (drift): factor functions of run fraction u in [0, 1]
    drift_mode = p.get("drift_mode", "compaction") if case == "drift" else None
    dr = dict(p.get("drift", {})) if case == "drift" else {}
    u_patch = float(p.get("patch_at", 0.5))

    def soil_at(u):
        u = np.asarray(u, float)
        if drift_mode is None:
            return lab_si
        if drift_mode == "compaction":
            w = u                                  # linear along the run
        else:                                      # "patch": another ground from u_patch on
            w = 0.5 * (1 + np.tanh((u - u_patch) / 0.01))
        s2 = terra.soil_si(transform_soil(true_soil, dr))
        return {k: lab_si[k] + w * (s2[k] - lab_si[k]) for k in lab_si}

    # static feasibility check: can the vehicle move on this soil?
    s_grid = np.linspace(0.02, 0.92, 24)
    so0 = soil_at(np.zeros(1))
    so1 = soil_at(np.ones(1))
    for so in (so0, so1):
        Dr, _, _, zr = terra.forces(s_grid, W_rear, so, wheel, eff)
        Df, _, _, zf = terra.forces(s_grid, W_front, so, wheel, eff)
        pull = 2 * Dr + 2 * Df
        if np.max(pull) < 0.05 * M * G:
            refuse("vehicle cannot move on this soil: maximum net traction %.0f N < %.0f N "
                   "(5%% of its weight)" % (np.max(pull), 0.05 * M * G))
        if max(zr[0], zf[0]) > 0.45 * wheel["r"]:
            refuse("vehicle cannot move on this soil: static sinkage %.3f m exceeds 0.45 r"
                   % max(zr[0], zf[0]))
        if max(np.max(zr), np.max(zf)) > 0.6 * wheel["r"]:
            refuse("vehicle cannot move on this soil: sinkage at high slip %.3f m exceeds 0.6 r "
                   "(axle drag; the rigid-wheel model does not hold)" % max(np.max(zr), np.max(zf)))

    # self-propelled cruise slip: sum Dp = 0 -> choose cruise slip a bit above it
    s_fine = np.linspace(-0.2, 0.5, 141)
    pull = 2 * terra.forces(s_fine, W_rear, so0, wheel, eff)[0] + 2 * terra.forces(s_fine, W_front, so0, wheel, eff)[0]
    s_sp = float(s_fine[np.argmax(pull > 0)])
    s_cruise = max(s_sp, 0.0) + float(p.get("s_cruise_extra", rng.uniform(0.03, 0.06)))

    # -------- dynamics at 100 Hz: 4 wheels, locked 4WD (one omega), towed brake trailer
    dt = 0.01
    nst = int(duration / dt) + 1
    t = np.arange(nst) * dt
    V = np.empty(nst); om = np.empty(nst); acc = np.empty(nst); Ftow = np.empty(nst)
    scmd = np.empty(nst); phase = np.empty(nst, dtype=np.int8)
    v = v_base; F = 0.0; a_prev = 0.0
    omega = v / (wheel["r"] * (1 - s_cruise))
    # cycle state machine
    state, t_state, s_b0 = 0, 0.0, 0.0
    cyc_rng = np.random.default_rng(seed + 7919)
    T_cruise, T_up, T_hold, T_down = 3.0, cyc_rng.uniform(5, 7), 0.8, cyc_rng.uniform(2.5, 3.5)
    om_max = 48.0
    tau_tow = 0.25
    W_r_rough = lowpass_noise_fast(rng, nst, dt, 0.25, 0.02)
    for i in range(nst):
        ts = t_state
        if state == 0:        # cruise: the trailer operator holds the base speed
            sc, at = s_cruise, float(np.clip(1.0 * (v_base - v), -0.3, 0.3))
            if ts >= T_cruise:
                state, t_state = 1, 0.0
        elif state == 1:      # accelerate: slip sweep up
            sc = s_cruise + (s_max - s_cruise) * min(ts / T_up, 1.0)
            at = a_up
            if ts >= T_up:
                state, t_state = 2, 0.0
        elif state == 2:      # hold the top slip
            sc, at = s_max, a_up
            if ts >= T_hold:
                state, t_state = 3, 0.0
        elif state == 3:      # slip sweep down to cruise slip
            sc = s_max + (s_cruise - s_max) * min(ts / T_down, 1.0)
            at = -0.15
            if ts >= T_down:
                state, t_state = 4, 0.0
        elif state == 4:      # brake pulse: into skid, trailer released
            sc = s_cruise + (s_brake - s_cruise) * min(ts / 0.3, 1.0)
            at = 0.0
            if v <= v_base + 0.1 or ts > 0.8:
                state, t_state, s_b0 = 5, 0.0, sc
        else:                 # back to cruise slip
            sc = s_b0 + (s_cruise - s_b0) * min(ts / 0.4, 1.0)
            at = 0.0
            if ts >= 0.4:
                state, t_state, s_b0 = 0, 0.0, 0.0
                T_up, T_down = cyc_rng.uniform(5, 7), cyc_rng.uniform(2.5, 3.5)
        t_state += dt
        om_cmd = min(v / (wheel["r"] * (1 - sc)), om_max)
        # drivetrain rate limit (engine / brakes)
        omega += float(np.clip(om_cmd - omega, -60 * dt, 40 * dt))
        omega = max(omega, 0.05)
        s_act = (wheel["r"] * omega - v) / (wheel["r"] * omega)
        dW = M * a_prev * hcg / (2 * L)
        u = t[i] / duration
        so = soil_at(np.array([u]))
        so4 = {k: np.repeat(np.asarray(val, float).reshape(-1)[:1], 4) for k, val in so.items()}
        Wv = np.array([W_rear * (1 + W_r_rough[i]) + dW, W_rear + dW, W_front - dW, W_front - dW])
        vs = s_act * wheel["r"] * omega
        Dp = terra.forces(np.full(4, s_act), Wv, so4, wheel, eff, vslip=np.full(4, vs))[0]
        sumDp = float(np.sum(Dp))
        F_des = min(max(sumDp - M * at, 0.0), 15000.0)
        F += (F_des - F) * dt / tau_tow
        a = (sumDp - F) / M
        V[i], om[i], acc[i], Ftow[i], scmd[i], phase[i] = v, omega, a, F, sc, state
        v += a * dt
        a_prev = a
        if v < 0.25:
            refuse("vehicle got stuck at t=%.1f s (speed %.2f m/s): the soil cannot carry this "
                   "procedure" % (t[i], v))

    return dict(rng=rng, t=t, V=V, om=om, acc=acc, Ftow=Ftow, scmd=scmd, phase=phase,
                W_rough=W_r_rough, M=M, L=L, hcg=hcg, W_rear=W_rear, W_front=W_front,
                wheel=wheel, eff=eff, meas=meas, soil_at=soil_at, duration=duration,
                latency=latency, fmt=fmt, lab=lab, true_soil=true_soil, jitter=jitter,
                dev_sigma=dev_sigma, added=added, v_base=v_base, s_max=s_max,
                s_brake=s_brake, a_up=a_up, s_cruise=s_cruise, soil_name=soil_name,
                drift_mode=drift_mode, drift=dr, patch_at=u_patch)


def measured_wheel(R):
    """500 Hz signals of the measured (left rear) wheel."""
    rng = R["rng"]
    wheel = R["wheel"]
    dur = R["duration"]
    fs = 500.0
    tt = np.arange(0.0, dur - 0.02, 1 / fs)
    V = np.interp(tt, R["t"], R["V"])
    om = np.interp(tt, R["t"], R["om"])
    a = np.interp(tt, R["t"], R["acc"])
    dom = np.gradient(om, tt)
    rough = np.interp(tt, R["t"], R["W_rough"])
    W = R["W_rear"] * (1 + rough) + R["M"] * a * R["hcg"] / (2 * R["L"])
    s = (wheel["r"] * om - V) / (wheel["r"] * om)
    so = R["soil_at"](tt / dur)
    Dp, T, Wm, z0 = terra.forces(s, W, so, wheel, R["eff"], vslip=s * wheel["r"] * om)
    # soil inhomogeneity (process noise), correlated over ~0.15 s
    Dp = Dp + lowpass_noise_fast(rng, tt.size, 1 / fs, 0.15, 35.0)
    T = T + lowpass_noise_fast(rng, tt.size, 1 / fs, 0.15, 15.0)
    # hub frame as the WFT sees it (inertia of the outboard wheel not compensated)
    Fx = Dp - WHEEL["m_w"] * a
    My = T + WHEEL["I_w"] * dom
    Fz = W
    ang = np.cumsum(om) / fs
    ang = ang - ang[0] + rng.uniform(0, 2 * np.pi)
    return dict(tt=tt, V=V, om=om, s=s, W=W, Dp=Dp, T=T, z0=z0, Wm=Wm, Fx=Fx, My=My, Fz=Fz, ang=ang)


# ---------------------------------------------------------------- CAN encoding
def load_db():
    import cantools
    for d in DBC_DIRS:
        if os.path.exists(os.path.join(d, "wft.dbc")):
            db = cantools.database.Database()
            for f in ("wft.dbc", "wheel_speed.dbc", "gps_rt_speedbox.dbc"):
                db.add_dbc_file(os.path.join(d, f))
            return db
    raise SystemExit("DBC files not found")


def make_frames(R, S, seed):
    import can
    rng = np.random.default_rng(seed + 104729)
    db = load_db()
    meas = R["meas"]
    t0 = 1.7e9 + (seed % 1000) * 1000.0 + 123.456
    msgs = []

    def add(ts, name, data, ch):
        m = db.get_message_by_name(name)
        payload = m.encode(data, strict=False)
        msgs.append(can.Message(timestamp=ts, arbitration_id=m.frame_id, is_extended_id=m.is_extended_frame,
                                data=payload, channel=ch, is_rx=True))

    tt = S["tt"]
    n = tt.size
    dur = R["duration"]
    # --- WFT, 500 Hz on can0
    a = S["ang"]
    Fx, Fz, My = S["Fx"].copy(), S["Fz"].copy(), S["My"].copy()
    if "torque_gain" in meas:
        My *= 1 + meas["torque_gain"]
    temp = 24.0 + 6.0 * tt / dur
    if "my_zero_drift" in meas:
        My += meas["my_zero_drift"] * tt / dur
    Fxw = Fx * np.cos(a) - Fz * np.sin(a) + rng.normal(0, 12.0, n)
    Fzw = Fx * np.sin(a) + Fz * np.cos(a) + rng.normal(0, 25.0, n)
    Fyw = lowpass_noise_fast(rng, n, 1 / 500, 0.3, 60.0) + rng.normal(0, 12.0, n)
    My = My + rng.normal(0, 3.0, n)
    Mxw = rng.normal(0, 4.0, n) + Fyw * 0.05
    Mzw = rng.normal(0, 4.0, n)
    ang_rep = a + math.radians(meas.get("wft_angle_offset", 0.0))
    ang_deg = np.degrees(ang_rep) % 360.0
    jit = rng.normal(0, 30e-6, n)
    # DBC ranges: a saturated bridge is clipped and flagged (Status bit 0: overload)
    over = (np.abs(Fxw) > 16383) | (np.abs(Fyw) > 16383) | (np.abs(Fzw) > 32767) | (np.abs(My) > 8191)
    Fxw = np.clip(Fxw, -16384, 16383); Fyw = np.clip(Fyw, -16384, 16383); Fzw = np.clip(Fzw, -32768, 32767)
    My = np.clip(My, -8192, 8191); Mxw = np.clip(Mxw, -8192, 8191); Mzw = np.clip(Mzw, -8192, 8191)
    stat = over.astype(int)
    for i in range(n):
        ts = t0 + tt[i] + 0.0004 + jit[i]
        cnt = i % 256
        add(ts, "WFT_RL_Force", {"Fx_w": float(Fxw[i]), "Fy_w": float(Fyw[i]), "Fz_w": float(Fzw[i]),
                                 "Counter": cnt, "Status": int(stat[i])}, "can0")
        add(ts + 0.00012, "WFT_RL_Moment", {"Mx_w": float(Mxw[i]), "My": float(My[i]), "Mz_w": float(Mzw[i]),
                                           "Counter": cnt, "Status": int(stat[i])}, "can0")
        add(ts + 0.00024, "WFT_RL_Angle", {"WheelAngle": float(min(ang_deg[i], 359.99)), "Counter": cnt,
                                          "Status": 0}, "can0")
    # WFT diag: 1 Hz per mux value
    for k in range(int(dur) - 1):
        ts = t0 + k + 0.2
        add(ts, "WFT_RL_Diag", {"DiagMux": 0, "BridgeTemp": float(24.0 + 6.0 * k / dur), "SupplyVoltage": 12.1}, "can0")
        add(ts + 0.001, "WFT_RL_Diag", {"DiagMux": 1, "SerialNumber": 80812}, "can0")
        add(ts + 0.002, "WFT_RL_Diag", {"DiagMux": 2, "FirmwareMajor": 3, "FirmwareMinor": 2, "CalibrationId": 4711}, "can0")
    # --- wheel speeds 100 Hz on can1 (locked 4WD: one omega; independent sensor noise)
    tw = np.arange(0.0, dur - 0.03, 0.01)
    omw = np.interp(tw, tt, S["om"]) * (1 + meas.get("wss_scale", 0.0))
    rpm = omw * 60 / (2 * np.pi)
    for i in range(tw.size):
        ts = t0 + tw[i] + 0.0031 + rng.normal(0, 50e-6)
        vals = np.clip(rpm[i] * (1 + rng.normal(0, 0.002, 4)), 0, 655.0)
        add(ts, "WSS_WheelSpeeds", {"WheelSpeed_FL": float(vals[0]), "WheelSpeed_FR": float(vals[1]),
                                    "WheelSpeed_RL": float(vals[2]), "WheelSpeed_RR": float(vals[3])}, "can1")
        if i % 10 == 0:
            add(ts + 0.0003, "WSS_Status", {"RollingCounter": (i // 10) % 16, "SensorFault_FL": 0,
                                            "SensorFault_FR": 0, "SensorFault_RL": 0, "SensorFault_RR": 0}, "can1")
    # --- GNSS 20 Hz on can1: fixes on the receiver's 50 ms grid, late by the latency
    gps_off = 1.3e9 + rng.uniform(0, 1e5)         # receiver clock - host clock (unknown)
    week = 2290
    lat = R["latency"]
    gt0 = math.ceil((t0 + gps_off) / 0.05) * 0.05
    k = 0
    while True:
        gt = gt0 + k * 0.05
        th = gt - gps_off - t0                   # fix time on the host timeline
        k += 1
        if th + lat > dur - 0.05:
            break
        if th < 0:
            continue
        vf = float(np.interp(th, tt, S["V"])) + rng.normal(0, 0.015)
        vside = rng.normal(0, 0.015)
        ts = t0 + th + lat + rng.normal(0, 0.0005)
        tow = (gt - week * 604800.0) % 604800.0
        add(ts, "RT_SB_GPS_Time", {"GPS_Week": week, "GPS_Time": round(tow, 3), "Accuracy_GPS_Time": 10,
                                   "Validity_GPS_Week": 1, "Validity_GPS_Time": 1}, "can1")
        sp = abs(vf)
        add(ts + 0.0002, "RT_SB_GPS_Speed", {"GPS_Speed_3D": sp, "GPS_Speed_2D": sp, "Accuracy_GPS_Speed": 3,
                                            "Validity_GPS_Speed_3D": 1, "Validity_GPS_Speed_2D": 1}, "can1")
        add(ts + 0.0004, "RT_SB_INS_Vel_Body_Axes", {"INS_Vel_Sideways_2D": vside, "INS_Vel_Forwards_2D": vf,
                                                    "Accuracy_INS_Vel_Body": 3, "Validity_INS_Vel_Sideways": 1,
                                                    "Validity_INS_Vel_Forwards": 1}, "can1")
        if k % 20 == 0:
            add(ts + 0.0006, "RT_SB_GPS_Status", {"RTK_Status": 0, "GPS_nSv_RTK": 0, "GPS_nSv_2": 0, "GPS_nSv": 12,
                                                 "Firmware_Version_Minor": 1, "Firmware_Version_Intermediate": 0,
                                                 "Firmware_Version_Major": 2, "GPS_Status": 2}, "can1")
    msgs.sort(key=lambda m: m.timestamp)
    return msgs


def write_log(msgs, path):
    import can
    if os.path.exists(path):
        os.remove(path)
    with can.Logger(path) as lg:
        for m in msgs:
            lg.on_message_received(m)


# ---------------------------------------------------------------- main
def parse_p(items):
    out = {}
    for it in items or []:
        k, _, v = it.partition("=")
        try:
            out[k] = json.loads(v)
        except json.JSONDecodeError:
            out[k] = v
    return out


def generate(case, seed, name, outdir, p):
    if case not in CASES:
        raise SystemExit("unknown case %r; cases: %s" % (case, ", ".join(CASES)))
    params = dict(DEFAULTS.get(case, {}))
    params.update(p)
    R = build_run(case, seed, params)
    S = measured_wheel(R)
    msgs = make_frames(R, S, seed)
    ext = {"log": ".log", "asc": ".asc", "blf": ".blf"}[R["fmt"]]
    os.makedirs(outdir, exist_ok=True)
    data_path = os.path.join(outdir, name + ext)
    write_log(msgs, data_path)
    acc = IN_FAMILY.get(case) or OUT_FAMILY.get(case)
    drive = S["s"] > 0.1
    truth = {
        "case": case,
        "family": CASES[case],
        "acceptable_verdicts": list(acc),
        "params": {
            "seed": seed,
            "effect_params": params,
            "soil": R["soil_name"],
            "lab_terrain_file": "benchmarks/foreign8/" + SOILS[R["soil_name"]],
            "lab_soil": {k: R["lab"][k] for k in ("c_kpa", "phi_deg", "K_m", "n", "kc", "kphi")},
            "lab_uncertainty": {k: v for k, v in R["lab"]["uncertainty"].items() if k != "source"},
            "true_soil": R["true_soil"],
            "true_k_eq": keq(R["true_soil"]), "lab_k_eq": keq(R["lab"]),
            "true_minus_lab_in_sigma": {k: round(v, 3) for k, v in R["dev_sigma"].items()},
            "drift": {"mode": R["drift_mode"], "end_values_factors": R["drift"], "patch_at": R["patch_at"]}
            if R["drift_mode"] else None,
            "soil_model_options": R["eff"],
            "measurement_faults": R["meas"],
            "wheel": {"radius_m": WHEEL["r"], "width_m": WHEEL["b"], "mass_kg": WHEEL["m_w"],
                      "inertia_kgm2": WHEEL["I_w"]},
            "vehicle": {"mass_kg": R["M"], "wheelbase_m": R["L"], "cg_height_m": R["hcg"],
                        "drive": "4x4, locked (all wheels one speed)",
                        "static_load_measured_wheel_n": R["W_rear"], "added_load_n": R["added"],
                        "static_load_front_wheel_n": R["W_front"]},
            "procedure": {"kind": "accelerate-brake slip sweeps against a towed brake trailer",
                          "duration_s": R["duration"], "v_base_mps": R["v_base"], "s_max": R["s_max"],
                          "s_brake": R["s_brake"], "a_up_mps2": R["a_up"], "s_cruise": R["s_cruise"]},
            "gnss_latency_s": R["latency"],
            "sinkage_law": "Eq. (10) with the instantaneous vertical load",
            "summary": {"slip_range": [float(S["s"].min()), float(S["s"].max())],
                        "speed_range_mps": [float(S["V"].min()), float(S["V"].max())],
                        "omega_max_radps": float(S["om"].max()),
                        "load_range_n": [float(S["W"].min()), float(S["W"].max())],
                        "mean_Dp_s_gt_0.1_n": float(S["Dp"][drive].mean()) if drive.any() else None,
                        "mean_T_s_gt_0.1_nm": float(S["T"][drive].mean()) if drive.any() else None,
                        "z0_range_m": [float(S["z0"].min()), float(S["z0"].max())],
                        "frames": len(msgs), "wft_overload_samples": int(sum(1 for m in msgs if m.arbitration_id == 0x120 and m.data[7] & 1))},
        },
        "fit_args": [data_path, "--terrain", "benchmarks/foreign8/" + SOILS[R["soil_name"]],
                     "--wheel-radius", str(WHEEL["r"]), "--wheel-width", str(WHEEL["b"]),
                     "--wheel-mass", str(WHEEL["m_w"]), "--wheel-inertia", str(WHEEL["I_w"])],
    }
    with open(os.path.join(outdir, name + "_truth.json"), "w") as f:
        json.dump(truth, f, indent=1, default=float)
    return data_path, truth


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("case")
    ap.add_argument("--seed", type=int, required=True)
    ap.add_argument("--out", required=True)
    ap.add_argument("--outdir", required=True)
    ap.add_argument("--p", action="append", default=[], help="key=value (JSON or plain string)")
    a = ap.parse_args(argv)
    path, truth = generate(a.case, a.seed, a.out, a.outdir, parse_p(a.p))
    print("wrote", path, "(%d frames)" % truth["params"]["summary"]["frames"])


if __name__ == "__main__":
    main()
