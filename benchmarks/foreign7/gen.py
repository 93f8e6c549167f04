#!/usr/bin/env python
"""foreign7: single-wheel soil-bin testbed time-series generator.

usage: gen.py CASE --seed S --out NAME --outdir DIR [--p key=value ...]

Writes DIR/NAME.csv, DIR/NAME.json (sidecar: wheel) and DIR/NAME_truth.json.
See README.md for the physics, the rig, the noise model and the cases.
"""
import argparse
import json
import os
import sys
import tomllib

import numpy as np
from scipy import signal

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
import terra  # noqa: E402

MAIN = os.path.dirname(os.path.dirname(HERE))  # the repository root (was "/work/main")

# --------------------------------------------------------------------------- rig presets
PRESETS = {
    # rigid aluminium wheel with sand-blasted rim, fine dry sand
    "sand": dict(toml="soil_sand.toml", r=0.25, b=0.15, loads=[350.0, 500.0, 700.0], V=0.12,
                 I_w=0.35, m_w=9.0, gamma=15500.0, lam=0.05),
    # rigid steel wheel (rubber-coated rim), moist sandy loam
    "loam": dict(toml="soil_loam.toml", r=0.30, b=0.20, loads=[1000.0, 1500.0, 2000.0], V=0.15,
                 I_w=0.9, m_w=16.0, gamma=17500.0, lam=0.06),
}

# --------------------------------------------------------------------------- cases
CASES = {
    # in family
    "none": dict(family="in", acceptable=["none"], form=None, defaults={}),
    "vasilev": dict(family="in", acceptable=["slip_sinkage"], form="vasilev", defaults={"H": 0.03}),
    "lyasko": dict(family="in", acceptable=["slip_sinkage"], form="lyasko", defaults={"m1": 0.8, "m2": 0.2}),
    "ding": dict(family="in", acceptable=["slip_sinkage"], form="ding", defaults={"n1": 0.35}),
    "mismatch": dict(family="in", acceptable=["terrain_mismatch"], form=None, defaults={"changes": {"phi_deg": 5.0}}),
    "wong_reece": dict(family="in", acceptable=["stress_distribution"], form=None, defaults={"a1": 0.1, "a2": 0.35}),
    "drift": dict(family="in", acceptable=["terrain_drift"], form=None,
                  defaults={"mode": "passes", "changes": {"k_eq": 1.7, "K_m": 0.6}, "at_pass": None}),
    # out of family
    "tilt": dict(family="out", acceptable=["unexplained"], form=None, defaults={"alpha_deg": 2.5}),
    "sinkage_gain": dict(family="out", acceptable=["unexplained"], form=None, defaults={"gain": 1.6, "drift_mm": 2.0}),
    "bulldozing": dict(family="out", acceptable=["unexplained"], form=None, defaults={"f_b": 1.0}),
    "peak_shear": dict(family="out", acceptable=["unexplained"], form=None, defaults={"Kr": 0.6, "Kw_rel": 1.5}),
    "lugged": dict(family="out", acceptable=["unexplained"], form=None, defaults={"h_g": 0.012, "n_g": 16}),
    "rate": dict(family="out", acceptable=["unexplained"], form=None, defaults={"beta": 0.2, "speeds": [0.04, 0.2]}),
    "drivetrain_drag": dict(family="out", acceptable=["unexplained"], form=None, defaults={"T0": 8.0, "mu_b": 0.006}),
}

PROTOCOL_DEFAULTS = {
    "soil": "sand",          # preset: sand | loam
    "r": None, "b": None,    # override the wheel
    "loads": None,           # dead weights (N), cycled over passes
    "passes": 6,
    "V": None,               # carriage speed (m/s)
    "fs": 100.0,             # logging rate (Hz)
    "program": "mixed",      # mixed | sweeps | steps
    "smax": 0.8,
    "steps": [0.15, 0.3, 0.45, 0.6, 0.75],
    "ramp_s": 15.0,          # duration of one slip ramp (s)
    "hold_s": 4.0,           # duration of one slip step (s)
    "torque": True,          # torque channel present
    "sinkage": True,         # sinkage channel present
    "cycle_col": True,
    "valid_col": True,
    "noise": 1.0,            # scale of all measurement noise
    "bin_offset_sigma": 0.5,  # bin-vs-lab offsets, uniform within +-this many lab sigmas
}

MULT_KEYS = ("k_eq", "kc", "kphi", "K_m")
ADD_KEYS = ("n", "c_kpa", "phi_deg")


def parse_value(v):
    try:
        return json.loads(v)
    except Exception:
        return v


def load_toml(path):
    with open(path, "rb") as f:
        return tomllib.load(f)


def apply_changes(lab, changes, w=1.0):
    """Return a soil dict (toml units) with `changes` applied with weight w
    (multiplicative keys: factor**w, additive keys: w*delta).  k_eq scales kc
    and kphi together."""
    d = dict(lab)
    for k, v in (changes or {}).items():
        if k == "k_eq":
            d["kc"] = d["kc"] * v ** w
            d["kphi"] = d["kphi"] * v ** w
        elif k in ("kc", "kphi", "K_m"):
            d[k] = d[k] * v ** w
        elif k in ADD_KEYS:
            d[k] = d[k] + w * v
        else:
            raise ValueError("unknown soil key %r" % k)
    return d


def ar1(rng, n, rho, sd):
    """Stationary AR(1) sequence (standard deviation sd, lag-one correlation rho)."""
    e = rng.standard_normal(n) * sd * np.sqrt(1 - rho * rho)
    y0 = rng.standard_normal() * sd
    return signal.lfilter([1.0], [1.0, -rho], e, zi=[rho * y0])[0]


def field_along(rng, x, corr_len, sd, dx=0.01):
    """Random field along the lane (AR(1) on a 1 cm grid), sampled at x."""
    L = max(float(np.max(x)) if len(x) else 0.0, 0.0) + 0.05
    g = np.arange(0.0, L + dx, dx)
    f = ar1(rng, len(g), np.exp(-dx / corr_len), sd)
    return np.interp(x, g, f)


# --------------------------------------------------------------------------- protocol
def pass_segments(P, rng, pidx):
    """List of segments (duration, V_frac0, V_frac1, s0, s1, cycle_slot, valid)."""
    s_lo = 0.05
    segs = [(2.0, 0.0, 0.0, 0.0, 0.0, -1, 0),          # loaded wheel at rest, logging started
            (2.5, 0.0, 1.0, s_lo, s_lo, -1, 1),        # carriage and wheel accelerate
            (2.0, 1.0, 1.0, s_lo, s_lo, -1, 1)]
    smax = P["smax"]
    R = P["ramp_s"]

    def sweep(slot):
        return [(R, 1.0, 1.0, s_lo, smax, slot, 1), (1.5, 1.0, 1.0, smax, smax, slot, 1),
                (R, 1.0, 1.0, smax, s_lo, slot, 1)]

    def steps(slot):
        st = list(P["steps"])
        order = rng.permutation(len(st)) if pidx % 2 else np.arange(len(st))
        return [(P["hold_s"], 1.0, 1.0, st[i], st[i], slot, 1) for i in order]

    gap = [(2.0, 1.0, 1.0, s_lo, s_lo, -1, 1)]
    if P["program"] == "mixed":
        body = sweep(0) + gap + steps(1)
    elif P["program"] == "sweeps":
        body = sweep(0) + gap + sweep(1)
    elif P["program"] == "steps":
        body = steps(0) + gap + steps(1)
    else:
        raise ValueError(P["program"])
    segs += body + [(1.5, 1.0, 1.0, s_lo, s_lo, -1, 1), (2.5, 1.0, 0.0, s_lo, s_lo, -1, 1)]
    return segs


def build_timeline(P, rng):
    fs = P["fs"]
    dt = 1.0 / fs
    out = {k: [] for k in ("t", "Vc", "sc", "slot", "valid", "pass")}
    t0 = 0.0
    for p in range(P["passes"]):
        segs = pass_segments(P, rng, p)
        tl = 0.0
        for (d, v0, v1, s0, s1, slot, val) in segs:
            n = int(round(d * fs))
            u = (np.arange(n) + 0.5) / n
            sm = 0.5 - 0.5 * np.cos(np.pi * u)                 # smooth speed change
            out["t"].append(t0 + tl + np.arange(n) * dt)
            out["Vc"].append((v0 + (v1 - v0) * sm) * P["Vpass"][p])
            out["sc"].append(s0 + (s1 - s0) * u)
            out["slot"].append(np.full(n, slot))
            out["valid"].append(np.full(n, val))
            out["pass"].append(np.full(n, p))
            tl += n * dt
        t0 += tl + 60.0 + 30.0 * rng.random()                  # carriage return, lane preparation
    return {k: np.concatenate(v) for k, v in out.items()}


def first_order(x, tau, dt, starts):
    """First-order lag, restarted at every pass start (index list)."""
    a = 1.0 - np.exp(-dt / tau)
    y = np.empty_like(x)
    bounds = list(starts) + [len(x)]
    for i0, i1 in zip(bounds[:-1], bounds[1:]):
        y[i0:i1] = signal.lfilter([a], [1.0, a - 1.0], x[i0:i1], zi=[(1.0 - a) * x[i0]])[0]
    return y


# --------------------------------------------------------------------------- main generator
def generate(case, seed, params):
    if case not in CASES:
        raise SystemExit("unknown case %r; cases: %s" % (case, ", ".join(CASES)))
    C = CASES[case]
    rng = np.random.default_rng(seed)
    P = dict(PROTOCOL_DEFAULTS)
    cp = dict(C["defaults"])
    for k, v in params.items():
        if k in PROTOCOL_DEFAULTS:
            P[k] = v
        else:
            cp[k] = v
    pre = PRESETS[P["soil"]]
    r = float(P["r"] or pre["r"])
    b = float(P["b"] or pre["b"])
    loads = [float(x) for x in (P["loads"] or pre["loads"])]
    V0 = float(P["V"] or pre["V"])
    fs = float(P["fs"])
    dt = 1.0 / fs
    npass = int(P["passes"])
    lab_full = load_toml(os.path.join(HERE, pre["toml"]))
    unc = lab_full["uncertainty"]
    lab = {k: float(lab_full[k]) for k in ("c_kpa", "phi_deg", "K_m", "n", "kc", "kphi")}
    noise = float(P["noise"])

    # ---- pass plan: loads cycled, speeds (rate case alternates two speeds)
    Wpass = [loads[p % len(loads)] for p in range(npass)]
    if case == "rate":
        sp = [float(v) for v in cp["speeds"]]
        Vpass = [sp[p % len(sp)] for p in range(npass)]
    else:
        Vpass = [V0] * npass
    P["Vpass"] = Vpass

    # ---- bin soil vs lab: small offsets within +-bin_offset_sigma lab sigmas (the `none` convention)
    u = rng.uniform(-1, 1, 5) * float(P["bin_offset_sigma"])
    bin_changes = {"k_eq": 1.0 + u[0] * unc["k_eq_rel"], "n": u[1] * unc["n"], "c_kpa": u[2] * unc["c_kpa"],
                   "phi_deg": u[3] * unc["phi_deg"], "K_m": 1.0 + u[4] * unc["K_m"] / lab["K_m"]}
    bin_soil = apply_changes(lab, bin_changes)
    true_soil = dict(bin_soil)
    if case == "mismatch":
        true_soil = apply_changes(bin_soil, cp["changes"])

    # ---- timeline and rig dynamics
    TL = build_timeline(P, rng)
    N = len(TL["t"])
    pidx = TL["pass"]
    starts = np.flatnonzero(np.r_[True, pidx[1:] != pidx[:-1]])
    Vc = TL["Vc"]
    # carriage speed: drive lag + chain/sprocket ripple + slow wander (true values)
    V = first_order(Vc, 0.25, dt, starts)
    x_pass = np.zeros(N)
    for i0, i1 in zip(starts, list(starts[1:]) + [N]):
        x_pass[i0:i1] = np.cumsum(V[i0:i1]) * dt
    ripple = 0.006 * np.sin(2 * np.pi * x_pass / 0.0381 + rng.uniform(0, 6.28)) + ar1(rng, N, np.exp(-dt / 1.0), 0.003)
    V = V * (1.0 + ripple)
    # wheel speed servo: commanded from the measured carriage speed and the slip programme
    wc = V / (r * (1.0 - TL["sc"]))
    w = first_order(wc, 0.10, dt, starts)
    moving = (V > 0.15 * np.array(Vpass)[pidx]) & (w > 1e-3)
    s_true = np.where(moving, 1.0 - V / (r * np.maximum(w, 1e-9)), 0.0)
    dV = np.gradient(V, dt)
    dw = np.gradient(w, dt)
    for i0 in starts[1:]:
        dV[i0 - 1:i0 + 1] = 0.0
        dw[i0 - 1:i0 + 1] = 0.0
    ang = np.zeros(N)
    for i0, i1 in zip(starts, list(starts[1:]) + [N]):
        ang[i0:i1] = np.cumsum(w[i0:i1]) * dt
    dist_cum = np.zeros(N)
    off = 0.0
    for i0, i1 in zip(starts, list(starts[1:]) + [N]):
        dist_cum[i0:i1] = off + x_pass[i0:i1]
        off = dist_cum[i1 - 1]
    total_dist = off

    # vertical load: dead weight + slide friction wander + wheel run-out (once per rev)
    Wd = np.array(Wpass)[pidx]
    W = Wd * (1.0 + ar1(rng, N, np.exp(-dt / 0.5), 0.006) + 0.008 * np.sin(ang + rng.uniform(0, 6.28)))

    # ---- soil per sample (toml units first)
    nS = {k: np.full(N, true_soil[k]) for k in lab}
    # drift along the run
    if case == "drift":
        mode = cp["mode"]
        if mode == "ramp":
            wgt = dist_cum / total_dist
        elif mode == "passes":
            wgt = pidx / max(npass - 1, 1)
        elif mode == "step":
            k = cp.get("at_pass") or npass // 2
            wgt = (pidx >= k).astype(float)
        else:
            raise ValueError(mode)
        for k, v in cp["changes"].items():
            if k == "k_eq":
                nS["kc"] = nS["kc"] * v ** wgt
                nS["kphi"] = nS["kphi"] * v ** wgt
            elif k in ("kc", "kphi", "K_m"):
                nS[k] = nS[k] * v ** wgt
            else:
                nS[k] = nS[k] + v * wgt
    # lane preparation scatter (per pass) and spatial variability along the lane
    lane_k = 1.0 + 0.03 * rng.standard_normal(npass)
    lane_phi = 0.3 * rng.standard_normal(npass)
    fk = np.ones(N)
    ft = np.ones(N)
    for p, (i0, i1) in enumerate(zip(starts, list(starts[1:]) + [N])):
        fk[i0:i1] = lane_k[p] * (1.0 + field_along(rng, x_pass[i0:i1], 0.25, 0.04))
        ft[i0:i1] = 1.0 + field_along(rng, x_pass[i0:i1], 0.25, 0.03)
        nS["phi_deg"][i0:i1] += lane_phi[p]
    if case == "rate":
        vref = np.sqrt(np.prod(cp["speeds"])) if len(cp["speeds"]) == 2 else np.exp(np.mean(np.log(cp["speeds"])))
        fr = 1.0 + float(cp["beta"]) * np.log10(np.array(Vpass)[pidx] / vref)
        fk = fk * fr
        ft = ft * fr
    S = terra.soil_si(nS)
    S["kc"] = S["kc"] * fk
    S["kphi"] = S["kphi"] * fk
    S["c"] = S["c"] * ft
    S["phi"] = np.arctan(np.tan(S["phi"]) * ft)

    # ---- sinkage (steady law) and its lag over travel
    form = C["form"]
    sp = {}
    if form == "vasilev":
        sp = {"H": float(cp["H"])}
    elif form == "lyasko":
        sp = {"m1": float(cp["m1"]), "m2": float(cp["m2"])}
    elif form == "ding":
        sp = {"n1": float(cp["n1"])}
    Zss, Nexp = terra.sinkage_law(W, s_true, r, b, S["kc"], S["kphi"], S["n"], form, **sp)
    lam = pre["lam"]
    Z = np.empty(N)
    dx = V * dt
    alpha = 1.0 - np.exp(-dx / lam)
    for i0, i1 in zip(starts, list(starts[1:]) + [N]):
        z = Zss[i0]
        for i in range(i0, i1):
            z += alpha[i] * (Zss[i] - z)
            Z[i] = z

    # ---- soil forces at the true slip, load and sinkage of every sample
    kw = {}
    dist = "wong"
    if case == "wong_reece":
        dist = "wong_reece"
        kw.update(a1=float(cp["a1"]), a2=float(cp["a2"]))
    if case == "peak_shear":
        kw.update(shear="brittle", Kr=float(cp["Kr"]), Kw=float(cp["Kw_rel"]) * S["K"].reshape(-1, 1))
    if case == "lugged":
        kw.update(h_g=float(cp["h_g"]))
    Dp = np.empty(N)
    T = np.empty(N)
    CH = 20000
    for i0 in range(0, N, CH):
        sl = slice(i0, min(N, i0 + CH))
        kk = dict(kw)
        if "Kw" in kk:
            kk["Kw"] = kk["Kw"][sl]
        f = terra.wheel_forces(s_true[sl], Z[sl], r, b, S["c"][sl], S["phi"][sl], S["K"][sl], Nexp[sl],
                               S["kc"][sl], S["kphi"][sl], dist=dist, **kk)
        Dp[sl] = f["Dp"]
        T[sl] = f["T"]
    if case == "bulldozing":
        Dp = Dp - terra.bulldozing(Z, b, S["c"], S["phi"], pre["gamma"], float(cp["f_b"]))
    # at rest: no traction, no torque (brake holds); soil forces fade in as the wheel starts
    ramp_in = np.clip(w / (0.3 * np.array(Vpass)[pidx] / r), 0, 1)
    Dp *= ramp_in
    T *= ramp_in
    if case == "lugged":
        osc = np.cos(int(cp["n_g"]) * ang)
        Dp = Dp + 0.05 * np.abs(T) / r * osc
        T = T * (1.0 + 0.03 * osc)
        W = W * (1.0 + 0.01 * osc)

    # ---- what the sensors see
    m_w, I_w = pre["m_w"], pre["I_w"]
    Wref = float(np.median(loads))
    Fx = Dp - m_w * dV
    Fz = W.copy()
    if case == "tilt":
        a = np.radians(float(cp["alpha_deg"]))
        Fx, Fz = Fx * np.cos(a) - W * np.sin(a), W * np.cos(a) + Dp * np.sin(a)
    Tm = T + I_w * dw
    if case == "drivetrain_drag":
        Tm = Tm + (float(cp["T0"]) + float(cp["mu_b"]) * W) * (w > 1e-3)

    sos = signal.butter(4, min(20.0, fs / 4.0), fs=fs, output="sos")

    def lp(x):
        y = np.empty_like(x)
        for i0, i1 in zip(starts, list(starts[1:]) + [N]):
            y[i0:i1] = signal.sosfilt(sos, x[i0:i1], zi=signal.sosfilt_zi(sos) * x[i0])[0]
        return y

    def per_pass(sd):
        return np.array([sd * rng.standard_normal() for _ in range(npass)])[pidx]

    tloc = TL["t"] - TL["t"][starts][pidx]
    # load cell (hub): white noise, carriage vibration, residual zero offsets and slow thermal drift
    fvib = 7.5 + 2.0 * rng.random()
    vib = np.sin(2 * np.pi * fvib * TL["t"] + rng.uniform(0, 6.28))
    Fx_m = Fx + noise * (0.008 * Wref * rng.standard_normal(N) + 0.006 * Wref * vib
                         + per_pass(0.003 * Wref) + per_pass(0.00005 * Wref) * tloc)
    Fz_m = Fz + noise * (0.010 * Wref * rng.standard_normal(N) + 0.008 * Wref * vib
                         + per_pass(0.004 * Wref) + per_pass(0.00008 * Wref) * tloc)
    Fx_m, Fz_m = lp(Fx_m), lp(Fz_m)
    Tref = 0.1 * Wref * r
    T_m = lp(Tm + noise * (0.015 * Tref * rng.standard_normal(N) + 0.008 * Tref * np.sin(6 * ang)
                           + per_pass(0.005 * Tref)))
    # sinkage: LVDT on the vertical slide, zeroed with the wheel touching the levelled surface
    Zm = Z.copy()
    if case == "sinkage_gain":
        Zm = Z * float(cp["gain"]) + float(cp["drift_mm"]) * 1e-3 * tloc / max(tloc.max(), 1.0)
    rough = np.zeros(N)
    for i0, i1 in zip(starts, list(starts[1:]) + [N]):
        rough[i0:i1] = field_along(rng, x_pass[i0:i1], 0.15, 0.0007)
    Zm = Zm + noise * (rough + per_pass(0.0006) + lp(0.0003 * rng.standard_normal(N)))
    # speeds: carriage encoder (rack) and wheel encoder, software-filtered
    Vm = V * (1.0 + noise * lp(0.004 * rng.standard_normal(N)))
    wm = w * (1.0 + noise * lp(0.004 * rng.standard_normal(N)))
    slip_m = np.where(moving, 1.0 - Vm / (r * np.maximum(wm, 1e-9)), 0.0)
    dist_m = np.zeros(N)
    off = 0.0
    for i0, i1 in zip(starts, list(starts[1:]) + [N]):
        dist_m[i0:i1] = off + np.cumsum(Vm[i0:i1]) * dt
        off = dist_m[i1 - 1]

    valid = TL["valid"].copy()
    valid[~moving] = 0
    # DAQ glitches: a few single-sample spikes on the load-cell channels, flagged by the DAQ
    ng = 2 * npass + rng.integers(0, 4)
    gi = rng.choice(N, ng, replace=False)
    Fx_m[gi] += rng.choice([-1, 1], ng) * Wref * rng.uniform(0.5, 2.0, ng)
    Fz_m[gi] += rng.choice([-1, 1], ng) * Wref * rng.uniform(0.5, 2.0, ng)
    valid[gi] = 0
    # cycle id per slip sweep / step sequence
    slot = TL["slot"]
    cycle = np.where(slot >= 0, pidx * 2 + slot, -1)
    # dropped samples (USB buffer overruns): a few short bursts
    keep = np.ones(N, bool)
    for _ in range(rng.integers(2, 6)):
        i = rng.integers(0, N - 50)
        keep[i:i + rng.integers(3, 40)] = False

    cols = [("t_s", TL["t"], "%.3f"), ("slip", slip_m, "%.5f"), ("load_n", Fz_m, "%.2f"),
            ("drawbar_pull_n", Fx_m, "%.2f")]
    if P["torque"]:
        cols.append(("torque_nm", T_m, "%.3f"))
    if P["sinkage"]:
        cols.append(("sinkage_m", Zm, "%.5f"))
    cols += [("distance_m", dist_m, "%.4f"), ("speed_mps", Vm, "%.5f")]
    if P["valid_col"]:
        cols.append(("valid", valid, "%d"))
    if P["cycle_col"]:
        cols.append(("cycle", cycle, "%d"))

    info = dict(r=r, b=b, loads=loads, Wpass=Wpass, Vpass=Vpass, lab=lab, bin_soil=bin_soil, true_soil=true_soil,
                case_params=cp, protocol={k: v for k, v in P.items() if k != "Vpass"}, pre=pre, N=int(keep.sum()),
                duration_s=float(TL["t"][-1]), total_dist_m=float(total_dist))
    return cols, keep, info


# --------------------------------------------------------------------------- effect sizes
def effect_sizes(case, info):
    """Noise-free effect at the median load: what the case changes in the measured
    Dp (and T, sinkage) at s = 0.25 and 0.5, relative to the paper's model with the
    LAB soil values (i.e. what the user's model predicts)."""
    r, b = info["r"], info["b"]
    cp = info["case_params"]
    pre = info["pre"]
    W = float(np.median(info["loads"]))
    s = np.array([0.25, 0.5, 0.75])
    lab = terra.soil_si(info["lab"])
    ref = terra.forces_simple(s, W, r, b, lab)
    C = CASES[case]
    sp = {k: cp[k] for k in ("H", "m1", "m2", "n1") if k in cp}

    def model(soil_t, **kw):
        return terra.forces_simple(s, W, r, b, terra.soil_si(soil_t), C["form"], sp, **kw)

    if case == "drift":
        first = model(info["bin_soil"])
        last = model(apply_changes(info["bin_soil"], cp["changes"]))
        out = {"ref": "first vs last soil state", "dp_pct": 100 * (last["Dp"] / first["Dp"] - 1),
               "T_pct": 100 * (last["T"] / first["T"] - 1), "Z_pct": 100 * (last["Z"] / first["Z"] - 1)}
    elif case == "rate":
        sp2 = cp["speeds"]
        vref = np.exp(np.mean(np.log(sp2)))
        res = []
        for v in (min(sp2), max(sp2)):
            fr = 1 + cp["beta"] * np.log10(v / vref)
            d = terra.soil_si(info["bin_soil"])
            d["kc"] *= fr
            d["kphi"] *= fr
            d["c"] *= fr
            d["phi"] = np.arctan(np.tan(d["phi"]) * fr)
            res.append(terra.forces_simple(s, W, r, b, d))
        out = {"ref": "fast vs slow pass", "dp_pct": 100 * (res[1]["Dp"] / res[0]["Dp"] - 1),
               "T_pct": 100 * (res[1]["T"] / res[0]["T"] - 1), "Z_pct": 100 * (res[1]["Z"] / res[0]["Z"] - 1)}
    else:
        soil_t = info["true_soil"]
        kw = {}
        if case == "wong_reece":
            kw = dict(dist="wong_reece", a1=cp["a1"], a2=cp["a2"])
        if case == "peak_shear":
            kw = dict(shear="brittle", Kr=cp["Kr"], Kw=cp["Kw_rel"] * soil_t["K_m"])
        if case == "lugged":
            kw = dict(h_g=cp["h_g"])
        f = model(soil_t, **kw)
        Dp, T, Z = f["Dp"], f["T"], f["Z"]
        if case == "bulldozing":
            Dp = Dp - terra.bulldozing(Z, b, soil_t["c_kpa"] * 1e3, np.radians(soil_t["phi_deg"]), pre["gamma"], cp["f_b"])
        if case == "tilt":
            a = np.radians(cp["alpha_deg"])
            Dp = Dp * np.cos(a) - W * np.sin(a)
        if case == "drivetrain_drag":
            T = T + cp["T0"] + cp["mu_b"] * W
        if case == "sinkage_gain":
            Z = Z * cp["gain"]
        out = {"ref": "vs paper model with lab values", "dp_pct": 100 * (Dp / ref["Dp"] - 1),
               "T_pct": 100 * (T / ref["T"] - 1), "Z_pct": 100 * (Z / ref["Z"] - 1)}
    # the case's own effect: relative to the plain model with the same bin soil
    if case in ("drift", "rate"):
        pure = out
    else:
        base = terra.forces_simple(s, W, r, b, terra.soil_si(info["bin_soil"]))
        pure = {"dp_pct": 100 * (Dp / base["Dp"] - 1), "T_pct": 100 * (T / base["T"] - 1), "Z_pct": 100 * (Z / base["Z"] - 1)}
    res = {"load_n": W, "ref": out["ref"]}
    for k in ("dp_pct", "T_pct", "Z_pct"):
        res["case_" + k + "_s025"] = round(float(pure[k][0]), 1)
        res["case_" + k + "_s05"] = round(float(pure[k][1]), 1)
        res["case_" + k + "_s075"] = round(float(pure[k][2]), 1)
    for k in ("dp_pct", "T_pct", "Z_pct"):
        res[k + "_s025"] = round(float(out[k][0]), 1)
        res[k + "_s05"] = round(float(out[k][1]), 1)
        res[k + "_s075"] = round(float(out[k][2]), 1)
    # the bin-vs-lab offsets alone (the `none` part every case carries)
    bo = terra.forces_simple(s, W, r, b, terra.soil_si(info["bin_soil"]))
    res["bin_offset_dp_pct_s05"] = round(float(100 * (bo["Dp"][1] / ref["Dp"][1] - 1)), 1)
    res["bin_offset_Z_pct"] = round(float(100 * (bo["Z"][1] / ref["Z"][1] - 1)), 1)
    return res


NOTES = {
    "none": "Paper's model (Eq. 10 static sinkage, no slip sinkage, paper stress distribution); bin soil within +-{bos} lab sigma of the lab values.",
    "vasilev": "Slip sinkage Z = Z0 + H s (Eq. 11), measured sinkage follows it (with a short lag over travel).",
    "lyasko": "Slip sinkage Z = (1 + m1 s)/(1 - m2 s) Z0 (Eq. 12).",
    "ding": "Slip sinkage via N = n + n1 s replacing n in Eq. 10 and in the pressure law (Eq. 13).",
    "mismatch": "The bin's soil differs from the lab values by the listed changes (multiplicative: k_eq, kc, kphi, K_m; additive: n, c_kpa, phi_deg), constant over the run.",
    "wong_reece": "Wong-Reece normal stress with maximum at theta_m = (a1 + a2 s) theta1 and a rear region (theta2 = 0); same Eq. 10 sinkage.",
    "drift": "Soil changes along the run (cumulative distance): mode 'passes' = staircase per pass (same lane re-run, compaction), 'ramp' = linear in distance, 'step' = lanes from pass at_pass on prepared from another batch.",
    "tilt": "The hub load cell is pitched by alpha about the axle (mounting error): Fx = Dp cos a - W sin a, Fz = W cos a + Dp sin a. Soil physics is the plain model.",
    "sinkage_gain": "Sinkage sensor (LVDT) calibration gain error and a slow reference drift within each pass; forces follow the plain model.",
    "bulldozing": "Frontal bulldozing of the soil wedge ahead of the sunk wheel (Rankine passive resistance x f_b) subtracts from Dp; radial, so no torque; sinkage plain.",
    "peak_shear": "Soil with a peak shear strength (Wong's hump curve, peak at j = Kw, residual Kr) instead of Janosi; lab c, phi are the peak values.",
    "lugged": "Wheel with grousers of height h_g (sidecar gives the rim radius): shear acts on the grouser-tip cylinder, plus grouser-passing force ripple.",
    "rate": "Rate-dependent soil: strength and pressure-sinkage moduli x (1 + beta log10(V/Vref)); passes alternate between two carriage speeds.",
    "drivetrain_drag": "Torque transducer sits before the wheel bearings and seals: measured torque includes drag T0 + mu_b W; Dp and sinkage plain.",
}


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("case", choices=sorted(CASES))
    ap.add_argument("--seed", type=int, required=True)
    ap.add_argument("--out", required=True)
    ap.add_argument("--outdir", required=True)
    ap.add_argument("--p", action="append", default=[], metavar="key=value")
    a = ap.parse_args(argv)
    params = {}
    for kv in a.p:
        k, _, v = kv.partition("=")
        params[k.strip()] = parse_value(v)
    write_case(a.case, a.seed, a.out, a.outdir, params)


def write_case(case, seed, name, outdir, params):
    os.makedirs(outdir, exist_ok=True)
    cols, keep, info = generate(case, seed, params)
    csv_path = os.path.join(outdir, name + ".csv")
    header = ",".join(c[0] for c in cols)
    arr = np.column_stack([c[1][keep] for c in cols])
    fmt = [c[2] for c in cols]
    np.savetxt(csv_path, arr, fmt=fmt, delimiter=",", header=header, comments="")
    with open(os.path.join(outdir, name + ".json"), "w") as f:
        json.dump({"wheel": {"radius_m": info["r"], "width_m": info["b"]}}, f, indent=1)
    C = CASES[case]
    acceptable = list(C["acceptable"])
    P = info["protocol"]
    notes = NOTES[case].format(bos=P["bin_offset_sigma"])
    if C["family"] == "in" and case != "none" and not P["torque"] and not P["sinkage"]:
        acceptable.append("unexplained")
        notes += " Neither torque nor sinkage logged: only Dp(s, W) is left, judged possibly undecidable, so 'unexplained' is also accepted."
    eff = effect_sizes(case, info)
    abs_out = os.path.abspath(outdir)
    rel = os.path.relpath(abs_out, MAIN) if abs_out.startswith(MAIN + os.sep) else abs_out
    fit_args = [os.path.join(rel, name + ".csv"), "--terrain", os.path.join("benchmarks/foreign7", info["pre"]["toml"])]
    truth = {
        "name": name, "case": case, "family": C["family"], "acceptable_verdicts": acceptable,
        "form": C["form"], "params": {"seed": seed, **params, "case_params": info["case_params"],
                                      "wheel": {"radius_m": info["r"], "width_m": info["b"]},
                                      "loads_per_pass_n": info["Wpass"], "speed_per_pass_mps": info["Vpass"],
                                      "lab_soil": info["lab"], "bin_soil_true": info["bin_soil"],
                                      "true_soil_constant_part": info["true_soil"],
                                      "protocol": P},
        "effect": eff, "fit_args": fit_args, "notes": notes, "generator": "foreign7",
        "n_rows": info["N"], "duration_s": info["duration_s"], "total_distance_m": info["total_dist_m"],
    }
    with open(os.path.join(outdir, name + "_truth.json"), "w") as f:
        json.dump(truth, f, indent=1, default=float)
    return truth


if __name__ == "__main__":
    main()
