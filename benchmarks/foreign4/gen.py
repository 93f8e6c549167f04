#!/usr/bin/env python
"""foreign4 field-run generator (written from hardware.md, the paper and the DBCs only).

usage: gen.py CASE --seed S --out NAME --outdir DIR --format {asc,blf,log} [--p key=value ...]

Simulates one field run of the instrumented left-rear wheel of the 4x4 test
vehicle on the foreign4 silty clay loam and writes a CAN log with every
message of hardware.md on can0 (WFT) and can1 (wheel-speed module, GNSS/INS),
plus NAME_truth.json.  See README.md.
"""
import argparse
import json
import math
import os
import sys
import tomllib

import numpy as np
from scipy import signal

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
import terra  # noqa: E402

import can  # noqa: E402
import cantools  # noqa: E402


def _dbc_dir():
    for d in (os.environ.get("F4_DBC_DIR", ""), os.path.join(HERE, "..", "..", "dbc"), "/work/shared/dbc"):
        if d and os.path.exists(os.path.join(d, "wft.dbc")):
            return d
    raise SystemExit("DBC directory not found (set F4_DBC_DIR)")


# ----------------------------------------------------------------- constants --
WHEEL = dict(r=0.41, b=0.26, m=62.0, I=6.4)        # rigid-wheel equivalent of a 32x10.5R16 class tyre
VEH = dict(L=3.30, h=0.95,
           W={"FL": 7000.0, "FR": 7200.0, "RL": 10500.0, "RR": 10300.0})   # rear-laden (ballast in the bed)
VEH["M"] = sum(VEH["W"].values()) / terra.G          # 3568 kg
LAB_TOML = "lab_soil.toml"
DT = 0.01          # vehicle dynamics step (s)
S_MIN = -0.6       # slip clip (skidding)

CASES = {
    # case: (effect, acceptable verdicts, model-name)
    "none": ("none", ["none"], "none"),
    "vasilev": ("slip_sinkage", ["slip_sinkage"], "vasilev"),
    "lyasko": ("slip_sinkage", ["slip_sinkage"], "lyasko"),
    "ding": ("slip_sinkage", ["slip_sinkage"], "ding"),
    "terrain_mismatch": ("terrain_mismatch", ["terrain_mismatch"], "terrain_mismatch"),
    "wong_reece": ("stress_distribution", ["stress_distribution"], "wong_reece"),
    "terrain_drift": ("terrain_drift", ["terrain_drift"], "terrain_drift"),
    # out of family
    "rut": ("rut_from_previous_pass", ["unexplained"], "rut"),
    "progressive_sinkage": ("progressive_slip_sinkage", ["unexplained", "slip_sinkage"], "progressive_sinkage"),
    "soft_tyre": ("soft_tyre_contact", ["unexplained"], "soft_tyre"),
    "wft_lowpass": ("wft_electronics_lowpass", ["unexplained"], "wft_lowpass"),
    "gnss_smoothing": ("gnss_velocity_smoothing", ["unexplained", "none"], "gnss_smoothing"),
    "antenna_pitch": ("gnss_antenna_pitch_lever_arm", ["unexplained", "none"], "antenna_pitch"),
    "wft_usb_delay": ("wft_transport_delay", ["unexplained", "none"], "wft_usb_delay"),
}

DEFAULTS = {
    "vasilev": {"H": 0.08}, "lyasko": {"m1": 1.0, "m2": 0.2}, "ding": {"n1": 0.4},
    "terrain_mismatch": {"k_factor": 0.65}, "wong_reece": {"a1": 0.40, "a2": 0.20},
    "terrain_drift": {"param": "k_factor", "to": 0.65, "shape": "linear"},
    "rut": {"fraction": 0.7, "depth_m": 0.04}, "progressive_sinkage": {"H": 0.08, "L_m": 2.5},
    "soft_tyre": {"r_contact_m": 0.55, "inflation_kpa": 140}, "wft_lowpass": {"fc_hz": 20.0},
    "gnss_smoothing": {"tau_s": 1.0}, "antenna_pitch": {"h_m": 2.1, "pitch_gain": 0.012, "f_hz": 1.3},
    "wft_usb_delay": {"delay_s": 0.08},
}
MISMATCH_KEYS = ("k_factor", "n_delta", "c_factor", "phi_delta_deg", "K_factor")


def load_lab():
    with open(os.path.join(HERE, LAB_TOML), "rb") as f:
        d = tomllib.load(f)
    return {k: d[k] for k in ("c_kpa", "phi_deg", "K_m", "n", "kc", "kphi")}


def apply_change(fs, key, val):
    """Apply one lab-value change (field units)."""
    fs = dict(fs)
    if key == "k_factor":
        fs["kc"] *= val; fs["kphi"] *= val          # k = kc/b + kphi scales by val
    elif key == "n_delta":
        fs["n"] += val
    elif key == "c_factor":
        fs["c_kpa"] *= val
    elif key == "phi_delta_deg":
        fs["phi_deg"] += val
    elif key == "K_factor":
        fs["K_m"] *= val
    else:
        raise SystemExit(f"unknown terrain key {key}")
    return fs


def neutral(key):
    return 0.0 if key.endswith("delta") or key.endswith("delta_deg") else 1.0


# ------------------------------------------------------------ physics setup --
class Physics:
    """Field truth: soil (maybe drifting) + terra options."""

    def __init__(self, case, p, lab):
        self.case, self.p = case, p
        self.lab = lab
        self.field = dict(lab)
        self.opts = {"model": "wong"}
        self.drift = None
        if case in ("vasilev", "lyasko", "ding"):
            self.opts.update(model=case, **{k: float(v) for k, v in p.items()})
        elif case == "terrain_mismatch":
            keys = [k for k in p if k in MISMATCH_KEYS]
            if len(keys) != 1:
                raise SystemExit("terrain_mismatch needs exactly one of " + ", ".join(MISMATCH_KEYS))
            self.field = apply_change(lab, keys[0], float(p[keys[0]]))
        elif case == "wong_reece":
            self.opts["wr"] = (float(p["a1"]), float(p["a2"]))
        elif case == "terrain_drift":
            self.drift = (p["param"], float(p["to"]), p.get("shape", "linear"), float(p.get("at", 0.5)))
        elif case == "rut":
            self.opts["rut"] = (float(p["fraction"]), float(p["depth_m"]))
        elif case == "progressive_sinkage":
            self.opts_dyn = dict(model="vasilev", H=float(p["H"]))     # steady state for vehicle dynamics
        elif case == "soft_tyre":
            self.opts["r_contact"] = float(p["r_contact_m"])

    def soil_at(self, u):
        """Field soil (field units) at run fraction u (0..1)."""
        if self.drift is None:
            return dict(self.field)
        key, to, shape, at = self.drift
        v0 = neutral(key)
        if shape == "step":
            v = to if u >= at else v0
        else:
            v = v0 + (to - v0) * u
        return apply_change(self.lab, key, v)

    def u_nodes(self):
        if self.drift is None:
            return np.array([0.0])
        if self.drift[2] == "step":
            return np.array([0.0, 1.0])
        return np.linspace(0.0, 1.0, 6)

    def dyn_opts(self):
        return getattr(self, "opts_dyn", self.opts)


class Table:
    """Dp, T over (u, W, s) for the vehicle-dynamics loop (all four wheels)."""

    def __init__(self, phys, r, b, opts=None, Wg=None, sg=None, soil_override=None):
        self.Wg = np.linspace(3000.0, 15000.0, 25) if Wg is None else Wg
        self.sg = np.linspace(S_MIN, 1.0, 97) if sg is None else sg
        self.ug = phys.u_nodes() if soil_override is None else np.array([0.0])
        opts = phys.dyn_opts() if opts is None else opts
        WW, SS = np.meshgrid(self.Wg, self.sg, indexing="ij")
        self.Dp = np.zeros((len(self.ug),) + WW.shape)
        self.T = np.zeros_like(self.Dp)
        for iu, u in enumerate(self.ug):
            fs = soil_override if soil_override is not None else phys.soil_at(u)
            o = terra.wheel(WW.ravel(), SS.ravel(), terra.soil_from_field_units(fs), r, b, opts)
            self.Dp[iu] = o["Dp"].reshape(WW.shape)
            self.T[iu] = o["T"].reshape(WW.shape)
        self.step = phys.drift is not None and phys.drift[2] == "step" and soil_override is None
        self.at = phys.drift[3] if self.step else None

    def _uw(self, u):
        if len(self.ug) == 1:
            return 0, 0, 0.0
        if self.step:
            return (1, 1, 0.0) if u >= self.at else (0, 0, 0.0)
        x = np.clip(u, 0, 1) * (len(self.ug) - 1)
        i = min(int(x), len(self.ug) - 2)
        return i, i + 1, x - i

    def lookup(self, arr, u, W, s):
        i0, i1, fu = self._uw(u)
        W = np.clip(W, self.Wg[0], self.Wg[-1]); s = np.clip(s, self.sg[0], self.sg[-1])
        xw = (W - self.Wg[0]) / (self.Wg[1] - self.Wg[0]); iw = np.minimum(xw.astype(int), len(self.Wg) - 2); fw = xw - iw
        xs = (s - self.sg[0]) / (self.sg[1] - self.sg[0]); js = np.minimum(xs.astype(int), len(self.sg) - 2); fs = xs - js

        def bil(A):
            return ((1 - fw) * (1 - fs) * A[iw, js] + fw * (1 - fs) * A[iw + 1, js]
                    + (1 - fw) * fs * A[iw, js + 1] + fw * fs * A[iw + 1, js + 1])
        v = bil(arr[i0])
        if fu > 0:
            v = (1 - fu) * v + fu * bil(arr[i1])
        return v

    def front_slip(self, u, W, Tb):
        """Slip of a towed/braked wheel: T(s) = -Tb (quasi-static)."""
        out = np.empty_like(W)
        for k in range(len(W)):
            Trow = self.lookup(self.T, u, np.full(self.sg.shape, W[k]), self.sg)
            target = -Tb[k] if np.ndim(Tb) else -Tb
            if target <= Trow[0]:
                out[k] = self.sg[0]
            else:
                out[k] = np.interp(target, Trow, self.sg)
        return out


# ------------------------------------------------------------ random fields --
def smooth_field(rng, x, rms, lmin, lmax, nmodes=24):
    """Band-limited random function of position x (m) with the given rms."""
    lam = np.exp(rng.uniform(np.log(lmin), np.log(lmax), nmodes))
    ph = rng.uniform(0, 2 * np.pi, nmodes)
    amp = rng.normal(size=nmodes)
    y = np.zeros_like(x)
    for a, l, p_ in zip(amp, lam, ph):
        y += a * np.sin(2 * np.pi * x / l + p_)
    return y * rms / math.sqrt(0.5 * np.sum(amp ** 2))


# -------------------------------------------------------------- procedure --
def build_procedure(rng, lab_tab, r):
    """Commands at 100 Hz: omega_cmd (rear), mode (0 4x4 locked, 1 rear drive +
    front brakes), Tb (front brake torque per wheel).  The brake levels are
    planned by the 'driver' from the LAB soil so that the rear slip would sit
    at the planned plateau; the true soil decides where it really sits."""
    keys = []          # (t, omega_cmd, Tb, mode)
    tgt = []           # (t0, t1, target slip) held by the driver with the front brakes
    t = 0.0

    def hold(dur, om, tb, mode):
        nonlocal t
        keys.append((t, om, tb, mode)); t += dur; keys.append((t, om, tb, mode))

    def ramp(dur, om0, om1, tb0, tb1, mode):
        nonlocal t
        keys.append((t, om0, tb0, mode)); t += dur; keys.append((t, om1, tb1, mode))

    Wr, Wf = VEH["W"]["RL"], 0.5 * (VEH["W"]["FL"] + VEH["W"]["FR"])
    sg = np.linspace(S_MIN, 1.0, 321)
    Dr = lab_tab.lookup(lab_tab.Dp, 0.0, np.full_like(sg, Wr), sg)
    Df = lab_tab.lookup(lab_tab.Dp, 0.0, np.full_like(sg, Wf), sg)
    Tf = lab_tab.lookup(lab_tab.T, 0.0, np.full_like(sg, Wf), sg)
    neg = sg <= 0.2

    def brake_for(s_target):
        F = np.interp(s_target, sg, Dr)                    # rear pull per wheel
        # front wheel: Dp(s_f) = -F  (Dp increasing in s)
        sf = np.interp(-F, Df[neg], sg[neg]) if -F > Df[0] else sg[0]
        return max(0.0, -float(np.interp(sf, sg, Tf)))

    J = lambda: rng.uniform(0.9, 1.15)  # noqa: E731
    hold(4.0 * J(), 0, 0, 0)                                   # standstill, logger check
    # launch A (4x4): throttle step, hold, brake to rest
    oA = rng.uniform(4.0, 5.0)
    ramp(0.2, 0, oA, 0, 0, 0); hold(7.0 * J(), oA, 0, 0); ramp(3.0, oA, 0, 0, 0, 0); hold(2.0 * J(), 0, 0, 0)
    # launch B (4x4): bigger step, step down, brake to rest
    oB = rng.uniform(7.5, 8.5)
    ramp(0.2, 0, oB, 0, 0, 0); hold(6.0 * J(), oB, 0, 0); ramp(1.0, oB, 3.0, 0, 0, 0)
    hold(4.0 * J(), 3.0, 0, 0); ramp(3.0, 3.0, 0, 0, 0, 0); hold(2.0 * J(), 0, 0, 0)
    # drawbar staircase at low speed (4x2, front brakes as the load)
    oL = rng.uniform(4.5, 5.5)
    hold(1.0, 0, 0, 1)
    ramp(2.0, 0, oL, 0, 0, 1)
    tb = 0.0
    plan = []
    for st in (0.15, 0.30, 0.45, 0.60, 0.75):
        st = st + rng.uniform(-0.03, 0.03)
        nb = brake_for(st); plan.append((round(st, 3), round(nb, 1)))
        t0_ = t; ramp(1.5, oL, oL, tb, nb, 1); hold(7.5 * J(), oL, nb, 1); tb = nb; tgt.append((t0_, t, st))
    stall = 1.6 * brake_for(0.97)
    ramp(2.0, oL, oL, tb, stall, 1); hold(3.0 * J(), oL, stall, 1)             # stall: s -> 1
    ramp(2.0, oL, 0, stall, stall, 1); ramp(1.0, 0, 0, stall, 0, 1); hold(2.0, 0, 0, 1)
    # drawbar staircase at the higher speed, descending
    oH = rng.uniform(8.5, 9.5)
    first = brake_for(0.85 + rng.uniform(-0.03, 0.03))
    ramp(3.0, 0, oH, 0, 0.5 * first, 1); tb = 0.5 * first
    for st in (0.85, 0.65, 0.50, 0.35, 0.20):
        st = st + rng.uniform(-0.03, 0.03)
        nb = brake_for(st); plan.append((round(st, 3), round(nb, 1)))
        t0_ = t; ramp(1.5, oH, oH, tb, nb, 1); hold(6.5 * J(), oH, nb, 1); tb = nb; tgt.append((t0_, t, st))
    ramp(1.5, oH, oH, tb, 0, 1); hold(4.0 * J(), oH, 0, 1)                     # towed fronts only
    ramp(4.0, oH, 0, 0, 0.6 * stall, 1); ramp(1.0, 0, 0, 0.6 * stall, 0, 1); hold(2.0, 0, 0, 1)
    # launch C (4x4): throttle ramp, hold, brake
    oC = rng.uniform(9.5, 10.5)
    hold(1.0, 0, 0, 0)
    ramp(4.0 * J(), 0, oC, 0, 0, 0); hold(3.0 * J(), oC, 0, 0); ramp(2.5, oC, 0, 0, 0, 0)
    hold(max(3.0, 152.0 - t), 0, 0, 0)
    k = np.array(keys)
    tt = np.arange(0.0, k[-1, 0], DT)
    om = np.interp(tt, k[:, 0], k[:, 1])
    Tb = np.interp(tt, k[:, 0], k[:, 2])
    # mode is piecewise constant: take the mode of the segment start
    idx = np.searchsorted(k[:, 0], tt, side="right") - 1
    mode = k[idx, 3].astype(int)
    s_tgt = np.full(len(tt), np.nan)
    for (a_, b_, st) in tgt:
        s_tgt[(tt >= a_) & (tt < b_)] = st
    proc = dict(omega_launch_A=round(oA, 2), omega_launch_B=round(oB, 2), omega_staircase_low=round(oL, 2),
                omega_staircase_high=round(oH, 2), omega_launch_C=round(oC, 2),
                planned_plateaus_slip_and_front_brake_torque_Nm=plan)
    return tt, om, Tb, mode, s_tgt, proc


def simulate_vehicle(rng, phys, tab, tt, om_cmd, Tb_ff, mode, s_tgt, r, xtot=280.0):
    """4x4 longitudinal dynamics at 100 Hz."""
    M, L, h = VEH["M"], VEH["L"], VEH["h"]
    Wst = np.array([VEH["W"][k] for k in ("FL", "FR", "RL", "RR")])
    n = len(tt)
    V = np.zeros(n); om = np.zeros(n); omf = np.zeros(n); a = np.zeros(n); af = np.zeros(n)
    x = np.zeros(n); sr = np.zeros(n); sf = np.zeros(n); Fsum = np.zeros(n)
    tau_gov, acc_max, dec_max, tau_susp = 0.30, 14.0, 10.0, 0.12
    # track-wise traction scatter of the other three wheels (+LR) for the dynamics
    xs = np.linspace(0, 600, 6001)
    var = [smooth_field(rng, xs, 0.03, 2.0, 25.0) for _ in range(4)]
    Vk, omk, afk, xk = 0.0, 0.0, 0.0, 0.0
    # the driver holds the planned slip with the front brakes, watching a live
    # slip display (lagged 0.3 s), PI-like, pedal rate limited
    s_disp, integ, tb_prev = 0.0, 0.0, 0.0
    Kp, Ki, rate = 500.0, 250.0, 400.0
    Tb = np.zeros(n)
    for k in range(n):
        dom = np.clip((om_cmd[k] - omk) / tau_gov, -dec_max, acc_max)
        omk = max(0.0, omk + dom * DT)
        dW = M * afk * h / (2 * L)
        W = Wst + np.array([-dW, -dW, dW, dW])
        vr = r * omk
        if vr > 1e-3:
            s = 1.0 - Vk / vr
        elif Vk > 1e-3:
            s = S_MIN
        else:
            s = 0.0
        s = min(max(s, S_MIN), 1.0)
        g = min(1.0, max(vr, Vk) / 0.05)
        u = min(xk / xtot, 1.0)
        s_disp += (s - s_disp) * DT / 0.3
        if np.isnan(s_tgt[k]):
            tb_k = Tb_ff[k]; integ = 0.0
        else:
            e = s_tgt[k] - s_disp
            integ += e * DT
            tb_k = max(0.0, Tb_ff[k] + Kp * e + Ki * integ)
        tb_k = min(max(tb_k, tb_prev - rate * DT), tb_prev + rate * DT) if mode[k] == 1 else 0.0
        tb_prev = tb_k
        Tb[k] = tb_k
        if mode[k] == 0:
            ss = np.full(4, s)
            F = tab.lookup(tab.Dp, u, W, ss)
            omfk = omk
            sfk = s
        else:
            sfr = tab.front_slip(u, W[:2], np.full(2, tb_k))
            ss = np.array([sfr[0], sfr[1], s, s])
            F = tab.lookup(tab.Dp, u, W, ss)
            sfk = float(np.mean(sfr))
            omfk = Vk / (r * (1.0 - sfk)) if Vk > 1e-4 else 0.0
        ix = min(int(xk / 0.1), 6000)
        F = F * g * (1.0 + np.array([var[i][ix] for i in range(4)]))
        Ft = float(np.sum(F))
        ak = Ft / M
        if Vk <= 0.0 and ak < 0.0:
            ak = 0.0
        Vk = max(0.0, Vk + ak * DT)
        if Vk == 0.0:
            ak = 0.0 if Ft < 0 else ak
        afk += (ak - afk) * DT / tau_susp
        xk += Vk * DT
        V[k], om[k], omf[k], a[k], af[k], x[k], sr[k], sf[k], Fsum[k] = Vk, omk, omfk, ak, afk, xk, s, sfk, Ft
    return dict(t=tt, V=V, om=om, omf=omf, a=a, af=af, x=x, s=sr, sf=sf, F=Fsum, Tb=Tb)


# ------------------------------------------------------------- LR wheel -----
def lr_wheel_forces(rng, phys, dyn, tq, r, b, x_total):
    """Exact (GL) left-rear forces at the WFT sample times tq."""
    t = dyn["t"]
    V = np.interp(tq, t, dyn["V"]); om = np.interp(tq, t, dyn["om"])
    x = np.interp(tq, t, dyn["x"]); af = np.interp(tq, t, dyn["af"])
    dVdt = np.interp(tq, t, dyn["a"])
    domdt = np.interp(tq, t, np.gradient(dyn["om"], DT))
    M, L, h = VEH["M"], VEH["L"], VEH["h"]
    rough = smooth_field(rng, x, 0.025 * VEH["W"]["RL"], 0.4, 4.0)          # track roughness
    W = VEH["W"]["RL"] + M * af * h / (2 * L) + rough
    vr = r * om
    s = np.where(vr > 1e-3, 1.0 - V / np.maximum(vr, 1e-9), np.where(V > 1e-3, S_MIN, 0.0))
    s = np.clip(s, S_MIN, 1.0)
    g = np.minimum(1.0, np.maximum(vr, V) / 0.05)
    u = np.clip(x / x_total, 0, 1)
    # soil along the track: a few per cent scatter of k, c, tan(phi)
    ek = smooth_field(rng, x, 0.03, 1.5, 20.0)
    ec = smooth_field(rng, x, 0.03, 1.5, 20.0)
    ep = smooth_field(rng, x, 0.015, 1.5, 20.0)
    if phys.drift is None:
        fsu = [phys.soil_at(0.0)] * 1
        base = {k: np.full(len(tq), v) for k, v in fsu[0].items()}
    else:
        keys = ("c_kpa", "phi_deg", "K_m", "n", "kc", "kphi")
        if phys.drift[2] == "step":
            f0, f1 = phys.soil_at(0.0), phys.soil_at(1.0)
            base = {k: np.where(u >= phys.drift[3], f1[k], f0[k]) for k in keys}
        else:
            f0, f1 = phys.soil_at(0.0), phys.soil_at(1.0)
            base = {k: f0[k] + (f1[k] - f0[k]) * u for k in keys}
    soil = terra.soil_from_field_units(base)
    soil["kc"] = soil["kc"] * (1 + ek); soil["kphi"] = soil["kphi"] * (1 + ek)
    soil["c"] = soil["c"] * (1 + ec)
    soil["phi"] = np.arctan(np.tan(soil["phi"]) * (1 + ep))
    out_Dp = np.zeros(len(tq)); out_T = np.zeros(len(tq)); out_Z = np.zeros(len(tq))
    CH = 20000
    if phys.case == "progressive_sinkage":
        H, Ld = float(phys.p["H"]), float(phys.p["L_m"])
        Z0 = terra.z0_static(W, r, b, soil["n"], soil["kc"], soil["kphi"])
        Zt = Z0 + H * np.clip(s, 0, 1)
        Z = np.empty_like(Zt); z = Z0[0]
        dtq = np.diff(tq, prepend=tq[0])
        for i in range(len(tq)):
            z += (Zt[i] - z) * min(1.0, vr[i] * dtq[i] / Ld)
            z = max(z, Z0[i])      # never less than the static sinkage
            Z[i] = z
        for i0 in range(0, len(tq), CH):
            sl = slice(i0, i0 + CH)
            ss = {k: v[sl] for k, v in soil.items()}
            o = terra.forces_gl(Z[sl], s[sl], ss, r, b, {})
            out_Dp[sl], out_T[sl], out_Z[sl] = o["Dp"], o["T"], Z[sl]
    else:
        for i0 in range(0, len(tq), CH):
            sl = slice(i0, i0 + CH)
            ss = {k: v[sl] for k, v in soil.items()}
            o = terra.wheel(W[sl], s[sl], ss, r, b, phys.opts)
            out_Dp[sl], out_T[sl], out_Z[sl] = o["Dp"], o["T"], o["Z"]
    Dp = out_Dp * g; T = out_T * g
    return dict(W=W, Dp=Dp, T=T, Z=out_Z, s=s, V=V, om=om, dVdt=dVdt, domdt=domdt, x=x)


# ------------------------------------------------------------------ main ----
def parse_p(items):
    p = {}
    for it in items or []:
        k, v = it.split("=", 1)
        try:
            p[k] = json.loads(v)
        except json.JSONDecodeError:
            p[k] = v
    return p


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("case", choices=sorted(CASES))
    ap.add_argument("--seed", type=int, required=True)
    ap.add_argument("--out", required=True)
    ap.add_argument("--outdir", default=".")
    ap.add_argument("--format", choices=("asc", "blf", "log"), default="asc")
    ap.add_argument("--p", action="append", default=[], help="key=value (repeatable)")
    a = ap.parse_args(argv)
    generate(a.case, a.seed, a.out, a.outdir, a.format, parse_p(a.p))


def generate(case, seed, name, outdir, fmt, p_in):
    rng = np.random.default_rng(seed)
    p = dict(DEFAULTS.get(case, {}))
    glob = {k: p_in.pop(k) for k in list(p_in) if k in ("gnss_latency_s",)}
    if case == "terrain_mismatch" and any(k in MISMATCH_KEYS for k in p_in):
        p = {}
    p.update(p_in)
    r, b = WHEEL["r"], WHEEL["b"]
    lab = load_lab()
    phys = Physics(case, p, lab)
    lab_phys = Physics("none", {}, lab)
    lab_tab = Table(lab_phys, r, b)
    tab = Table(phys, r, b)

    # ------------------------------------------------ procedure + dynamics
    tt, om_cmd, Tb, mode, s_tgt, proc = build_procedure(rng, lab_tab, r)
    st = rng.bit_generator.state
    dyn = simulate_vehicle(rng, phys, tab, tt, om_cmd, Tb, mode, s_tgt, r)
    if phys.drift is not None:       # second pass with the true run length for the drift fraction
        rng.bit_generator.state = st
        dyn = simulate_vehicle(rng, phys, tab, tt, om_cmd, Tb, mode, s_tgt, r, xtot=max(dyn["x"][-1], 1.0))
    if dyn["V"].max() < 0.5:
        raise SystemExit("refused: the vehicle cannot make this run on this soil (V never exceeds 0.5 m/s)")
    # launches must move the vehicle: check that launch A gets it rolling
    x_total = max(dyn["x"][-1], 1.0)
    duration = tt[-1]

    # ------------------------------------------------ device clocks
    host0 = 1778746353.0 + 86400.0 * (seed % 50) + rng.uniform(0, 3600)     # logger epoch of t = 0
    ppm_wft = rng.uniform(20, 60) * 1e-6
    ppm_wss = -rng.uniform(10, 40) * 1e-6
    ppm_gnss = rng.uniform(-15, 15) * 1e-6
    lat = float(glob.get("gnss_latency_s", rng.uniform(0.04, 0.16)))
    t_end = duration - 0.3

    # ------------------------------------------------ WFT (can0)
    t0w = rng.uniform(0.0, 0.002)
    nw = int((t_end - t0w) / (0.002 * (1 + ppm_wft)))
    tq = t0w + np.arange(nw) * 0.002 * (1 + ppm_wft)                    # true sample instants
    lr = lr_wheel_forces(rng, phys, dyn, tq, r, b, x_total)
    Fx = lr["Dp"] - WHEEL["m"] * lr["dVdt"]
    Fz = lr["W"]
    My = lr["T"] + WHEEL["I"] * lr["domdt"]
    Fy = smooth_field(rng, lr["x"], 120.0, 1.0, 15.0) + 40.0
    Mx = -Fy * (r - 0.5 * np.clip(lr["Z"], 0, 0.2)) + smooth_field(rng, lr["x"], 15.0, 0.5, 5.0)
    Mz = 0.02 * Fx + smooth_field(rng, lr["x"], 8.0, 0.5, 5.0)
    theta = np.interp(tq, dyn["t"], np.concatenate([[0.0], np.cumsum(0.5 * (dyn["om"][1:] + dyn["om"][:-1]) * DT)]))
    ang0 = rng.uniform(0, 2 * np.pi)
    ang = ang0 + theta
    ca, sa = np.cos(ang), np.sin(ang)
    ch = dict(Fx_w=Fx * ca - Fz * sa, Fz_w=Fx * sa + Fz * ca, Fy_w=Fy,
              Mx_w=Mx * ca - Mz * sa, Mz_w=Mx * sa + Mz * ca, My=My)
    if case == "wft_lowpass":
        bb, aa = signal.butter(2, float(p["fc_hz"]), fs=500.0)
        for k in ch:
            zi = signal.lfilter_zi(bb, aa) * ch[k][0]
            ch[k] = signal.lfilter(bb, aa, ch[k], zi=zi)[0]
    nsd = dict(Fx_w=18.0, Fz_w=22.0, Fy_w=12.0, Mx_w=4.0, Mz_w=4.0, My=2.5)
    for k in ch:
        ch[k] = ch[k] + rng.normal(0, nsd[k], nw)
    ang_deg = np.mod(np.degrees(ang), 360.0)
    # lost frames: scattered single frames + two bursts
    keep = np.ones((nw, 3), bool)
    keep &= rng.random((nw, 3)) > 3e-4
    bursts = []
    for _ in range(2):
        i0 = int(rng.uniform(0.1, 0.9) * nw); ln = int(rng.integers(6, 40))
        keep[i0:i0 + ln, :] = False; bursts.append((round(float(tq[i0]), 3), ln))
    usb = rng.exponential(0.00015, nw) + 0.0006
    extra = float(p["delay_s"]) if case == "wft_usb_delay" else 0.0
    rx_w = tq + usb + extra
    # ------------------------------------------------ WSS (can1)
    tw0 = rng.uniform(0, 0.01)
    ns = int((t_end - tw0) / (0.01 * (1 + ppm_wss)))
    tws = tw0 + np.arange(ns) * 0.01 * (1 + ppm_wss)
    th_r = np.concatenate([[0.0], np.cumsum(0.5 * (dyn["om"][1:] + dyn["om"][:-1]) * DT)])
    th_f = np.concatenate([[0.0], np.cumsum(0.5 * (dyn["omf"][1:] + dyn["omf"][:-1]) * DT)])

    def wss_read(thc, omc):
        d = 0.004
        om_now = np.interp(tws - d, dyn["t"], omc)
        Tp = np.clip((2 * np.pi / 48) / np.maximum(om_now, 1e-3), 0.01, 0.5)
        a1 = np.interp(tws - d, dyn["t"], thc); a0 = np.interp(tws - d - Tp, dyn["t"], thc)
        w = (a1 - a0) / Tp * (1 + rng.normal(0, 0.003, ns))
        w[om_now < 0.25] = 0.0
        return np.clip(w * 60 / (2 * np.pi), 0, 655.35)
    rpm = dict(FL=wss_read(th_f, dyn["omf"]), FR=wss_read(th_f, dyn["omf"]),
               RL=wss_read(th_r, dyn["om"]), RR=wss_read(th_r, dyn["om"]))
    rx_s = tws + 0.0003 + rng.exponential(0.0001, ns)
    # ------------------------------------------------ GNSS (can1)
    gps_off = host0 - 315964800.0 + 18.0 + rng.uniform(-2.0, 2.0)        # GPS seconds at host t=0
    g0 = math.ceil((gps_off + 0.2) / 0.05) * 0.05
    ge = np.arange(g0, gps_off + t_end - lat - 0.05, 0.05)               # fix epochs in GPS time
    te = (ge - gps_off) * (1 + ppm_gnss)                                  # true (host) time of fix
    Vtrue = np.interp(te, dyn["t"], dyn["V"])
    Vm = Vtrue.copy()
    if case == "gnss_smoothing":
        al = 1 - math.exp(-0.05 / float(p["tau_s"]))
        Vm = signal.lfilter([al], [1, -(1 - al)], Vtrue, zi=[(1 - al) * Vtrue[0]])[0]
    if case == "antenna_pitch":
        wn = 2 * np.pi * float(p["f_hz"]); ze = 0.35; kg = float(p["pitch_gain"])
        sysp = signal.lti([kg * wn ** 2, 0.0], [1.0, 2 * ze * wn, wn ** 2])      # pitch rate from accel
        _, qrate, _ = signal.lsim(sysp, dyn["a"], dyn["t"])
        Vm = Vtrue - float(p["h_m"]) * np.interp(te, dyn["t"], qrate)
    nge = len(ge)
    Vf = Vm + rng.normal(0, 0.012, nge)
    Vside = rng.normal(0, 0.015, nge) + 0.01 * np.sin(te / 7.0)
    vz = rng.normal(0, 0.02, nge)
    valid = np.ones(nge, bool)
    drops = []
    movers = np.where(Vtrue > 0.5)[0]
    for _ in range(int(rng.integers(1, 4))):
        if len(movers) < 100:
            break
        i0 = int(rng.choice(movers)); ln = int(rng.uniform(0.6, 2.0) / 0.05)
        valid[i0:i0 + ln] = False; drops.append((round(float(te[i0]), 2), round(ln * 0.05, 2)))
    # hold last valid value during dropouts
    Vf_s = Vf.copy(); Vside_s = Vside.copy()
    for i in range(1, nge):
        if not valid[i]:
            Vf_s[i] = Vf_s[i - 1]; Vside_s[i] = Vside_s[i - 1]
    rx_g = te + lat + rng.uniform(0.0, 0.0008, nge)

    # ------------------------------------------------ encode
    dbd = _dbc_dir()
    db_w = cantools.database.load_file(os.path.join(dbd, "wft.dbc"))
    db_s = cantools.database.load_file(os.path.join(dbd, "wheel_speed.dbc"))
    db_g = cantools.database.load_file(os.path.join(dbd, "gps_rt_speedbox.dbc"))
    mF = db_w.get_message_by_name("WFT_RL_Force"); mM = db_w.get_message_by_name("WFT_RL_Moment")
    mA = db_w.get_message_by_name("WFT_RL_Angle"); mD = db_w.get_message_by_name("WFT_RL_Diag")
    mS = db_s.get_message_by_name("WSS_WheelSpeeds"); mST = db_s.get_message_by_name("WSS_Status")
    mGS = db_g.get_message_by_name("RT_SB_GPS_Speed"); mGV = db_g.get_message_by_name("RT_SB_INS_Vel_Body_Axes")
    mGT = db_g.get_message_by_name("RT_SB_GPS_Time"); mGST = db_g.get_message_by_name("RT_SB_GPS_Status")

    def q(x, sc, lo, hi):
        return np.clip(np.round(np.asarray(x) / sc) * sc, lo, hi)

    frames = []   # (t, channel, id, ext, data)
    Fxw = q(ch["Fx_w"], 0.5, -16384, 16383.5); Fyw = q(ch["Fy_w"], 0.5, -16384, 16383.5)
    Fzw = q(ch["Fz_w"], 1.0, -32768, 32767)
    Mxw = q(ch["Mx_w"], 0.25, -8192, 8191.75); Myq = q(ch["My"], 0.25, -8192, 8191.75)
    Mzw = q(ch["Mz_w"], 0.25, -8192, 8191.75)
    angq = np.mod(np.round(ang_deg / 0.0054931640625), 65536) * 0.0054931640625
    debug = os.environ.get("F4_DEBUG")
    intended = []

    def enc(m, d):
        if debug:
            intended.append(dict(d))
        return m.encode(d, scaling=True, strict=False)
    for i in range(nw):
        cnt = i % 256
        t_i = rx_w[i]
        if keep[i, 0]:
            frames.append((t_i, 0, mF.frame_id, False, enc(mF, {"Fx_w": Fxw[i], "Fy_w": Fyw[i], "Fz_w": Fzw[i], "Counter": cnt, "Status": 0})))
        if keep[i, 1]:
            frames.append((t_i + 0.000128, 0, mM.frame_id, False, enc(mM, {"Mx_w": Mxw[i], "My": Myq[i], "Mz_w": Mzw[i], "Counter": cnt, "Status": 0})))
        if keep[i, 2]:
            frames.append((t_i + 0.000240, 0, mA.frame_id, False, enc(mA, {"WheelAngle": angq[i], "Counter": cnt, "Status": 0})))
    # WFT diagnostics: 1 Hz per mux value
    serial = 20417731
    for sec in range(int(t_end)):
        tb_ = sec + 0.37 + rng.uniform(0, 0.001) + extra
        temp = 17.5 + 6.0 * (1 - math.exp(-sec / 300.0)) + rng.normal(0, 0.03)
        frames.append((tb_, 0, mD.frame_id, False, enc(mD, {"DiagMux": 0, "BridgeTemp": round(temp, 2), "SupplyVoltage": round(12.2 + rng.normal(0, 0.01), 3)})))
        frames.append((tb_ + 0.333, 0, mD.frame_id, False, enc(mD, {"DiagMux": 1, "SerialNumber": serial})))
        frames.append((tb_ + 0.667, 0, mD.frame_id, False, enc(mD, {"DiagMux": 2, "FirmwareMajor": 3, "FirmwareMinor": 4, "CalibrationId": 1187})))
    # WSS
    lost_s = rng.random(ns) < 1e-4
    for i in range(ns):
        if lost_s[i]:
            continue
        frames.append((rx_s[i], 1, mS.frame_id, False, enc(mS, {"WheelSpeed_FL": round(rpm["FL"][i], 2), "WheelSpeed_FR": round(rpm["FR"][i], 2),
                                                              "WheelSpeed_RL": round(rpm["RL"][i], 2), "WheelSpeed_RR": round(rpm["RR"][i], 2)})))
        if i % 10 == 3:
            frames.append((rx_s[i] + 0.00025, 1, mST.frame_id, False, enc(mST, {"RollingCounter": (i // 10) % 16, "SensorFault_FL": 0, "SensorFault_FR": 0, "SensorFault_RL": 0, "SensorFault_RR": 0})))
    # GNSS
    week = np.floor(ge / 604800.0).astype(int)
    tow = ge - week * 604800.0
    for i in range(nge):
        v = int(valid[i]); tr = rx_g[i]
        sp2 = abs(Vf_s[i] + 0.003 * rng.normal())
        sp3 = math.sqrt(sp2 ** 2 + vz[i] ** 2)
        frames.append((tr, 1, mGS.frame_id, True, enc(mGS, {"GPS_Speed_3D": round(sp3, 4), "GPS_Speed_2D": round(sp2, 4), "Accuracy_GPS_Speed": 8 if v else 60,
                                                            "Validity_GPS_Speed_3D": v, "Validity_GPS_Speed_2D": v})))
        frames.append((tr + 0.00027, 1, mGV.frame_id, True, enc(mGV, {"INS_Vel_Sideways_2D": round(Vside_s[i], 4), "INS_Vel_Forwards_2D": round(Vf_s[i], 4),
                                                                      "Accuracy_INS_Vel_Body": 10 if v else 70, "Validity_INS_Vel_Sideways": v, "Validity_INS_Vel_Forwards": v})))
        frames.append((tr + 0.00054, 1, mGT.frame_id, True, enc(mGT, {"GPS_Week": int(week[i]), "GPS_Time": round(tow[i], 3), "Accuracy_GPS_Time": 3,
                                                                      "Validity_GPS_Week": 1, "Validity_GPS_Time": 1})))
        if i % 20 == 7:
            frames.append((tr + 0.00081, 1, mGST.frame_id, True, enc(mGST, {"RTK_Status": 0, "GPS_nSv_RTK": 0, "GPS_nSv_2": 0, "GPS_nSv": int(11 + rng.integers(0, 4)) if v else 3,
                                                                            "Firmware_Version_Minor": 7, "Firmware_Version_Intermediate": 2, "Firmware_Version_Major": 1,
                                                                            "GPS_Status": 12 if v else 2})))
    if debug:
        frames = [f + (d,) for f, d in zip(frames, intended)]
    frames.sort(key=lambda f: f[0])
    if debug:
        import pickle
        with open(debug, "wb") as fh:
            pickle.dump(dict(frames=[(host0 + f[0], f[1], f[2], f[3], f[5]) for f in frames],
                             tq=host0 + tq, rx_w=host0 + rx_w, Fx=Fx, Fz=Fz, My=My, Dp=lr["Dp"], T=lr["T"], W=lr["W"],
                             s=lr["s"], V=lr["V"], om=lr["om"], ang=ang_deg), fh)
        frames = [f[:5] for f in frames]
    os.makedirs(outdir, exist_ok=True)
    path = os.path.join(outdir, f"{name}.{fmt}")
    if os.path.exists(path):
        os.remove(path)
    chan = ("can0", "can1")
    w = can.Logger(path)
    for (t_, c_, id_, ext, data) in frames:
        w.on_message_received(can.Message(timestamp=host0 + t_, arbitration_id=id_, is_extended_id=ext,
                                          data=data, dlc=len(data), channel=chan[c_], is_rx=True))
    w.stop()

    # ------------------------------------------------ truth
    W5 = np.array([VEH["W"]["RL"]])
    f_lab = terra.wheel(W5, 0.5, terra.soil_from_field_units(lab), r, b, {})["Dp"][0]
    if phys.drift is None and case != "progressive_sinkage":
        f_true = terra.wheel(W5, 0.5, terra.soil_from_field_units(phys.field), r, b, phys.opts)["Dp"][0]
    elif case == "progressive_sinkage":
        f_true = terra.wheel(W5, 0.5, terra.soil_from_field_units(lab), r, b, phys.opts_dyn)["Dp"][0]
    else:
        f_true = terra.wheel(W5, 0.5, terra.soil_from_field_units(phys.soil_at(1.0)), r, b, phys.opts)["Dp"][0]
    moving = lr["V"] > 0.05
    sl = lr["s"][moving & (lr["s"] > 0)]
    hist = np.histogram(sl, bins=[0, 0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 0.9, 1.0001])[0] / 500.0
    eff, acc, model = CASES[case]
    truth = dict(
        case=case, effect=eff, params=p, acceptable_verdicts=acc, model=model,
        gnss_latency_s=round(lat, 4), wheel_radius_m=r, wheel_width_m=b,
        wheel_mass_kg=WHEEL["m"], wheel_inertia_kgm2=WHEEL["I"],
        terrain_toml=LAB_TOML, lab_soil=lab,
        field_soil=(phys.field if phys.drift is None else {"start": phys.soil_at(0.0), "end": phys.soil_at(1.0),
                                                          "drift": dict(param=phys.drift[0], to=phys.drift[1], shape=phys.drift[2], at=phys.drift[3], along="distance fraction")}),
        dp_at_s05_static_load_N=dict(lab_model=round(f_lab, 1), field_truth=round(f_true, 1),
                                    change_pct=round(100 * (f_true / f_lab - 1), 1),
                                    note="W = static LR load; for drift: end of run; for progressive_sinkage: steady state"),
        seed=seed, format=fmt, file=os.path.basename(path), duration_s=round(duration, 2),
        distance_m=round(float(x_total), 1), max_speed_mps=round(float(dyn["V"].max()), 2),
        static_loads_N=VEH["W"], vehicle_mass_kg=round(VEH["M"], 1),
        slip_seconds_per_decile=[round(float(h_), 2) for h_ in hist],
        procedure=proc,
        clocks=dict(wft_ppm=round(ppm_wft * 1e6, 2), wss_ppm=round(ppm_wss * 1e6, 2), gnss_ppm_vs_host=round(ppm_gnss * 1e6, 2),
                    gps_minus_host_s=round(gps_off - host0, 4), host_start_epoch=host0),
        wft_lost_bursts=bursts, wft_frames_lost=int((~keep).sum()), gnss_invalid_intervals=drops,
        wft_extra_transport_delay_s=extra,
        notes="written by benchmarks/foreign4/gen.py from hardware.md, the seed paper and the DBCs only",
    )
    with open(os.path.join(outdir, f"{name}_truth.json"), "w") as f:
        json.dump(truth, f, indent=1, default=float)
    return truth


if __name__ == "__main__":
    main()
