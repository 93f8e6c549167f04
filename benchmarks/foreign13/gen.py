#!/usr/bin/env python3
"""foreign13 blind test-data generator: slip-controlled tow test of a compact
4WD utility tractor with one instrumented rear wheel, recorded as CAN logs.

usage: gen.py CASE --seed S --out NAME --outdir DIR [--p key=value ...]
writes DIR/NAME.<fmt> (candump .log, .blf, .asc or .trc) and DIR/NAME_truth.json.
A run the vehicle could not drive exits with code 2 and prints REFUSED: reason.
See README.md.
"""
import argparse
import json
import math
import os
import sys
import time

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
import wong13 as wm  # noqa: E402

try:
    import tomllib
except ImportError:  # pragma: no cover
    import tomli as tomllib

G = 9.81
DT = 0.002                      # simulation step = WFT sample period (s)
WHEEL = dict(r=0.34, b=0.26, m_w=24.0, I_w=1.35)
VEH = dict(M=1900.0, L=1.90, rear_share=0.56, h_hitch=0.45, h_cg=0.75,
           track_f=1.55, track_r=1.10, F_min=350.0, F_max=12000.0, T_max=2500.0)
SOILS = {"siltyclay": "lab_siltyclay.toml", "loamysand": "lab_loamysand.toml"}
REPO_REL = "benchmarks/foreign13"
KEYS = ("keq", "n", "c", "phi", "K")
SD_KEY = {"keq": "k_eq_rel", "n": "n", "c": "c_kpa", "phi": "phi_deg", "K": "K_m"}

CASES_IN = {
    "none": ["none"],
    "slip_sinkage_vasilev": ["slip_sinkage"],
    "slip_sinkage_lyasko": ["slip_sinkage"],
    "slip_sinkage_ding": ["slip_sinkage"],
    "terrain_mismatch": ["terrain_mismatch"],
    "stress_distribution": ["stress_distribution"],
    "terrain_drift": ["terrain_drift"],
}
CASES_OUT = ["bead_slip", "smooth_tread", "snow_cover", "dry_crust",
             "curved_lane", "gnss_filter", "multipass"]
FORMATS = ("log", "blf", "asc", "trc")


class Refused(Exception):
    pass


# --------------------------------------------------------------------------
# parameters
# --------------------------------------------------------------------------
class Draw:
    """Random draws that a --p key=value can override; all recorded."""

    def __init__(self, rng, over):
        self.rng, self.over, self.rec = rng, dict(over), {}

    def u(self, key, lo, hi):
        v = float(self.over.pop(key)) if key in self.over else float(self.rng.uniform(lo, hi))
        self.rec[key] = v
        return v

    def choice(self, key, options):
        if key in self.over:
            v = self.over.pop(key)
        else:
            v = options[int(self.rng.integers(len(options)))]
        self.rec[key] = v
        return v


def load_lab(soil):
    """The lab soil file (wheelsoil's terrain TOML: kc, kphi in kN units), with kc_kn, kphi_kn for this module."""
    with open(os.path.join(HERE, SOILS[soil]), "rb") as f:
        lab = tomllib.load(f)
    return {**lab, "kc_kn": lab["kc"], "kphi_kn": lab["kphi"]}


def field_value(lab, key, off_sd, b):
    """lab value shifted by off_sd lab standard deviations (SI units)."""
    unc = lab["uncertainty"]
    if key == "keq":
        return (lab["kc_kn"] * 1e3 / b + lab["kphi_kn"] * 1e3) * (1.0 + off_sd * unc["k_eq_rel"])
    if key == "n":
        return lab["n"] + off_sd * unc["n"]
    if key == "c":
        return max(0.0, (lab["c_kpa"] + off_sd * unc["c_kpa"]) * 1e3)
    if key == "phi":
        return math.radians(lab["phi_deg"] + off_sd * unc["phi_deg"])
    if key == "K":
        return max(0.002, lab["K_m"] + off_sd * unc["K_m"])
    raise KeyError(key)


def soil_dict(lab, offs, b):
    return {k: field_value(lab, k, offs[k], b) for k in KEYS}


def human_soil(P, b, lab):
    kc_over_keq = lab["kc_kn"] / b / (lab["kc_kn"] / b + lab["kphi_kn"])
    return dict(c_kpa=P["c"] / 1e3, phi_deg=math.degrees(P["phi"]), K_m=P["K"], n=P["n"],
                k_eq_kn=P["keq"] / 1e3, kc_kn=P["keq"] * kc_over_keq * b / 1e3,
                kphi_kn=P["keq"] * (1 - kc_over_keq) / 1e3)


# --------------------------------------------------------------------------
# force tables (W, s[, third axis]) for fast lookups in the time loop
# --------------------------------------------------------------------------
S_LO, S_BRK, S_HI, S_D1, S_D2 = -0.10, 0.20, 1.0, 0.004, 0.02
N1 = int(round((S_BRK - S_LO) / S_D1))
S_GRID = np.concatenate([S_LO + S_D1 * np.arange(N1), S_BRK + S_D2 * np.arange(int(round((S_HI - S_BRK) / S_D2)) + 1)])
NS = S_GRID.size
W0, DW, NW = 2000.0, 400.0, 17          # 2.0 .. 8.4 kN


class Table:
    def __init__(self, slices, axis_vals, r, b, extra=None):
        """slices: list of (P, law) for each third-axis value."""
        self.nu = len(slices)
        self.u0 = float(axis_vals[0])
        self.du = float(axis_vals[1] - axis_vals[0]) if self.nu > 1 else 1.0
        Wg = W0 + DW * np.arange(NW)
        WW, SS = np.meshgrid(Wg, S_GRID, indexing="ij")
        dp, tq, zz = [], [], []
        for P, law in slices:
            PP = {k: v for k, v in P.items()}
            if extra is not None:
                PP.update(extra(P, WW.size))
            o = wm.wheel(WW.ravel(), SS.ravel(), PP, law, r, b)
            if np.isnan(o["Dp"]).any():
                bad = WW.ravel()[np.isnan(o["Dp"])].min()
                raise Refused("the soil cannot carry a wheel load of %.0f N (the wheel would belly)" % bad)
            dp.append(o["Dp"]), tq.append(o["T"]), zz.append(o["z"])
        self.Dp = np.concatenate(dp).tolist()
        self.T = np.concatenate(tq).tolist()
        self.Z = np.concatenate(zz).tolist()

    def look(self, u, W, s):
        """bilinear in (W, s), linear in u -> Dp, T, dDp/ds, z"""
        if self.nu > 1:
            x = (u - self.u0) / self.du
            x = min(max(x, 0.0), self.nu - 1.000001)
            iu = int(x)
            fu = x - iu
        else:
            iu, fu = 0, 0.0
        x = (W - W0) / DW
        x = min(max(x, 0.0), NW - 1.000001)
        iw = int(x)
        fw = x - iw
        if s < S_BRK:
            y = (s - S_LO) / S_D1
            y = max(y, 0.0)
            h = S_D1
        else:
            y = N1 + (s - S_BRK) / S_D2
            y = min(y, NS - 1.000001)
            h = S_D2
        js = int(y)
        fs = y - js
        if js == N1 - 1:
            h = S_GRID[N1] - S_GRID[N1 - 1]
        out = [0.0, 0.0, 0.0, 0.0]
        for k, (uu, wu) in enumerate(((iu, 1.0 - fu), (iu + 1, fu))):
            if wu == 0.0:
                continue
            base = (uu * NW + iw) * NS + js
            b2 = base + NS
            for q, arr in enumerate((self.Dp, self.T, self.Z)):
                a00, a01, a10, a11 = arr[base], arr[base + 1], arr[b2], arr[b2 + 1]
                lo = a00 + (a01 - a00) * fs
                hi = a10 + (a11 - a10) * fs
                out[q if q < 2 else 3] += wu * (lo + (hi - lo) * fw)
                if q == 0:
                    out[2] += wu * ((a01 - a00) * (1 - fw) + (a11 - a10) * fw) / h
        return out


# --------------------------------------------------------------------------
# test procedure
# --------------------------------------------------------------------------
def procedure(dr):
    """Wheel-speed command and slip target schedule (piecewise)."""
    wA = dr.u("omega_A_radps", 5.2, 5.8)
    wB = dr.u("omega_B_radps", 7.0, 7.8)
    t0 = dr.u("t_standstill_s", 2.0, 2.6)
    up = [0.10, 0.18, 0.28, 0.40, 0.55, 0.72]
    down = [0.60, 0.45, 0.32, 0.21, 0.12, 0.06]
    jit = dr.rng.uniform(-0.015, 0.015, len(up) + len(down))
    steps = []  # (t_start, duration, omega_cmd, s_target)
    t = t0
    steps.append(("launch", t, 4.0, wA, 0.04))
    t += 4.0
    for i, s in enumerate(up + down):
        d = float(dr.rng.uniform(4.2, 4.8))
        steps.append(("step", t, d, wA if i < len(up) else wB, round(s + jit[i], 4)))
        t += d
    t_stop = t
    stop_dur = 2.5
    t_end_drive = t_stop + stop_dur
    t_total = t_end_drive + 1.8
    return dict(steps=steps, t0=t0, t_stop=t_stop, stop_dur=stop_dur, t_end_drive=t_end_drive,
                t_total=t_total, wA=wA, wB=wB)


def omega_command(pr, t):
    """commanded wheel speed (rad/s) and slip target at times t (arrays)."""
    cmd = np.zeros_like(t)
    stg = np.full_like(t, 0.04)
    ramp_launch = 0.45
    ramp_change = 0.30
    prev = 0.0
    for kind, ts, d, w, s in pr["steps"]:
        m = (t >= ts) & (t < ts + d)
        if kind == "launch":
            cmd[m] = np.clip((t[m] - ts) / ramp_launch, 0, 1) * w
        else:
            cmd[m] = prev + (w - prev) * np.clip((t[m] - ts) / ramp_change, 0, 1)
        stg[m] = s
        prev = w
    m = (t >= pr["t_stop"]) & (t < pr["t_end_drive"])
    cmd[m] = prev * (1.0 - (t[m] - pr["t_stop"]) / pr["stop_dur"])
    stg[m] = 0.12
    return cmd, stg


# --------------------------------------------------------------------------
# the vehicle
# --------------------------------------------------------------------------
def simulate(cfg, rng):
    r, b = WHEEL["r"], WHEEL["b"]
    M, L = VEH["M"], VEH["L"]
    pr = cfg["proc"]
    N = int(pr["t_total"] / DT) + 1
    t = np.arange(N) * DT
    cmd, stg = omega_command(pr, t)
    # engine governor + driveline: first-order lag
    tau_g = 0.10
    om = np.zeros(N)
    k_g = 1.0 - math.exp(-DT / tau_g)
    for k in range(1, N):
        om[k] = om[k - 1] + (cmd[k - 1] - om[k - 1]) * k_g
    om[om < 1e-6] = 0.0
    domdt = np.gradient(om, DT)
    phi_rot = np.concatenate([[0.0], np.cumsum(0.5 * (om[1:] + om[:-1]) * DT)])
    t_launch = pr["t0"]
    # load roughness: AR(1) noise, 2 % of the static load, active when moving
    def ar1(sd, tau):
        a = math.exp(-DT / tau)
        e = rng.normal(0, sd * math.sqrt(1 - a * a), N)
        out = np.zeros(N)
        for k in range(1, N):
            out[k] = a * out[k - 1] + e[k]
        return out
    Wst_r = VEH["rear_share"] * M * G / 2
    Wst_f = (1 - VEH["rear_share"]) * M * G / 2
    rough = [ar1(0.02 * Wst_f, 0.12), ar1(0.02 * Wst_f, 0.12), ar1(0.02 * Wst_r, 0.12), ar1(0.02 * Wst_r, 0.12)]
    rough = np.array(rough)  # FL, FR, RR, LR
    # geometry factors (wheel ground speed / reference speed at rear-axle centre)
    g = [1.0, 1.0, 1.0, 1.0]
    Rc = cfg.get("curve_R")
    if Rc:
        tf, tr = VEH["track_f"], cfg["track_r"]
        g = [math.hypot(Rc - tf / 2, L) / Rc, math.hypot(Rc + tf / 2, L) / Rc, (Rc + tr / 2) / Rc, (Rc - tr / 2) / Rc]
    tab_f, tab_r = cfg["tab_front"], cfg["tab_rear"]
    tab_rv = cfg.get("tab_rear_virgin", tab_r)
    multipass = cfg["case"] == "multipass"
    x_ref = cfg["x_ref"]
    drift = cfg["case"] == "terrain_drift"
    bead = cfg.get("bead")
    ffg = cfg["ff_gain"]
    Kp, Ki, tau_b, rate_b = 8000.0, 6000.0, 0.20, 8000.0

    V = 0.0
    x = 0.0
    Fd = 0.0
    Ictl = 0.0
    a_prev = 0.0
    om_b = 0.0
    Wf_hist = np.zeros((2, N))
    xs = np.zeros(N)
    ptr = 0
    rec = {k: np.zeros(N) for k in ("V", "x", "a", "W", "Dp", "T", "z", "s", "Fd", "omb", "u", "Fy", "WR")}
    slow = 0.0
    tmax_seen = 0.0
    ffc = None
    for k in range(N):
        tk = t[k]
        w = om[k]
        rw = r * w
        moving = (w > 0.0) or (V > 0.0)
        # mobilisation of the soil forces at launch and their release after the stop
        f = min(1.0, (phi_rot[k]) / 0.25) if tk >= t_launch else 0.0
        if tk > pr["t_end_drive"]:
            f *= math.exp(-(tk - pr["t_end_drive"]) / 0.3)
        dW = (Fd * VEH["h_hitch"] + M * a_prev * VEH["h_cg"]) / L
        lat = 0.0
        if Rc:
            lat = M * V * V / Rc * VEH["h_cg"]
        mv = min(1.0, V / 0.5)
        Wl = [Wst_f - dW / 2 + mv * rough[0, k], Wst_f - dW / 2 + mv * rough[1, k],
              Wst_r + dW / 2 + mv * rough[2, k], Wst_r + dW / 2 + mv * rough[3, k]]
        if Rc:
            lf = (1 - VEH["rear_share"]) * lat
            lr = VEH["rear_share"] * lat
            Wl[0] -= lf / VEH["track_f"]
            Wl[1] += lf / VEH["track_f"]
            Wl[2] += lr / cfg["track_r"]
            Wl[3] -= lr / cfg["track_r"]
        u = min(max(x / x_ref, 0.0), 1.0) if drift else 0.0
        Wf_hist[0, k], Wf_hist[1, k] = Wl[1], Wl[0]   # front wheel ahead of RR is FR, of LR is FL
        xs[k] = x
        Ftr = 0.0
        dFdV = 0.0
        outLR = None
        sLR = 0.0
        if moving:
            rwe = max(rw, 1e-4)
            for i in range(4):
                wi = w
                if i == 3 and bead:
                    wi = max(w - om_b, 1e-6)
                rwi = max(r * wi, 1e-4)
                si = 1.0 - g[i] * V / rwi
                si = min(max(si, -0.1), 1.0)
                if i < 2:
                    tb, uu = tab_f, u
                else:
                    tb, uu = tab_r, u
                    if multipass:
                        xr = x - 0.0
                        if xr < L:
                            tb, uu = tab_rv, 0.0
                        else:
                            while ptr < k and xs[ptr] < xr - L:
                                ptr += 1
                            uu = Wf_hist[0 if i == 2 else 1, ptr]
                dp, tq, dds, zz = tb.look(uu, Wl[i], si)
                Ftr += f * dp
                if -0.1 < si < 1.0:
                    dFdV += f * dds * (-g[i] / rwi)
                if tq > tmax_seen:
                    tmax_seen = tq
                if i == 3:
                    outLR = (dp, tq, zz)
                    sLR = si
            # Newton's law for the vehicle, implicit in V
            a = (Ftr - Fd) / (M - DT * dFdV)
            Vn = V + DT * a
            if Vn < 0.0:
                Vn = 0.0
                a = -V / DT
            # slip controller of the towed dynamometer
            if tk < t_launch + 1.2 or tk > pr["t_end_drive"]:
                Fcmd = VEH["F_min"] if tk <= pr["t_end_drive"] else 0.0
                Ictl = 0.0
            else:
                st = stg[k]
                sctl = 1.0 - V / rwe
                a_des = r * (cmd[min(k + 1, N - 1)] - cmd[k]) / DT * (1.0 - st)
                if k % 10 == 0 or ffc is None:      # feed-forward updated at 50 Hz
                    ffc = 0.0
                    for i in range(4):
                        tb = tab_f if i < 2 else tab_rv
                        ffc += tb.look(0.0, Wl[i], st)[0]
                ff = ffg * ffc - M * a_des
                e = st - sctl
                Ictl = min(max(Ictl + Ki * e * DT, -4000.0), 4000.0)
                Fcmd = min(max(ff + Kp * e + Ictl, VEH["F_min"]), VEH["F_max"])
            dF = (Fcmd - Fd) * DT / tau_b
            Fd += min(max(dF, -rate_b * DT), rate_b * DT)
            if V <= 0.0 and Ftr < Fd:
                a, Vn = 0.0, 0.0
            V = Vn
            x += V * DT
        else:
            a = 0.0
            Fd = 0.0
        if bead and outLR is not None:
            tgt = max(0.0, f * outLR[1] - bead["T_b"]) / bead["c_b"]
            om_b += (tgt - om_b) * DT / 0.04
        # stall watch during the test steps
        if pr["steps"][1][1] < tk < pr["t_stop"] and V < 0.05:
            slow += DT
            if slow > 2.0:
                raise Refused("the vehicle stalled at t = %.1f s (it cannot pull the dynamometer)" % tk)
        else:
            slow = 0.0
        rec["V"][k], rec["x"][k], rec["a"][k] = V, x, a
        rec["W"][k] = Wl[3]
        rec["WR"][k] = Wl[2]
        if outLR is not None:
            rec["Dp"][k], rec["T"][k], rec["z"][k] = f * outLR[0], f * outLR[1], outLR[2]
        rec["s"][k] = sLR
        rec["Fd"][k] = Fd
        rec["omb"][k] = om_b
        rec["u"][k] = u
        rec["Fy"][k] = (Wl[3] / G * V * V / Rc) if Rc else 0.0
        a_prev = a
    if tmax_seen > VEH["T_max"]:
        raise Refused("a wheel torque of %.0f N m exceeds the driveline limit %.0f N m" % (tmax_seen, VEH["T_max"]))
    rec.update(t=t, om=om, domdt=domdt, phi=phi_rot, cmd=cmd, stg=stg, g=np.array(g))
    return rec


# --------------------------------------------------------------------------
# CAN frames
# --------------------------------------------------------------------------
def load_dbs():
    import cantools
    d = os.path.join(HERE, "dbc")
    return {k: cantools.database.load_file(os.path.join(d, k + ".dbc"))
            for k in ("wft", "wheel_speed", "gps_rt_speedbox")}


class Frames:
    def __init__(self):
        self.ts, self.bus, self.id, self.ext, self.data = [], [], [], [], []

    def add(self, ts, bus, fid, ext, data):
        """ts (n,), data (n, dlc) uint8"""
        n = len(ts)
        self.ts.append(np.asarray(ts, float))
        self.bus.append(np.full(n, bus, np.int8))
        self.id.append(np.full(n, fid, np.int64))
        self.ext.append(np.full(n, ext, bool))
        self.data.append([bytes(row) for row in np.asarray(data, np.uint8)])

    def finish(self):
        ts = np.concatenate(self.ts)
        order = np.argsort(ts, kind="stable")
        data = [d for chunk in self.data for d in chunk]
        return (ts[order], np.concatenate(self.bus)[order], np.concatenate(self.id)[order],
                np.concatenate(self.ext)[order], [data[i] for i in order])


def i16(x, scale):
    return np.clip(np.round(np.asarray(x) / scale), -32768, 32767).astype("<i2")


def make_frames(cfg, rec, rng, dbs, imp):
    r = WHEEL["r"]
    t = rec["t"]
    T_end = t[-1]
    host0 = imp["host_epoch"]
    fr = Frames()
    lost = {"wft_frames": 0, "wss_frames": 0, "gnss_frames": 0}
    # ---------------- WFT, 500 Hz on its own clock --------------------------
    ppm = imp["wft_clock_ppm"] * 1e-6
    tw = imp["wft_phase_s"] + np.arange(int((T_end - 0.01) / (DT * (1 + ppm)))) * DT * (1 + ppm)
    tw = tw[tw < T_end - 0.005]
    n = tw.size
    Vw = rec["V"] * rec["g"][3]
    dVdt = np.gradient(Vw, DT)
    Dp = np.interp(tw, t, rec["Dp"])
    Fz = np.interp(tw, t, rec["W"])
    Tq = np.interp(tw, t, rec["T"])
    Fx = Dp - WHEEL["m_w"] * np.interp(tw, t, dVdt)
    My = Tq + WHEEL["I_w"] * np.interp(tw, t, rec["domdt"])
    Fy = np.interp(tw, t, rec["Fy"]) + rng.normal(0, 12.0, n)
    Mx = -Fy * (r - 0.03) + rng.normal(0, 3.0, n)
    Mz = rng.normal(0, 3.0, n) + 0.02 * Tq
    ang = np.deg2rad(imp["angle0_deg"]) + np.interp(tw, t, rec["phi"])
    ca, sa = np.cos(ang), np.sin(ang)
    Fx_w = Fx * ca - Fz * sa + rng.normal(0, imp["wft_noise_N"], n)
    Fz_w = Fx * sa + Fz * ca + rng.normal(0, imp["wft_noise_N"] * 1.4, n)
    Mx_w = Mx * ca - Mz * sa
    Mz_w = Mx * sa + Mz * ca
    My = My + rng.normal(0, imp["wft_noise_Nm"], n)
    angle_deg = np.mod(np.rad2deg(ang), 360.0)
    cnt = (np.arange(n) + imp["counter0"]) % 256
    base = host0 + tw + 0.00035 + np.abs(rng.normal(0, 60e-6, n))
    keep = np.ones((3, n), bool)
    keep &= rng.random((3, n)) > imp["wft_loss_p"]
    for _ in range(imp["wft_bursts"]):
        i0 = int(rng.integers(1000, n - 1000))
        keep[:, i0:i0 + int(rng.integers(3, 13))] = False
    lost["wft_frames"] = int((~keep).sum())
    st = np.zeros(n, np.uint8)
    force = np.zeros((n, 8), np.uint8)
    force[:, 0:2] = i16(Fx_w, 0.5).view(np.uint8).reshape(n, 2)
    force[:, 2:4] = i16(Fy, 0.5).view(np.uint8).reshape(n, 2)
    force[:, 4:6] = i16(Fz_w, 1.0).view(np.uint8).reshape(n, 2)
    force[:, 6] = cnt
    force[:, 7] = st
    mom = np.zeros((n, 8), np.uint8)
    mom[:, 0:2] = i16(Mx_w, 0.25).view(np.uint8).reshape(n, 2)
    mom[:, 2:4] = i16(My, 0.25).view(np.uint8).reshape(n, 2)
    mom[:, 4:6] = i16(Mz_w, 0.25).view(np.uint8).reshape(n, 2)
    mom[:, 6] = cnt
    angf = np.zeros((n, 4), np.uint8)
    araw = (np.round(angle_deg / (360.0 / 65536)).astype(np.int64) % 65536).astype("<u2")
    angf[:, 0:2] = araw.view(np.uint8).reshape(n, 2)
    angf[:, 2] = cnt
    for j, (fid, dat, off) in enumerate(((0x120, force, 0.0), (0x121, mom, 0.000135), (0x122, angf, 0.00027))):
        m = keep[j]
        fr.add(base[m] + off, 0, fid, False, dat[m])
    # WFT diagnostics, 1 Hz per multiplexer value
    dbw = dbs["wft"]
    msg = dbw.get_message_by_name("WFT_RL_Diag")
    td = np.arange(0.3, T_end - 0.1, 1.0)
    for i, tt in enumerate(td):
        for mux in (0, 1, 2):
            sig = {"DiagMux": mux}
            if mux == 0:
                sig.update(BridgeTemp=round(imp["bridge_temp_C"] + 0.02 * tt + rng.normal(0, 0.05), 2),
                           SupplyVoltage=round(12.05 + rng.normal(0, 0.01), 3))
            elif mux == 1:
                sig.update(SerialNumber=imp["wft_serial"])
            else:
                sig.update(FirmwareMajor=3, FirmwareMinor=7, CalibrationId=imp["wft_cal_id"])
            fr.add([host0 + tt + 0.33 * mux + 0.0004], 0, 0x123, False,
                   [list(msg.encode(sig))])
    # ---------------- wheel speeds, 100 Hz ----------------------------------
    dbs_w = dbs["wheel_speed"]
    tsw = imp["wss_phase_s"] + np.arange(int(T_end / 0.01)) * 0.01
    tsw = tsw[tsw < T_end - 0.005]
    m_ = tsw.size
    omw = np.interp(tsw - 0.005, t, rec["om"])     # the module averages over its 10 ms window
    rpm = omw * 60.0 / (2 * math.pi)
    sp = np.zeros((m_, 8), np.uint8)
    for q in range(4):
        v = np.clip(rpm + rng.normal(0, imp["wss_noise_rpm"], m_), 0, 655.35)
        raw = np.round(v / 0.01).astype(">u2")
        sp[:, 2 * q:2 * q + 2] = raw.view(np.uint8).reshape(m_, 2)
    keepw = rng.random(m_) > imp["wss_loss_p"]
    lost["wss_frames"] = int((~keepw).sum())
    hw = host0 + tsw + 0.0004 + np.abs(rng.normal(0, 80e-6, m_))
    fr.add(hw[keepw], 1, 0x300, False, sp[keepw])
    msg = dbs_w.get_message_by_name("WSS_Status")
    tst = imp["wss_phase_s"] + 0.002 + np.arange(int(T_end / 0.1)) * 0.1
    for i, tt in enumerate(tst[tst < T_end - 0.01]):
        d = msg.encode({"RollingCounter": i % 16, "SensorFault_FL": 0, "SensorFault_FR": 0,
                        "SensorFault_RL": 0, "SensorFault_RR": 0})
        fr.add([host0 + tt + 0.0004], 1, 0x301, False, [list(d)])
    # ---------------- GNSS / INS, 20 Hz, late by the receiver latency ----------
    dbg = dbs["gps_rt_speedbox"]
    lat = imp["gnss_latency_s"]
    tow0 = imp["gps_tow0_s"]
    first = math.ceil(tow0 / 0.05) * 0.05
    tfix = (first - tow0) + np.arange(int(T_end / 0.05) + 1) * 0.05
    tfix = tfix[tfix + lat < T_end - 0.01]
    Vsrc = rec["V"]
    if cfg.get("gnss_tau"):
        tau = cfg["gnss_tau"]
        Vf = np.zeros_like(Vsrc)
        kf = 1.0 - math.exp(-DT / tau)
        for k in range(1, Vf.size):
            Vf[k] = Vf[k - 1] + (Vsrc[k] - Vf[k - 1]) * kf
        Vsrc = Vf
    Vg = np.interp(tfix, t, Vsrc)
    nf = tfix.size
    vn = imp["gnss_noise_mps"]
    v2d = np.abs(Vg + rng.normal(0, vn, nf))
    vz = rng.normal(0, 0.01, nf)
    v3d = np.sqrt(v2d ** 2 + vz ** 2)
    vfw = Vg + rng.normal(0, vn, nf)
    vsw = rng.normal(0, 0.01, nf)
    mS = dbg.get_message_by_name("RT_SB_GPS_Speed")
    mV = dbg.get_message_by_name("RT_SB_INS_Vel_Body_Axes")
    mT = dbg.get_message_by_name("RT_SB_GPS_Time")
    mG = dbg.get_message_by_name("RT_SB_GPS_Status")
    harr = host0 + tfix + lat + np.abs(rng.normal(0, 150e-6, nf))
    for i in range(nf):
        tt = harr[i]
        fs = [(mS, {"GPS_Speed_3D": round(v3d[i], 4), "GPS_Speed_2D": round(v2d[i], 4), "Accuracy_GPS_Speed": 12,
                    "Validity_GPS_Speed_3D": 1, "Validity_GPS_Speed_2D": 1}),
              (mV, {"INS_Vel_Sideways_2D": round(vsw[i], 4), "INS_Vel_Forwards_2D": round(vfw[i], 4),
                    "Accuracy_INS_Vel_Body": 10, "Validity_INS_Vel_Sideways": 1, "Validity_INS_Vel_Forwards": 1}),
              (mT, {"GPS_Week": imp["gps_week"], "GPS_Time": round(tow0 + tfix[i], 3), "Accuracy_GPS_Time": 3,
                    "Validity_GPS_Week": 1, "Validity_GPS_Time": 1})]
        for j, (mm, sig) in enumerate(fs):
            if rng.random() < imp["gnss_loss_p"]:
                lost["gnss_frames"] += 1
                continue
            fr.add([tt + 0.00028 * j], 1, mm.frame_id, True, [list(mm.encode(sig))])
    for i, tt in enumerate(np.arange(0.61, T_end - 0.1, 1.0)):
        d = mG.encode({"RTK_Status": 3, "GPS_nSv_RTK": 11, "GPS_nSv_2": 12, "GPS_nSv": 13,
                       "Firmware_Version_Minor": 4, "Firmware_Version_Intermediate": 2,
                       "Firmware_Version_Major": 1, "GPS_Status": 12})
        fr.add([host0 + tt], 1, mG.frame_id, True, [list(d)])
    return fr.finish(), lost


def write_log(path, frames):
    ts, bus, ids, ext, data = frames
    fmt = os.path.splitext(path)[1].lstrip(".")
    if fmt == "log":
        chan = ("can0", "can1")
        with open(path, "w") as f:
            f.write("".join("(%.6f) %s %s#%s\n" % (ts[i], chan[bus[i]],
                                                   ("%08X" % ids[i]) if ext[i] else ("%03X" % ids[i]),
                                                   data[i].hex().upper()) for i in range(ts.size)))
        return
    import can
    W = {"blf": can.BLFWriter, "asc": can.ASCWriter, "trc": can.TRCWriter}[fmt]
    wr = W(path)
    try:
        for i in range(ts.size):
            wr.on_message_received(can.Message(timestamp=float(ts[i]), arbitration_id=int(ids[i]),
                                               is_extended_id=bool(ext[i]), channel=int(bus[i]),
                                               dlc=len(data[i]), data=data[i], is_rx=True))
    finally:
        wr.stop()


# --------------------------------------------------------------------------
# case set-up
# --------------------------------------------------------------------------
def setup(case, seed, over):
    rng = np.random.default_rng(seed)
    dr = Draw(rng, over)
    r, b = WHEEL["r"], WHEEL["b"]
    soil = over.pop("soil", "siltyclay" if seed % 2 else "loamysand")
    if soil not in SOILS:
        raise SystemExit("unknown soil %r" % soil)
    lab = load_lab(soil)
    offs = {k: float(np.clip(rng.normal(0, 0.5), -1.0, 1.0)) for k in KEYS}
    for k in KEYS:
        if "off_" + k in over:
            offs[k] = float(over.pop("off_" + k))
    eff = {}
    law = {}
    cfg = dict(case=case, soil=soil, track_r=VEH["track_r"])
    drift = None
    # values a case may change: all with a clearly measurable effect at 2.5-4.5 lab sd
    cand = ["keq", "n", "c", "phi", "K"] if soil == "siltyclay" else ["keq", "n", "phi", "K"]
    cand_drift = ["keq", "phi", "K"]
    if case == "slip_sinkage_vasilev":
        law["ss"] = ("vasilev", dr.u("H_m", 0.025, 0.045))
    elif case == "slip_sinkage_lyasko":
        law["ss"] = ("lyasko", dr.u("m1", 0.3, 0.6), dr.u("m2", 0.03, 0.10))
    elif case == "slip_sinkage_ding":
        law["ss"] = ("ding", dr.u("n1", 0.40, 0.60))
    elif case == "stress_distribution":
        law["wr"] = (dr.u("a1", 0.25, 0.38), dr.u("a2", 0.10, 0.25))
    elif case == "terrain_mismatch":
        nk = int(dr.choice("n_changed", [1, 2]))
        keys = list(rng.choice(cand, nk, replace=False)) if "keys" not in over else over.pop("keys").split("+")
        for k in keys:
            sz = dr.u("size_sd_" + k, 2.5, 4.0)
            sg = dr.choice("sign_" + k, [-1, 1])
            offs[k] = float(sg) * sz
        eff["changed"] = keys
        eff["offset_lab_sd"] = {k: offs[k] for k in keys}
    elif case == "terrain_drift":
        nk = int(dr.choice("n_changed", [1, 2]))
        keys = list(rng.choice(cand_drift, nk, replace=False)) if "keys" not in over else over.pop("keys").split("+")
        drift = {}
        for k in keys:
            sz = dr.u("drift_sd_" + k, 3.0, 4.5)
            sg = dr.choice("sign_" + k, [-1, 1])
            drift[k] = float(sg) * sz
        eff["changed"] = keys
        eff["total_change_lab_sd"] = dict(drift)
    P = soil_dict(lab, offs, b)
    if case == "bead_slip":
        eff["bead_frac_of_Tref"] = dr.u("bead_frac", 0.72, 0.85)
        eff["bead_creep_at_Tref"] = dr.u("bead_creep", 0.15, 0.25)
    elif case == "smooth_tread":
        dd = dr.u("delta_below_phi_deg", 4.0, 7.0)
        cf = dr.u("ca_over_c", 0.5, 0.8)
        law["smooth"] = (cf * P["c"], P["phi"] - math.radians(dd))
        eff.update(delta_deg=math.degrees(law["smooth"][1]), c_a_kpa=law["smooth"][0] / 1e3)
    elif case == "snow_cover":
        h = dr.u("snow_depth_m", 0.03, 0.05)
        rho0 = dr.u("snow_density0", 100.0, 160.0)
        rhof = 450.0
        sn = dict(zw=h * (1 - rho0 / rhof), pw=dr.u("snow_pw_kpa", 10.0, 18.0) * 1e3)
        z, p = wm.snow_table(P, sn)
        law["snow"] = dict(z=z, sig=p, c=dr.u("snow_c_kpa", 0.8, 1.4) * 1e3,
                           phi=math.radians(dr.u("snow_phi_deg", 19.0, 24.0)), K=dr.u("snow_K_m", 0.010, 0.016))
        eff.update(snow_zw_m=sn["zw"], snow_rho_final=rhof)
    elif case == "dry_crust":
        law["crust"] = (dr.u("crust_Ak", 1.8, 3.0), dr.u("crust_Ac", 1.2, 2.0), dr.u("crust_h_m", 0.015, 0.025))
    elif case == "curved_lane":
        cfg["curve_R"] = dr.u("curve_radius_m", 8.0, 12.0)
        eff["speed_ratio_LR"] = 1.0 - VEH["track_r"] / 2 / cfg["curve_R"]
    elif case == "gnss_filter":
        cfg["gnss_tau"] = dr.u("gnss_filter_tau_s", 0.7, 1.2)
    elif case == "multipass":
        cfg["track_r"] = VEH["track_f"]
        Au = dr.u("Au_kn_m4", 1.5e5, 3.0e5) if soil == "siltyclay" else dr.u("Au_kn_m4", 4.0e5, 7.0e5)
        eff["Au_N_m4"] = Au * 1e3
        eff["jres_fraction"] = dr.u("jres_fraction", 0.3, 0.6)
    pr = procedure(dr)
    cfg["proc"] = pr
    # imperfections of the measurement
    imp = dict(
        gnss_latency_s=dr.u("latency", 0.03, 0.18),
        host_epoch=1.712e9 + seed * 3600.0 + float(rng.uniform(0, 100)),
        gps_tow0_s=float(rng.uniform(1e5, 5e5)), gps_week=int(2300 + seed % 40),
        wft_clock_ppm=float(rng.uniform(-40, 40)), wft_phase_s=float(rng.uniform(0, 0.002)),
        wss_phase_s=float(rng.uniform(0, 0.01)), angle0_deg=float(rng.uniform(0, 360)),
        counter0=int(rng.integers(256)), wft_noise_N=dr.u("wft_noise_N", 15.0, 25.0),
        wft_noise_Nm=dr.u("wft_noise_Nm", 2.5, 4.5), wss_noise_rpm=dr.u("wss_noise_rpm", 0.12, 0.25),
        gnss_noise_mps=dr.u("gnss_noise_mps", 0.010, 0.020), wft_loss_p=2e-4, wft_bursts=2,
        wss_loss_p=5e-4, gnss_loss_p=1e-3, bridge_temp_C=float(rng.uniform(14, 28)),
        wft_serial=int(rng.integers(10000, 99999)), wft_cal_id=int(rng.integers(100, 999)))
    fmt = over.pop("fmt", "log" if seed % 4 in (0, 1) else "blf")
    if fmt not in FORMATS:
        raise SystemExit("unknown format %r" % fmt)
    cfg["ff_gain"] = float(rng.uniform(0.9, 1.1))
    if over:
        raise SystemExit("unknown --p keys: %s" % ", ".join(over))
    return dict(rng=rng, dr=dr, lab=lab, offs=offs, P=P, law=law, eff=eff, cfg=cfg, drift=drift,
                imp=imp, fmt=fmt, soil=soil)


def build_tables(S):
    r, b = WHEEL["r"], WHEEL["b"]
    cfg, P, law, lab = S["cfg"], S["P"], S["law"], S["lab"]
    pr = cfg["proc"]
    # rough length of the run, for the drift axis
    x_est = 0.0
    for kind, ts, d, w, s in pr["steps"]:
        x_est += d * r * w * (1 - s)
    cfg["x_ref"] = x_est
    if S["drift"]:
        us = np.linspace(0, 1, 6)
        slices = []
        for u in us:
            offs = dict(S["offs"])
            for k, dv in S["drift"].items():
                offs[k] = S["offs"][k] + dv * (u - 0.5)
            slices.append((soil_dict(lab, offs, b), law))
        cfg["tab_front"] = cfg["tab_rear"] = Table(slices, us, r, b)
        cfg["tab_rear_virgin"] = cfg["tab_front"]
    elif cfg["case"] == "multipass":
        cfg["tab_front"] = Table([(P, law)], [0.0], r, b)
        Wfs = np.arange(2500.0, 5501.0, 1000.0)
        Au = S["eff"]["Au_N_m4"]
        kap = S["eff"]["jres_fraction"]
        slices = [(dict(P, Wf=wf), dict(law, rut=dict(Au=Au, kappa=kap))) for wf in Wfs]
        cfg["tab_rear"] = Table(slices, Wfs, r, b)
        cfg["tab_rear_virgin"] = cfg["tab_front"]
    else:
        cfg["tab_front"] = cfg["tab_rear"] = Table([(P, law)], [0.0], r, b)
        cfg["tab_rear_virgin"] = cfg["tab_front"]
    # drivability
    Wst_r = VEH["rear_share"] * VEH["M"] * G / 2
    Wst_f = (1 - VEH["rear_share"]) * VEH["M"] * G / 2
    pull = 2 * cfg["tab_front"].look(0.5, Wst_f, 0.9)[0] + 2 * cfg["tab_rear_virgin"].look(0.5, Wst_r, 0.9)[0]
    if pull < 1.3 * VEH["F_min"]:
        raise Refused("the four wheels pull only %.0f N at 90 %% slip, less than the dynamometer's "
                      "rolling resistance %.0f N" % (pull, VEH["F_min"]))
    z = cfg["tab_rear_virgin"].look(0.5, Wst_r, 0.0)[3]
    if z > 0.45 * r:
        raise Refused("static sinkage %.0f mm of the rear wheel: the vehicle would belly" % (z * 1e3))
    if cfg["case"] == "bead_slip":
        Tref = cfg["tab_rear"].look(0.0, Wst_r, 0.6)[1]
        e = S["eff"]
        Tb = e["bead_frac_of_Tref"] * Tref
        cb = (Tref - Tb) / (e["bead_creep_at_Tref"] * pr["wA"])
        cfg["bead"] = dict(T_b=Tb, c_b=cb)
        e.update(T_ref_Nm=Tref, T_b_Nm=Tb, c_b_Nms=cb)


def effect_summary(S, rec):
    """RMS difference between what the wheel did and Wong's model (field soil,
    no effect) at the slip a user would compute from the recorded signals."""
    r, b = WHEEL["r"], WHEEL["b"]
    cfg = S["cfg"]
    t = rec["t"]
    k = np.arange(0, t.size, 25)
    om, V = rec["om"][k], rec["V"][k]
    Vref = V.copy()
    if cfg.get("gnss_tau"):
        Vf = np.zeros_like(rec["V"])
        kf = 1.0 - math.exp(-DT / cfg["gnss_tau"])
        for i in range(1, Vf.size):
            Vf[i] = Vf[i - 1] + (rec["V"][i] - Vf[i - 1]) * kf
        Vref = Vf[k]
    rw = np.maximum(r * om, 1e-6)
    s_app = 1 - Vref / rw
    m = (om > 2.0) & (V > 0.2) & (s_app > 0.03) & (s_app < 0.9) & (t[k] > cfg["proc"]["t0"] + 1.0) \
        & (t[k] < cfg["proc"]["t_stop"])
    W = rec["W"][k][m]
    P = dict(S["P"])
    if S["drift"]:
        P = {kk: np.full(W.size, v) for kk, v in P.items()}
    base = wm.wheel(W, s_app[m], P, {}, r, b)
    Plab = soil_dict(S["lab"], {kk: 0.0 for kk in KEYS}, b)
    lab = wm.wheel(W, s_app[m], Plab, {}, r, b)
    Dp, T = rec["Dp"][k][m], rec["T"][k][m]
    rms = lambda x: float(np.sqrt(np.mean(x ** 2)))
    return dict(n_points=int(m.sum()), slip_app_range=[float(s_app[m].min()), float(s_app[m].max())],
                dp_rms_N=rms(Dp), t_rms_Nm=rms(T),
                dp_vs_wong_field_rms_N=rms(Dp - base["Dp"]), t_vs_wong_field_rms_Nm=rms(T - base["T"]),
                dp_vs_wong_lab_rms_N=rms(Dp - lab["Dp"]), t_vs_wong_lab_rms_Nm=rms(T - lab["T"]))


def jsonable(o):
    if isinstance(o, dict):
        return {str(k): jsonable(v) for k, v in o.items()}
    if isinstance(o, (list, tuple)):
        return [jsonable(v) for v in o]
    if isinstance(o, (np.floating,)):
        return float(o)
    if isinstance(o, (np.integer,)):
        return int(o)
    if isinstance(o, np.ndarray):
        return o.tolist()
    return o


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("case", choices=list(CASES_IN) + CASES_OUT)
    ap.add_argument("--seed", type=int, required=True)
    ap.add_argument("--out", required=True)
    ap.add_argument("--outdir", default=".")
    ap.add_argument("--p", action="append", default=[], metavar="KEY=VALUE")
    a = ap.parse_args(argv)
    over = {}
    for kv in a.p:
        k, _, v = kv.partition("=")
        over[k.strip()] = v.strip()
    t_start = time.time()
    try:
        S = setup(a.case, a.seed, over)
        build_tables(S)
        rec = simulate(S["cfg"], S["rng"])
    except Refused as e:
        print("REFUSED: %s" % e)
        return 2
    dbs = load_dbs()
    frames, lost = make_frames(S["cfg"], rec, S["rng"], dbs, S["imp"])
    os.makedirs(a.outdir, exist_ok=True)
    fname = "%s.%s" % (a.out, S["fmt"])
    path = os.path.join(a.outdir, fname)
    write_log(path, frames)
    cfg = S["cfg"]
    r, b = WHEEL["r"], WHEEL["b"]
    lab = S["lab"]
    fit_args = [fname, "--terrain", "%s/%s" % (REPO_REL, SOILS[S["soil"]]),
                "--wheel-radius", repr(WHEEL["r"]), "--wheel-width", repr(WHEEL["b"]),
                "--wheel-mass", repr(WHEEL["m_w"]), "--wheel-inertia", repr(WHEEL["I_w"])]
    fam = "in" if a.case in CASES_IN else "out"
    form = {"slip_sinkage_vasilev": "vasilev", "slip_sinkage_lyasko": "lyasko",
            "slip_sinkage_ding": "ding"}.get(a.case)
    law = {k: (v if k != "snow" else {kk: vv for kk, vv in v.items() if kk not in ("z", "sig")})
           for k, v in S["law"].items()}
    pr = cfg["proc"]
    moving = rec["V"] > 0.05
    params = dict(
        seed=a.seed, gnss_latency_s=S["imp"]["gnss_latency_s"], soil=S["soil"],
        terrain_file="%s/%s" % (REPO_REL, SOILS[S["soil"]]),
        lab_soil=human_soil(soil_dict(lab, {k: 0.0 for k in KEYS}, b), b, lab),
        true_soil=human_soil(S["P"], b, lab),
        true_soil_start=human_soil(soil_dict(lab, {k: S["offs"][k] - 0.5 * S["drift"].get(k, 0.0) for k in KEYS}, b),
                                   b, lab) if S["drift"] else None,
        true_soil_end=human_soil(soil_dict(lab, {k: S["offs"][k] + 0.5 * S["drift"].get(k, 0.0) for k in KEYS}, b),
                                 b, lab) if S["drift"] else None,
        true_soil_offset_lab_sd=S["offs"],
        drift_total_lab_sd=S["drift"], drift_axis="distance travelled / x_ref (linear, centred on the offsets)",
        drift_x_ref_m=cfg.get("x_ref") if S["drift"] else None,
        effect=S["eff"], law=law, draws=S["dr"].rec,
        wheel=dict(WHEEL), vehicle=dict(VEH, track_r_used=cfg["track_r"]),
        sinkage="vertical balance of Eq. 7 (shear term included) at the actual slip; "
                "slip-sinkage forms applied to that sinkage",
        procedure=dict(kind="slip-controlled tow test (dynamometer drag controller), one pass",
                       steps=[dict(kind=s[0], t_start_s=round(s[1], 3), duration_s=round(s[2], 3),
                                   omega_cmd_radps=round(s[3], 3), slip_target=s[4]) for s in pr["steps"]],
                       t_stop_s=pr["t_stop"], t_total_s=pr["t_total"],
                       distance_m=float(rec["x"][-1]), max_speed_mps=float(rec["V"].max())),
        imperfections=dict(S["imp"], lost=lost, format=S["fmt"],
                           channels="can0 = WFT (BLF/ASC/TRC channel 1), can1 = WSS + GNSS (channel 2)"),
        check=effect_summary(S, rec),
        true_slip_range=[float(rec["s"][moving].min()), float(rec["s"][moving].max())],
    )
    truth = dict(name=a.out, case=a.case, family=fam,
                 acceptable_verdicts=CASES_IN.get(a.case, ["unexplained"]), form=form,
                 params=params, fit_args=fit_args, generator="benchmarks/foreign13/gen.py",
                 runtime_s=round(time.time() - t_start, 2))
    with open(os.path.join(a.outdir, a.out + "_truth.json"), "w") as f:
        json.dump(jsonable(truth), f, indent=1)
    print("%s: %s %s %d frames, %.1f s, %.1f MB, %.1f s cpu" % (
        a.out, a.case, fname, len(frames[0]), pr["t_total"], os.path.getsize(path) / 1e6, time.time() - t_start))
    return 0


if __name__ == "__main__":
    sys.exit(main())
