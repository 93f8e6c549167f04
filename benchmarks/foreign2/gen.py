#!/usr/bin/env python3
"""foreign2: independent generator of field test runs (candump -L logs + truth).

    python gen.py CASE --seed N --latency S --out NAME --outdir DIR [--p key=value ...]
    python gen.py --list

See README.md for the physics and the choices made.
"""
from __future__ import annotations

import argparse
import json
import math
import os
import sys
import time
from dataclasses import replace

import cantools
import numpy as np
from scipy.interpolate import RegularGridInterpolator

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
import wong2 as wm  # noqa: E402

# the project's copies of the sensors' DBC files (identical to the shared ones); FOREIGN2_DBC overrides
DBC_DIR = os.environ.get("FOREIGN2_DBC", os.path.join(os.path.dirname(os.path.dirname(HERE)), "dbc"))

# ----------------------------------------------------------------------------
# vehicle / test constants (hardware.md + paper section 2.2 + own choices)
# ----------------------------------------------------------------------------
G = 9.81
R_WHEEL = 0.47
B_WHEEL = 0.32
M_W = 80.0           # kg, wheel assembly outboard of the WFT
I_W = 11.5           # kg m^2
W_LR = 13000.0       # N: 8 kN static + 5 kN ballast (sand runs)
M_VEH = 3600.0 + 5000.0 / G          # vehicle + ballast
W_RR = 8000.0
W_F = (3600.0 * G - 2 * 8000.0) / 2  # each front wheel
WHEELBASE = 3.4      # m (own choice)
H_CG = 0.95          # m (own choice)
CDA = 2.5            # m^2 aero drag area (own choice, negligible at these speeds)
TAU_PITCH = 0.12     # s: lag of the load transfer (suspension pitch)
TAU_WHEEL = 0.06     # s: lag of the wheel speed behind the driver's demand
DT = 0.002           # s: integration step = WFT sample period

LAB = wm.SAND        # paper Tab. 1 sand (SI units)

CASES = {
    # name: (effect, model, defaults, in_list)
    "none":            ("none", "wong", {}, True),
    "vasilev":         ("slip_sinkage", "vasilev", {"H": 0.03}, True),
    "lyasko":          ("slip_sinkage", "lyasko", {"m1": 0.10, "m2": 0.02}, True),
    "ding":            ("slip_sinkage", "ding", {"n1": 0.15}, True),
    "terrain_k":       ("terrain_mismatch", "terrain_k", {"k_factor": 0.92}, True),
    "terrain_n":       ("terrain_mismatch", "terrain_n", {"n": 1.10}, True),
    "terrain_c":       ("terrain_mismatch", "terrain_c", {"c_kPa": 2.0}, True),
    "terrain_phi":     ("terrain_mismatch", "terrain_phi", {"phi_deg": 24.4}, True),
    "terrain_K":       ("terrain_mismatch", "terrain_K", {"K_m": 0.040}, True),
    "wong_reece":      ("stress_distribution", "wong_reece", {"a1": 0.02, "a2": 0.05}, True),
    "drift":           ("terrain_drift", "drift_k", {"param": "k", "mode": "linear",
                                                     "end_factor": 0.88, "end_dphi_deg": -0.8}, True),
    "tyre_deflection": ("unexplained", "tyre_deflection", {"r_eq": 0.50}, False),
    "fz_gain":         ("unexplained", "fz_gain", {"gain": 1.07}, False),
    "speed_gain":      ("unexplained", "speed_gain", {"gain": 1.04}, False),
    "bulldozing":      ("unexplained", "bulldozing", {"f_b": 0.25, "gamma": 16000.0}, False),
    "lugs":            ("unexplained", "lugs", {"h": 0.012, "n_lugs": 24, "eff": 0.3, "s0": 0.15}, False),
    "load_k":          ("unexplained", "load_k", {"beta": 0.8, "W_ref": 12000.0}, False),
    "fx_crosstalk":    ("unexplained", "fx_crosstalk", {"fz_to_fx": 0.01}, False),
}

ACCEPT = {
    "none": "none", "vasilev": "slip_sinkage (vasilev)", "lyasko": "slip_sinkage (lyasko)",
    "ding": "slip_sinkage (ding)", "terrain_k": "terrain_mismatch (k)",
    "terrain_n": "terrain_mismatch (n)", "terrain_c": "terrain_mismatch (c)",
    "terrain_phi": "terrain_mismatch (phi)", "terrain_K": "terrain_mismatch (K)",
    "wong_reece": "stress_distribution (wong_reece)", "drift": "terrain_drift",
}


def lab_terrain_dict():
    return {"name": "sand (paper Tab. 1)", "c": LAB.c / 1e3, "phi": LAB.phi_deg, "K": LAB.K,
            "n": LAB.n, "kc": LAB.kc / 1e3, "kphi": LAB.kphi / 1e3,
            "units": {"c": "kPa", "phi": "deg", "K": "m", "kc": "kN/m^(n+1)",
                      "kphi": "kN/m^(n+2)"},
            "wheel_width_m": B_WHEEL, "static_load_N": W_LR}


# ----------------------------------------------------------------------------
# soil-wheel physics of one wheel for a case
# ----------------------------------------------------------------------------
class CasePhysics:
    def __init__(self, case: str, p: dict):
        self.case, self.p = case, p
        soil = LAB
        if case == "terrain_k":
            soil = soil.scaled(k_factor=p["k_factor"])
        elif case == "terrain_n":
            soil = replace(soil, n=p["n"])
        elif case == "terrain_c":
            soil = replace(soil, c=p["c_kPa"] * 1e3)
        elif case == "terrain_phi":
            soil = replace(soil, phi_deg=p["phi_deg"])
        elif case == "terrain_K":
            soil = replace(soil, K=p["K_m"])
        self.soil = soil
        self.wheel = wm.Wheel(R_WHEEL, B_WHEEL)

    def point(self, s, W, fk=1.0, ftan=1.0, soil=None):
        """(Dp, T) on one wheel: slip s, load W, local soil factors."""
        case, p = self.case, self.p
        soil = (soil or self.soil).scaled(fk, ftan)
        kw = {}
        wheel = self.wheel
        if case in ("vasilev", "lyasko", "ding"):
            kw["slip_model"], kw["p"] = case, p
        elif case == "wong_reece":
            kw["dist"], kw["a1"], kw["a2"] = "wong_reece", p["a1"], p["a2"]
        elif case == "tyre_deflection":
            wheel = wm.Wheel(p["r_eq"], B_WHEEL)
            kw["torque_radius"] = R_WHEEL
        elif case == "load_k":
            soil = soil.scaled((W / p["W_ref"]) ** (-p["beta"]))
        Dp, T, _, Z = wm.forces(s, W, soil, wheel, **kw)
        if case == "bulldozing":
            Kp = math.tan(math.radians(45 + soil.phi_deg / 2)) ** 2
            Rb = p["f_b"] * B_WHEEL * (0.5 * p["gamma"] * Z * Z * Kp + 2 * soil.c * Z * math.sqrt(Kp))
            Dp -= Rb
        elif case == "lugs":
            th1 = math.acos(1 - min(Z, 0.99 * R_WHEEL) / R_WHEEL)
            n_c = th1 / (2 * math.pi / p["n_lugs"])
            sig_mean = W / (B_WHEEL * R_WHEEL * th1)
            Fl = p["eff"] * n_c * B_WHEEL * p["h"] * (soil.c + sig_mean * soil.tanphi)
            dF = Fl * math.copysign(1 - math.exp(-abs(s) / p["s0"]), s)
            Dp += dF
            T += (R_WHEEL + p["h"]) * dF
        return Dp, T


S_GRID = np.unique(np.concatenate([np.linspace(-0.7, -0.15, 34), np.linspace(-0.15, 0.25, 33),
                                   np.linspace(0.25, 0.99, 30)]))
W_GRID = np.linspace(4000.0, 17000.0, 14)


def build_table(phys: CasePhysics, fk_rng, ft_rng, nk=5, nt=3):
    fk = np.linspace(*fk_rng, nk) if fk_rng[1] > fk_rng[0] else np.array([fk_rng[0] - 1e-3, fk_rng[0] + 1e-3])
    ft = np.linspace(*ft_rng, nt) if ft_rng[1] > ft_rng[0] else np.array([ft_rng[0] - 1e-3, ft_rng[0] + 1e-3])
    shape = (len(S_GRID), len(W_GRID), len(fk), len(ft))
    Dp = np.empty(shape)
    T = np.empty(shape)
    for i, s in enumerate(S_GRID):
        for j, W in enumerate(W_GRID):
            for k, a in enumerate(fk):
                for m, b in enumerate(ft):
                    Dp[i, j, k, m], T[i, j, k, m] = phys.point(float(s), float(W), float(a), float(b))
    grid = (S_GRID, W_GRID, fk, ft)
    return (RegularGridInterpolator(grid, Dp, bounds_error=True),
            RegularGridInterpolator(grid, T, bounds_error=True))


# ----------------------------------------------------------------------------
# random fields along the track
# ----------------------------------------------------------------------------
def random_field(rng, length_m, dx, corr_m, std):
    n = int(length_m / dx) + 1
    w = rng.standard_normal(n + 8 * int(corr_m / dx))
    k = np.arange(-4 * int(corr_m / dx), 4 * int(corr_m / dx) + 1) * dx
    ker = np.exp(-0.5 * (k / corr_m) ** 2)
    f = np.convolve(w, ker, mode="valid")[:n]
    f = f / f.std() * std
    return f


class Track:
    """Soil factors (k, tan phi) and a load roughness along the two wheel tracks."""
    L = 2500.0
    DX = 0.05

    def __init__(self, rng, k_std=0.02, tan_std=0.005, corr=2.0, rough_std=0.02, rough_corr=0.6):
        self.x0 = -20.0
        self.fk = [1 + random_field(rng, self.L, self.DX, corr, k_std) for _ in range(2)]
        self.ft = [1 + random_field(rng, self.L, self.DX, corr, tan_std) for _ in range(2)]
        self.rough = [random_field(rng, self.L, self.DX, rough_corr, rough_std) for _ in range(4)]

    def idx(self, x):
        i = (x - self.x0) / self.DX
        return np.clip(i, 0, len(self.fk[0]) - 2)

    def sample(self, arr, x):
        i = self.idx(x)
        i0 = int(i)
        f = i - i0
        return arr[i0] * (1 - f) + arr[i0 + 1] * f


# ----------------------------------------------------------------------------
# driver (wheel-speed demand) and vehicle simulation
# ----------------------------------------------------------------------------
def plan_cycles(rng, n_cycles):
    cyc = []
    for _ in range(n_cycles):
        cyc.append(dict(P=rng.uniform(8.0, 10.5), t_up=rng.uniform(0.3, 0.5),
                        s_end=rng.uniform(-0.02, 0.04), t_hold_max=rng.uniform(9.0, 12.0),
                        A_b=rng.uniform(3.0, 5.0), s_abs=rng.uniform(0.18, 0.30),
                        V_low=rng.uniform(0.6, 1.1), t_cruise=rng.uniform(0.8, 1.6)))
    return cyc


def simulate(rng, phys_tables, track, drift, n_cycles, t_max=150.0):
    """Integrate the vehicle. Wheels: 0 LR, 1 RR, 2 FL, 3 FR (all 4 driven,
    diffs locked -> one omega). Returns arrays at DT."""
    Dp_i, T_i = phys_tables
    Wst = np.array([W_LR, W_RR, W_F, W_F])
    side = [0, 1, 0, 1]
    xoff = np.array([0.0, 0.0, WHEELBASE, WHEELBASE])
    sgn_tr = np.array([1.0, 1.0, -1.0, -1.0])  # accel -> rear loads up
    cyc = plan_cycles(rng, n_cycles)

    V = rng.uniform(0.7, 1.1)
    omega = V / R_WHEEL            # start rolling freely
    x = 0.0
    a_f = 0.0
    a_prev = 0.0
    theta = rng.uniform(0, 2 * math.pi)
    out = {k: [] for k in ("t", "V", "omega", "omegadot", "a", "x", "s", "Dp", "T", "W", "theta",
                           "fk", "ft")}
    # phases: pre-roll cruise then cycles
    phases = [("cruise", dict(t_cruise=2.0, V_low=V))]
    for c in cyc:
        phases += [("spinup", c), ("hold", c), ("brake", c), ("cruise", c)]
    t = 0.0
    ph_i = 0
    ph_t0 = 0.0
    ph_state = {}

    def soil_factors(xw, sd):
        fk = track.sample(track.fk[sd], xw)
        ft = track.sample(track.ft[sd], xw)
        if drift is not None:
            dk, dt_ = drift(xw)
            fk *= dk
            ft *= dt_
        return fk, ft

    cycles_done = 0
    while ph_i < len(phases) and t < t_max:
        name, c = phases[ph_i]
        if name == "spinup" and not ph_state and t > t_max - 17.0:
            break                       # not enough time left for a full cycle
        tp = t - ph_t0
        rw = omega * R_WHEEL
        s_now = (rw - V) / rw
        nxt = False
        if name == "cruise":
            if "rw" not in ph_state:
                ph_state["rw"] = c["V_low"]
            dem = ph_state["rw"]
            nxt = tp >= c["t_cruise"]
        elif name == "spinup":
            if "rw0" not in ph_state:
                cycles_done += 1
                ph_state["rw0"] = rw
            f = min(tp / c["t_up"], 1.0)
            dem = ph_state["rw0"] + (c["P"] - ph_state["rw0"]) * (0.5 - 0.5 * math.cos(math.pi * f))
            nxt = tp >= c["t_up"] + 0.1
        elif name == "hold":
            dem = c["P"] * (1 + 0.01 * math.sin(0.7 * tp))
            nxt = (s_now < c["s_end"]) or tp > c["t_hold_max"]
        elif name == "brake":
            if "rw" not in ph_state:
                ph_state["rw"] = rw
            ph_state["rw"] = max(ph_state["rw"] - c["A_b"] * DT, V / (1 + c["s_abs"]))
            dem = ph_state["rw"]
            nxt = V <= c["V_low"]
        if nxt:
            ph_i += 1
            ph_t0 = t
            ph_state = {}
            continue
        # wheel speed follows demand (first-order lag)
        om_dem = dem / R_WHEEL
        om_new = om_dem + (omega - om_dem) * math.exp(-DT / TAU_WHEEL)
        omegadot = (om_new - omega) / DT
        # forces at the current state
        rw = omega * R_WHEEL
        s = (rw - V) / rw
        W = np.empty(4)
        pts = np.empty((4, 4))
        for i in range(4):
            xw = x + xoff[i]
            W[i] = (Wst[i] + sgn_tr[i] * M_VEH * a_f * H_CG / WHEELBASE / 2) * \
                (1 + track.sample(track.rough[i], xw))
            fk, ft = soil_factors(xw, side[i])
            pts[i] = (s, W[i], fk, ft)
        Dp = Dp_i(pts)
        T = T_i(pts)
        F = Dp.sum() - 0.5 * 1.2 * CDA * V * abs(V)
        a = F / M_VEH
        out["t"].append(t); out["V"].append(V); out["omega"].append(omega)
        out["omegadot"].append(omegadot); out["a"].append(a); out["x"].append(x)
        out["s"].append(s); out["Dp"].append(Dp[0]); out["T"].append(T[0]); out["W"].append(W[0])
        out["theta"].append(theta); out["fk"].append(pts[0, 2]); out["ft"].append(pts[0, 3])
        # integrate (semi-implicit Euler, 2 ms)
        V_new = V + a * DT
        x += 0.5 * (V + V_new) * DT
        theta += 0.5 * (omega + om_new) * DT
        V = V_new
        omega = om_new
        a_f += (a - a_f) * (1 - math.exp(-DT / TAU_PITCH))
        a_prev = a
        t += DT
    res = {k: np.asarray(v) for k, v in out.items()}
    res["n_cycles"] = cycles_done
    return res


# ----------------------------------------------------------------------------
# CAN encoding
# ----------------------------------------------------------------------------
def load_db():
    db = cantools.database.Database()
    for f in ("wft.dbc", "wheel_speed.dbc", "gps_rt_speedbox.dbc"):
        db.add_dbc_file(os.path.join(DBC_DIR, f))
    return db


def fmt_line(ts, bus, fid, ext, data):
    ids = "%08X" % fid if ext else "%03X" % fid
    return "(%.6f) %s %s#%s\n" % (ts, bus, ids, data.hex().upper())


def make_frames(db, rng, sim, case, p, latency, ns=1.0):
    frames = []
    t = sim["t"]
    n = len(t)
    t0_host = 1700000000.0 + rng.uniform(0, 5e6)
    enc = db.encode_message
    mf = {m.name: m for m in db.messages}

    def add(ts, bus, name, sig):
        m = mf[name]
        data = enc(m.frame_id, sig, strict=True)
        frames.append((ts, bus, m.frame_id, m.is_extended_frame, data))

    # ---- WFT, 500 Hz ------------------------------------------------------
    Fx = sim["Dp"] - M_W * sim["a"]
    Fz = sim["W"].copy()
    My = sim["T"] + I_W * sim["omegadot"]
    if case == "fz_gain":
        Fz = Fz * p["gain"]
    if case == "fx_crosstalk":
        Fx = Fx + p["fz_to_fx"] * Fz
    Fy = 40 * np.sin(2 * np.pi * 0.05 * t + rng.uniform(0, 6)) + rng.normal(0, 30 * ns, n)
    Mx = 0.01 * Fz + rng.normal(0, 10 * ns, n)
    Mz = rng.normal(0, 6 * ns, n)
    a = sim["theta"]
    ca, sa = np.cos(a), np.sin(a)
    Fx_w = Fx * ca - Fz * sa + rng.normal(0, 25 * ns, n)
    Fz_w = Fx * sa + Fz * ca + rng.normal(0, 25 * ns, n)
    My_m = My + rng.normal(0, 8 * ns, n)
    Mx_w = Mx * ca - Mz * sa
    Mz_w = Mx * sa + Mz * ca
    ang_raw = np.round(np.degrees(a) / 0.0054931640625).astype(np.int64) % 65536
    ang = ang_raw * 0.0054931640625
    wft_jit = rng.uniform(0, 40e-6, n)
    for k in range(n):
        ts = t0_host + t[k] + 150e-6 + wft_jit[k]
        cnt = k % 256
        add(ts, "can0", "WFT_RL_Force", {"Fx_w": Fx_w[k], "Fy_w": Fy[k], "Fz_w": Fz_w[k],
                                         "Counter": cnt, "Status": 0})
        add(ts + 136e-6, "can0", "WFT_RL_Moment", {"Mx_w": Mx_w[k], "My": My_m[k], "Mz_w": Mz_w[k],
                                                  "Counter": cnt, "Status": 0})
        add(ts + 232e-6, "can0", "WFT_RL_Angle", {"WheelAngle": float(ang[k]), "Counter": cnt, "Status": 0})
    T_end = t[-1]
    for sec in range(int(T_end)):
        ts = t0_host + sec + 0.5003
        add(ts, "can0", "WFT_RL_Diag", {"DiagMux": 0, "BridgeTemp": 21.3 + 0.002 * sec + rng.normal(0, 0.05),
                                        "SupplyVoltage": 12.05 + rng.normal(0, 0.01)})
        add(ts + 0.3334, "can0", "WFT_RL_Diag", {"DiagMux": 1, "SerialNumber": 20140117})
        add(ts + 0.6667, "can0", "WFT_RL_Diag", {"DiagMux": 2, "FirmwareMajor": 3, "FirmwareMinor": 2,
                                                  "CalibrationId": 1211})

    # ---- wheel speeds, 100 Hz (all four wheels share omega: diffs locked) ---
    ph = rng.uniform(0, 0.01)
    tw = np.arange(ph, T_end, 0.01)
    om = np.interp(tw, t, sim["omega"])
    rpm = om * 60 / (2 * np.pi)
    if rpm.max() > 600:
        raise RuntimeError("wheel speed above the DBC range")
    for k, tt in enumerate(tw):
        sig = {nm: float(max(rpm[k] * (1 + bias) + rng.normal(0, 0.15 * ns), 0.0)) for nm, bias in
               (("WheelSpeed_FL", 0.0), ("WheelSpeed_FR", 0.0), ("WheelSpeed_RL", 0.0), ("WheelSpeed_RR", 0.0))}
        add(t0_host + tt + 0.0007, "can1", "WSS_WheelSpeeds", sig)
        if k % 10 == 0:
            add(t0_host + tt + 0.0011, "can1", "WSS_Status", {"RollingCounter": (k // 10) % 16,
                "SensorFault_FL": 0, "SensorFault_FR": 0, "SensorFault_RL": 0, "SensorFault_RR": 0})

    # ---- GNSS, 20 Hz ------------------------------------------------------
    # GPS clock = host clock + offset (arbitrary); fixes on the 50 ms GPS grid.
    week = int(rng.integers(2280, 2330))
    tow0 = rng.uniform(1e5, 5e5)
    offset = tow0 - t0_host              # gps_tow = host + offset
    # first fix epoch (GPS time) after the host start
    e0 = math.ceil((t0_host + offset) / 0.05) * 0.05
    epochs = np.arange(e0, t0_host + offset + T_end - latency - 0.01, 0.05)
    gain = p["gain"] if case == "speed_gain" else 1.0
    for k, eg in enumerate(epochs):
        t_fix = eg - offset - t0_host     # fix instant, sim time
        if t_fix < 0:
            continue
        Vf = float(np.interp(t_fix, t, sim["V"])) * gain
        arr = t0_host + t_fix + latency + rng.uniform(0.0003, 0.0015)
        add(arr, "can1", "RT_SB_GPS_Time", {"GPS_Week": week, "GPS_Time": round(eg, 3),
                                            "Accuracy_GPS_Time": 10, "Validity_GPS_Week": 1,
                                            "Validity_GPS_Time": 1})
        v2 = abs(Vf + rng.normal(0, 0.02 * ns))
        vz = rng.normal(0, 0.02 * ns)
        add(arr + 0.00026, "can1", "RT_SB_GPS_Speed", {"GPS_Speed_2D": v2,
                                                        "GPS_Speed_3D": math.hypot(v2, vz),
                                                        "Accuracy_GPS_Speed": 3,
                                                        "Validity_GPS_Speed_2D": 1,
                                                        "Validity_GPS_Speed_3D": 1})
        add(arr + 0.00052, "can1", "RT_SB_INS_Vel_Body_Axes", {
            "INS_Vel_Forwards_2D": Vf + rng.normal(0, 0.01 * ns), "INS_Vel_Sideways_2D": rng.normal(0, 0.01 * ns),
            "Accuracy_INS_Vel_Body": 4, "Validity_INS_Vel_Sideways": 1, "Validity_INS_Vel_Forwards": 1})
        if k % 20 == 0:
            add(arr + 0.0009, "can1", "RT_SB_GPS_Status", {"GPS_Status": 12, "GPS_nSv": int(rng.integers(10, 14)),
                "GPS_nSv_2": 0, "GPS_nSv_RTK": 0, "RTK_Status": 0, "Firmware_Version_Major": 2,
                "Firmware_Version_Intermediate": 5, "Firmware_Version_Minor": 7})
    frames.sort(key=lambda f: f[0])
    return frames


# ----------------------------------------------------------------------------
def parse_params(case, kvs):
    p = dict(CASES[case][2])
    for kv in kvs or []:
        k, v = kv.split("=", 1)
        if k not in p:
            raise SystemExit("unknown parameter %r for case %s (known: %s)" % (k, case, list(p)))
        p[k] = v if isinstance(p[k], str) else float(v)
    return p


def effect_size(case, p, s=0.5, W=W_LR):
    """Dp at slip s and load W: field truth (as the analyst would see it in the
    measured signals at the measured slip/load) vs the lab-soil Wong model."""
    lab = CasePhysics("none", {})
    phys = CasePhysics(case if case != "drift" else "none", p)
    truth = phys.point(s, W)[0]
    info = {}
    if case == "drift":
        if p["param"] == "k":
            truth = phys.point(s, W, fk=p["end_factor"])[0]
        else:
            ft = math.tan(math.radians(LAB.phi_deg + p["end_dphi_deg"])) / LAB.tanphi
            truth = phys.point(s, W, ftan=ft)[0]
        info["note"] = "drift: value at the end of the run (start = lab)"
    s_m, W_m, Dp_m = s, W, truth
    if case == "speed_gain":
        s_m = 1 - p["gain"] * (1 - s)
    if case == "fz_gain":
        W_m = W * p["gain"]
    if case == "fx_crosstalk":
        Dp_m = truth + p["fz_to_fx"] * W
    lab_pred = lab.point(s_m, W_m)[0]
    return dict(Dp_field=round(truth, 1), Dp_measured=round(Dp_m, 1), s_measured=round(s_m, 4),
                W_measured=round(W_m, 1), Dp_lab_model=round(lab_pred, 1),
                change_pct=round(100 * (Dp_m - lab_pred) / abs(lab_pred), 1), **info)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("case", nargs="?")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--latency", type=float, default=0.10, help="GNSS velocity latency, s")
    ap.add_argument("--out", default=None)
    ap.add_argument("--outdir", default=".")
    ap.add_argument("--p", action="append", metavar="KEY=VALUE", help="effect parameter (see --list)")
    ap.add_argument("--cycles", type=int, default=None, help="accelerate-brake cycles (default 8-12 random)")
    ap.add_argument("--soil-var", type=float, default=1.0, help="scale of the natural soil variability (0 = uniform)")
    ap.add_argument("--noise", type=float, default=1.0, help="scale of the sensor noise (1 = default sizes)")
    ap.add_argument("--list", action="store_true")
    a = ap.parse_args(argv)
    if a.list:
        print("%-16s %-20s %-16s %-6s %s" % ("case", "effect", "model", "listed", "default params"))
        for k, (e, m, d, inl) in CASES.items():
            print("%-16s %-20s %-16s %-6s %s" % (k, e, m, "yes" if inl else "no", json.dumps(d)))
        return 0
    if a.case not in CASES:
        ap.error("unknown case %r; use --list" % a.case)
    case = a.case
    effect, model, _, _ = CASES[case]
    p = parse_params(case, a.p)
    if case == "drift" and p["param"] == "phi":
        model = "drift_phi"
    out = a.out or "%s_s%d" % (case, a.seed)
    os.makedirs(a.outdir, exist_ok=True)
    t_start = time.time()
    rng = np.random.default_rng(a.seed)
    n_cycles = a.cycles or int(rng.integers(8, 11))
    track = Track(rng, k_std=0.015 * a.soil_var, tan_std=0.004 * a.soil_var)
    phys = CasePhysics(case if case != "drift" else "none", p)

    # drift: a function of distance (start = lab value)
    drift_fn = None
    dist_total = None
    if case == "drift":
        if p["param"] == "k":
            end_k, end_t = p["end_factor"], 1.0
        else:
            end_k = 1.0
            end_t = math.tan(math.radians(LAB.phi_deg + p["end_dphi_deg"])) / LAB.tanphi
        dist_total = 42.0 * n_cycles    # first guess, refined by a second pass

    # table ranges
    def rng_of(arrs, lo_extra=1.0, hi_extra=1.0):
        lo = min(float(x.min()) for x in arrs) * min(lo_extra, 1.0)
        hi = max(float(x.max()) for x in arrs) * max(hi_extra, 1.0)
        return lo - 0.005, hi + 0.005
    fk_rng = rng_of(track.fk, *(sorted([end_k, 1.0]) if case == "drift" else (1, 1)))
    ft_rng = rng_of(track.ft, *(sorted([end_t, 1.0]) if case == "drift" else (1, 1)))
    nk = 7 if case == "drift" and p["param"] == "k" else 5
    nt = 5 if case == "drift" and p["param"] == "phi" else 3
    tables = build_table(phys, fk_rng, ft_rng, nk=nk, nt=nt)
    t_tab = time.time() - t_start

    sim_seed = int(rng.integers(1 << 31))
    # drift: pass 1 measures the run's distance with a guessed drift, pass 2
    # spreads the drift over that distance (D of pass 1, recorded in the truth)
    for _pass in range(2 if case == "drift" else 1):
        if case == "drift":
            D = dist_total
            drift_D = D

            def drift_fn(x, D=D):
                f = min(max(x / D, 0.0), 1.0)
                if p["mode"] == "step":
                    f = 1.0 if x > D / 2 else 0.0
                return 1 + (end_k - 1) * f, 1 + (end_t - 1) * f
        sim = simulate(np.random.default_rng(sim_seed), tables, track, drift_fn, n_cycles)
        if case == "drift":
            dist_total = float(sim["x"][-1])
    db = load_db()
    frames = make_frames(db, np.random.default_rng(sim_seed + 1), sim, case, p, a.latency, ns=a.noise)
    logp = os.path.join(a.outdir, out + ".log")
    with open(logp, "w") as f:
        for ts, bus, fid, ext, data in frames:
            f.write(fmt_line(ts, bus, fid, ext, data))
    params = dict(p)
    if case == "drift":
        params.update(distance_m=round(drift_D, 2), start_factor=1.0,
                      end_factor=(end_k if p["param"] == "k" else None))
        if p["param"] == "phi":
            params.update(phi_start_deg=LAB.phi_deg, phi_end_deg=LAB.phi_deg + p["end_dphi_deg"])
        params.pop("end_dphi_deg" if p["param"] == "k" else "end_factor", None)
        if p["param"] == "phi":
            params.pop("start_factor", None)
        if p["mode"] == "step":
            params["step_at_m"] = round(drift_D / 2, 2)
    if case == "terrain_k":
        params.update(kc_field=LAB.kc * p["k_factor"] / 1e3, kphi_field=LAB.kphi * p["k_factor"] / 1e3)
    truth = {
        "effect": effect, "model": model, "params": params, "gnss_latency_s": a.latency,
        "wheel_radius_m": R_WHEEL, "terrain": lab_terrain_dict(), "seed": a.seed,
        "case": case, "in_list": CASES[case][3],
        "acceptable_verdicts": [ACCEPT[case]] if case in ACCEPT else ["unexplained", "none (if tiny)"],
        "effect_size_at_s0.5": effect_size(case, p),
        "run": {"duration_s": round(float(sim["t"][-1]), 3), "n_cycles": sim["n_cycles"],
                "distance_m": round(float(sim["x"][-1]), 2), "frames": len(frames),
                "slip_max": round(float(sim["s"].max()), 3), "slip_min": round(float(sim["s"].min()), 3),
                "drive": "4WD, diffs locked (one omega)", "soil_variability":
                    {"k_std": 0.015 * a.soil_var, "tanphi_std": 0.004 * a.soil_var, "corr_len_m": 2.0},
                "gen_time_s": round(time.time() - t_start, 2), "table_time_s": round(t_tab, 2)},
    }
    with open(os.path.join(a.outdir, out + "_truth.json"), "w") as f:
        json.dump(truth, f, indent=1)
    print(json.dumps({"log": logp, "frames": len(frames), **truth["run"],
                      "effect_size": truth["effect_size_at_s0.5"]}))
    return 0


if __name__ == "__main__":
    sys.exit(main())
