#!/usr/bin/env python3
"""foreign3: independent field-run simulator of the instrumented left-rear wheel
on the paper's CLAY, towed-vehicle slip-sweep procedure.

    python gen.py CASE --seed N --out NAME --outdir DIR [--p key=value ...] [--format asc|blf|log]
    python gen.py --list

Writes DIR/NAME.<asc|blf|log> (a CAN log through python-can's writers) and
DIR/NAME_truth.json.  See README.md.
"""
from __future__ import annotations

import argparse
import datetime as _dt
import json
import math
import os
import sys
import time

os.environ.setdefault("TZ", "UTC")
try:
    time.tzset()
except AttributeError:  # pragma: no cover
    pass

import numpy as np
from scipy.interpolate import CubicSpline
from scipy.ndimage import gaussian_filter1d
from scipy.signal import butter, sosfiltfilt

import can
import cantools

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
from terra import (CLAY_TABLE, Physics, Soil, lab_soil, static_sinkage,  # noqa: E402
                   wheel_forces)

# the sensors' DBC files: the project's copies of ../shared/dbc (or FOREIGN3_DBC_DIR)
DBC_DIR = os.environ.get("FOREIGN3_DBC_DIR", os.path.join(os.path.dirname(os.path.dirname(HERE)), "dbc"))
G = 9.81

# --------------------------------------------------------------------------
# cases
# --------------------------------------------------------------------------
IN_LIST = ["none", "slip_sinkage", "terrain_mismatch", "stress_distribution", "terrain_drift"]

CASES: dict[str, dict] = {
    "none": dict(effect="none", verdicts=["none"], defaults={},
                 doc="soil exactly the lab's (plus natural spatial variability about it)"),
    "vasilev": dict(effect="slip_sinkage", verdicts=["slip_sinkage"], defaults={"H": 0.025},
                    doc="Z = Z0 + H s (paper Eq. 11)"),
    "lyasko": dict(effect="slip_sinkage", verdicts=["slip_sinkage"], defaults={"m1": 0.1, "m2": 0.05},
                   doc="Z = (1 + m1 s)/(1 - m2 s) Z0 (paper Eq. 12)"),
    "ding": dict(effect="slip_sinkage", verdicts=["slip_sinkage"], defaults={"n1": 0.35},
                 doc="N = n + n1 s replaces n in Eqs. 2 and 10 (paper Eq. 13)"),
    "terrain_k": dict(effect="terrain_mismatch", verdicts=["terrain_mismatch"], defaults={"factor": 0.75},
                      doc="true kc and kphi = lab x factor"),
    "terrain_n": dict(effect="terrain_mismatch", verdicts=["terrain_mismatch"], defaults={"n": 0.96},
                      doc="true sinkage exponent n (lab 0.85); kc, kphi keep their numbers"),
    "terrain_c": dict(effect="terrain_mismatch", verdicts=["terrain_mismatch"], defaults={"factor": 1.3},
                      doc="true cohesion = lab x factor"),
    "terrain_phi": dict(effect="terrain_mismatch", verdicts=["terrain_mismatch"], defaults={"phi_deg": 15.2},
                        doc="true friction angle in deg (lab 14)"),
    "terrain_K": dict(effect="terrain_mismatch", verdicts=["terrain_mismatch"], defaults={"K": 0.045},
                      doc="true shear deformation modulus in m (lab 0.025)"),
    "wong_reece": dict(effect="stress_distribution", verdicts=["stress_distribution"],
                       defaults={"a1": 0.15, "a2": 0.10},
                       doc="Wong-Reece normal stress, maximum at theta_m = (a1 + a2 s) theta1, "
                           "theta2 = 0, sinkage still from Eq. 10"),
    "drift": dict(effect="terrain_drift", verdicts=["terrain_drift"],
                  defaults={"param": "k", "mode": "linear", "factor": 0.70, "step_at": 0.55,
                            "step_width_m": 0.6},
                  doc="one soil value (param in k|c|phi|n|K) goes from lab to lab x factor along the "
                      "track: 'linear' in distance, or 'step' at fraction step_at of the distance"),
    # ---- causes on no list -------------------------------------------------
    "wft_crosstalk": dict(effect="wft_crosstalk", verdicts=["unexplained"], defaults={"k": 0.03},
                          doc="WFT calibration: Fz_w bridge leaks into Fx_w: Fx_w' = Fx_w + k Fz_w "
                              "(hub Fx gains k W/2 plus a 2/rev ripple)"),
    "encoder_offset": dict(effect="encoder_offset", verdicts=["unexplained"], defaults={"deg": 1.2},
                           doc="WFT angle encoder zero not aligned with the bridge axes: reported "
                               "WheelAngle = true + deg (hub Fx gains W sin(deg))"),
    "torque_drift": dict(effect="torque_drift", verdicts=["unexplained"],
                         defaults={"drift_Nm": 150.0, "tau_s": 60.0, "temp_rise_C": 24.0},
                         doc="thermal zero drift of the My bridge as the hub heats up: "
                             "My' = My + drift_Nm (1 - exp(-t/tau_s)); BridgeTemp rises with it"),
    "shear_hump": dict(effect="shear_hump", verdicts=["unexplained"], defaults={"Kr": 0.85, "Kw": 0.02},
                       doc="clay with a peak-residual shear curve (Wong's hump form, residual ratio Kr, "
                           "peak at j = Kw) instead of Janosi's exponential Eq. 4"),
    "viscous_clay": dict(effect="viscous_clay", verdicts=["unexplained"],
                         defaults={"beta": 0.10, "vref": 0.01},
                         doc="rate-dependent cohesion c (1 + beta log10(1 + v_j/vref)), "
                             "v_j = r omega - V cos(theta) the local slip velocity"),
    "crab_angle": dict(effect="crab_angle", verdicts=["unexplained"], defaults={"deg": 10.0},
                       doc="towed off-line: the vehicle crabs at a slip angle; combined longitudinal+"
                           "lateral shear displacement (Janosi on the resultant), lateral force Fy"),
    "tyre_deflection": dict(effect="tyre_deflection", verdicts=["unexplained"], defaults={"r_roll": 0.452},
                            doc="soft (leaking) tyre: rolling radius r_roll < 0.47 m, so the true slip is "
                                "1 - (1 - s_0.47) 0.47/r_roll; contact geometry unchanged"),
    "mud_buildup": dict(effect="mud_buildup", verdicts=["unexplained"],
                        defaults={"dr": 0.015, "dm": 25.0},
                        doc="sticky clay builds up on the tyre linearly with distance: radius +dr "
                            "(rolling and contact), mass +dm kg at the rim (inertia not compensated, "
                            "its weight not zeroed)"),
    "rope_surge": dict(effect="rope_surge", verdicts=["unexplained", "none"],
                       defaults={"amp": 0.25, "freq": 0.6},
                       doc="elastic tow rope: episodes of speed surge amp (m/s) at freq (Hz); the soil "
                           "is the lab's (quasi-static), only the dynamics/latency handling is stressed"),
}

CASE_ORDER = list(CASES)


def parse_value(v: str):
    try:
        return json.loads(v)
    except json.JSONDecodeError:
        return v


# --------------------------------------------------------------------------
# helpers
# --------------------------------------------------------------------------
def smoothstep(x):
    x = np.clip(x, 0.0, 1.0)
    return x * x * (3.0 - 2.0 * x)


def raised_cos_ramp(t, t0, t1):
    """0 before t0, 1 after t1, raised cosine between."""
    x = np.clip((t - t0) / (t1 - t0), 0.0, 1.0)
    return 0.5 - 0.5 * np.cos(np.pi * x)


def random_field(rng, x, corr_len, n_modes=64):
    """Unit-variance Gaussian random field along x with Gaussian correlation
    exp(-d^2 / (2 corr_len^2)) (random Fourier modes)."""
    k = rng.normal(0.0, 1.0 / corr_len, n_modes)
    ph = rng.uniform(0, 2 * np.pi, n_modes)
    g = np.zeros_like(x)
    for ki, pi in zip(k, ph):
        g += np.cos(ki * x + pi)
    return g * math.sqrt(2.0 / n_modes)


def band_noise(rng, n, fs, lo, hi, sigma):
    w = rng.normal(0.0, 1.0, n + 2000)
    if lo <= 0:
        sos = butter(2, hi, btype="low", fs=fs, output="sos")
    else:
        sos = butter(2, [lo, hi], btype="band", fs=fs, output="sos")
    y = sosfiltfilt(sos, w)[1000:1000 + n]
    sd = y.std()
    return y * (sigma / sd if sd > 0 else 0.0)


# --------------------------------------------------------------------------
# physics per case
# --------------------------------------------------------------------------
def case_physics(case: str, p: dict, lab: Soil):
    """(soil, Physics) of the true ground for a case (before variability/drift)."""
    soil, ph = lab, Physics()
    if case == "vasilev":
        ph = Physics(sinkage="vasilev", H=p["H"])
    elif case == "lyasko":
        ph = Physics(sinkage="lyasko", m1=p["m1"], m2=p["m2"])
    elif case == "ding":
        ph = Physics(sinkage="ding", n1=p["n1"])
    elif case == "terrain_k":
        soil = lab.scaled(k=p["factor"])
    elif case == "terrain_n":
        soil = Soil(**{**lab.__dict__, "n": p["n"]})
    elif case == "terrain_c":
        soil = lab.scaled(c=p["factor"])
    elif case == "terrain_phi":
        soil = Soil(**{**lab.__dict__, "phi": math.radians(p["phi_deg"])})
    elif case == "terrain_K":
        soil = Soil(**{**lab.__dict__, "K": p["K"]})
    elif case == "wong_reece":
        ph = Physics(stress="wong_reece", a1=p["a1"], a2=p["a2"])
    elif case == "shear_hump":
        ph = Physics(shear="hump", Kr=p["Kr"], Kw=p["Kw"])
    elif case == "viscous_clay":
        ph = Physics(visc_beta=p["beta"], visc_vref=p["vref"])
    elif case == "crab_angle":
        ph = Physics(crab=math.radians(p["deg"]))
    return soil, ph


def drift_soil(soil: Soil, param: str, f: float) -> Soil:
    if f == 1.0:
        return soil
    if param == "k":
        return soil.scaled(k=f)
    if param == "c":
        return soil.scaled(c=f)
    if param == "phi":
        return Soil(**{**soil.__dict__, "phi": soil.phi * f})
    if param == "n":
        return Soil(**{**soil.__dict__, "n": soil.n * f})
    if param == "K":
        return Soil(**{**soil.__dict__, "K": soil.K * f})
    raise ValueError(f"drift param {param}")


def model_description(case, p, soil, ph):
    d = {"base": "Wong rigid wheel, paper Eqs. 1-10 with corrected Eqs. 2-3, theta2 = 0, "
                 "Janosi shear (Eq. 4), quad integration",
         "sinkage": ph.sinkage, "stress": ph.stress, "shear": ph.shear,
         "true_soil_paper_units": soil.to_table()}
    if ph.sinkage == "vasilev":
        d["H"] = ph.H
    if ph.sinkage == "lyasko":
        d.update(m1=ph.m1, m2=ph.m2)
    if ph.sinkage == "ding":
        d["n1"] = ph.n1
    if ph.stress == "wong_reece":
        d.update(a1=ph.a1, a2=ph.a2)
    if ph.shear == "hump":
        d.update(Kr=ph.Kr, Kw=ph.Kw)
    if ph.visc_beta:
        d.update(visc_beta=ph.visc_beta, visc_vref=ph.visc_vref)
    if ph.crab:
        d["crab_deg"] = math.degrees(ph.crab)
    if case == "drift":
        d["drift"] = {k: p[k] for k in ("param", "mode", "factor", "step_at", "step_width_m")}
    if case in ("wft_crosstalk", "encoder_offset", "torque_drift", "tyre_deflection",
                "mud_buildup", "rope_surge"):
        d["extra"] = {case: p}
    return d


# --------------------------------------------------------------------------
# effect sizes (what the wheel's Dp / T at a measured slip look like vs the lab)
# --------------------------------------------------------------------------
def apparent(case, p, s_meas, W, V, lab, r, b, soil_true, ph_true):
    """Apparent (Dp, T) at measured slip s_meas (slip computed with r) that a
    pipeline sees in steady state (end of run for time-dependent causes)."""
    if case == "drift":
        soil_end = drift_soil(lab, p["param"], p["factor"])
        o = wheel_forces(s_meas, W, soil_end, r, b, Physics(), V, with_w7=False)
        return o["Dp"], o["T"]
    if case == "tyre_deflection":
        s_true = 1 - (1 - s_meas) * r / p["r_roll"]
        o = wheel_forces(s_true, W, lab, r, b, Physics(), V, with_w7=False)
        return o["Dp"], o["T"]
    if case == "mud_buildup":
        re = r + p["dr"]
        s_true = 1 - (1 - s_meas) * r / re
        o = wheel_forces(s_true, W, lab, re, b, Physics(), V, with_w7=False)
        return o["Dp"], o["T"]
    o = wheel_forces(s_meas, W, soil_true, r, b, ph_true, V, with_w7=False)
    dp, T = o["Dp"], o["T"]
    if case == "wft_crosstalk":
        dp += p["k"] * W / 2.0
    elif case == "encoder_offset":
        d = math.radians(p["deg"])
        dp = dp * math.cos(d) + W * math.sin(d)
    elif case == "torque_drift":
        T += p["drift_Nm"]
    return dp, T


def effect_sizes(case, p, W, V, lab, r, b, soil_true, ph_true):
    grid = [0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.85]
    rows = []
    for s in grid:
        o = wheel_forces(s, W, lab, r, b, Physics(), V, with_w7=False)
        dp_a, T_a = apparent(case, p, s, W, V, lab, r, b, soil_true, ph_true)
        rows.append((s, o["Dp"], o["T"], o["H"], dp_a, T_a))
    s5 = [x for x in rows if x[0] == 0.5][0]
    d_dp = s5[4] - s5[1]
    out = {
        "effect_size_at_s0.5": d_dp / abs(s5[1]),
        "effect_dDp_N_at_s0.5": d_dp,
        "effect_dT_Nm_at_s0.5": s5[5] - s5[2],
        "effect_dDp_rel_to_gross_thrust_at_s0.5": d_dp / s5[3],
        "lab_Dp_N_at_s0.5": s5[1], "lab_T_Nm_at_s0.5": s5[2], "lab_gross_thrust_N_at_s0.5": s5[3],
        "effect_max_abs_dDp_N_s0.1_0.85": max(abs(x[4] - x[1]) for x in rows),
        "effect_max_abs_dT_Nm_s0.1_0.85": max(abs(x[5] - x[2]) for x in rows),
        "effect_curve": [{"s": x[0], "Dp_lab": round(x[1], 2), "T_lab": round(x[2], 2),
                          "Dp_apparent": round(x[4], 2), "T_apparent": round(x[5], 2)} for x in rows],
        "effect_reference": {"W_N": W, "V_mps": V},
    }
    return out


# --------------------------------------------------------------------------
# procedure
# --------------------------------------------------------------------------
def slip_program(rng, t, t0, t1, s_rest=0.10):
    """Driver's commanded slip (w.r.t. r = 0.47 m as on the dash display):
    alternating held-plateau staircases and slow ramps."""
    levels = [0.08, 0.15, 0.25, 0.35, 0.5, 0.65, 0.8]
    knots_t, knots_s = [0.0, t0], [s_rest, s_rest]
    tc, sc = t0, s_rest
    plan = ["stairs_up", "ramp_down", "ramp_up", "stairs_down"]
    i = 0
    segments = []
    while tc < t1:
        mod = plan[i] if i < len(plan) else rng.choice(["stairs_up", "stairs_down", "ramp_up",
                                                         "ramp_down", "stairs_mix"])
        i += 1
        if mod.startswith("stairs"):
            k = int(rng.integers(4, 7))
            lv = sorted(rng.choice(levels, size=k, replace=False))
            if mod == "stairs_down":
                lv = lv[::-1]
            elif mod == "stairs_mix":
                rng.shuffle(lv)
            for L in lv:
                L = float(np.clip(L + rng.normal(0, 0.015), 0.06, 0.84))
                tr = float(rng.uniform(0.8, 1.3))
                hold = float(rng.uniform(3.0, 5.0))
                knots_t += [tc + tr, tc + tr + hold]
                knots_s += [L, L]
                tc += tr + hold
                sc = L
            segments.append(mod)
        else:
            target = float(rng.uniform(0.80, 0.85)) if mod == "ramp_up" else float(rng.uniform(0.05, 0.08))
            if abs(target - sc) < 0.2:
                target = 0.06 if sc > 0.45 else 0.83
            rate = float(rng.uniform(0.025, 0.045))
            dur = abs(target - sc) / rate
            hold = float(rng.uniform(1.0, 2.5))
            knots_t += [tc + dur, tc + dur + hold]
            knots_s += [target, target]
            tc += dur + hold
            sc = target
            segments.append(mod)
    kt = np.array(knots_t)
    ks = np.array(knots_s)
    keep = kt < t1
    kt = np.concatenate([kt[keep], [t1, t1 + 1.0, t[-1] + 1.0]])
    s_end = np.interp(t1, np.array(knots_t), np.array(knots_s))
    ks = np.concatenate([ks[keep], [s_end, s_rest, s_rest]])
    s = np.interp(t, kt, ks)
    return s, segments


# --------------------------------------------------------------------------
# main simulation
# --------------------------------------------------------------------------
def simulate(case: str, seed: int, overrides: dict, fmt: str, outdir: str, name: str) -> dict:
    wall0 = time.time()
    if case not in CASES:
        raise SystemExit(f"unknown case {case}; see --list")
    spec = CASES[case]
    p = dict(spec["defaults"])
    ss = np.random.SeedSequence(seed)
    r_setup, r_proc, r_soil, r_noise, r_bus, r_gnss = [np.random.default_rng(x) for x in ss.spawn(6)]

    setup = {
        "duration_s": float(r_setup.uniform(140.0, 185.0)),
        "W0_N": float(r_setup.uniform(10800.0, 11200.0)),       # 8 kN static + 3 kN added
        "V0_mps": float(r_setup.uniform(1.4, 2.3)),
        "gnss_latency_s": float(r_setup.uniform(0.02, 0.20)),
        "soil_sigma_k": 0.03, "soil_sigma_c": 0.03, "soil_sigma_phi_deg": 0.25,
        "soil_corr_len_m": float(r_setup.uniform(2.0, 5.0)),
        "r": 0.47, "b": 0.32,
        "m_w": 80.0, "I_w": 11.5,
        "front_load_N": 8800.0, "vehicle_mass_kg": 4200.0,
        "hitch_height_m": 0.45, "wheelbase_m": 3.3,
        "front_skid": float(r_setup.uniform(-0.04, -0.02)),
        "host_clock_error_s": float(r_setup.uniform(-4.0, 4.0)),
        "wft_ppm": float(r_setup.uniform(-40, 40)), "wss_ppm": float(r_setup.uniform(-40, 40)),
        "wft_loss_prob": 1e-4, "can1_loss_prob": 5e-5,
        "wft_burst": bool(r_setup.uniform() < 0.5),
        "n_teeth": 48,
        "start_unix": 1418256000.0 + float(r_setup.uniform(1.0, 8.0)) * 3600.0,   # 2014-12-11 UTC
        "bridge_temp0_C": float(r_setup.uniform(4.0, 12.0)),
        "bridge_temp_rise_C": float(r_setup.uniform(2.0, 5.0)),
    }
    for k, v in overrides.items():
        if k in setup:
            setup[k] = v
        elif k in p:
            p[k] = v
        else:
            raise SystemExit(f"unknown parameter {k!r} for case {case}")
    if case == "torque_drift":
        setup["bridge_temp_rise_C"] = p["temp_rise_C"]

    D = float(setup["duration_s"])
    r, b = float(setup["r"]), float(setup["b"])
    W0 = float(setup["W0_N"])
    m_w, I_w = float(setup["m_w"]), float(setup["I_w"])
    lab = lab_soil()
    soil_case, ph = case_physics(case, p, lab)

    # ---------------- kinematics on a 1 ms grid ----------------
    dt = 1e-3
    t = np.arange(0.0, D + dt / 2, dt)
    n = t.size
    t_go0, t_go1 = 2.5, 7.5             # tractor pull-off
    t_st0, t_st1 = D - 7.0, D - 2.5     # tractor stops
    env = raised_cos_ramp(t, t_go0, t_go1) * (1.0 - raised_cos_ramp(t, t_st0, t_st1))
    V0 = float(setup["V0_mps"])
    vslow = np.zeros(n)
    for _ in range(3):
        A = r_proc.uniform(0.06, 0.14)
        P = r_proc.uniform(20.0, 80.0)
        vslow += A * np.sin(2 * np.pi * t / P + r_proc.uniform(0, 2 * np.pi))
    rope_f = r_proc.uniform(0.5, 0.9)
    vrope = 0.02 * np.sin(2 * np.pi * rope_f * t + r_proc.uniform(0, 2 * np.pi))
    if case == "rope_surge":
        # surge episodes of 5-10 s covering about half of the run
        m_env = np.zeros(n)
        tt = t_go1 + 2.0
        while tt < t_st0 - 5:
            L = r_proc.uniform(5.0, 10.0)
            m_env += raised_cos_ramp(t, tt, tt + 1.5) * (1 - raised_cos_ramp(t, tt + L - 1.5, tt + L))
            tt += L + r_proc.uniform(4.0, 12.0)
        vrope = vrope + p["amp"] * m_env * np.sin(2 * np.pi * p["freq"] * t + r_proc.uniform(0, 6.28))
    V = env * np.clip(V0 + vslow + vrope, 0.6, 3.0)
    dVdt = np.gradient(V, dt)

    s_prog, segments = slip_program(r_proc, t, t_go1 + 1.0, t_st0 - 1.0)
    s_prog = np.clip(s_prog, 0.05, 0.86)
    s_cmd = gaussian_filter1d(s_prog, 150.0, mode="nearest")
    jit = gaussian_filter1d(r_proc.normal(0, 1, n), 400.0, mode="wrap")
    jit *= 0.006 / max(jit.std(), 1e-12)
    s_cmd = np.clip(s_cmd + jit * smoothstep((s_cmd - 0.05) / 0.03), 0.05, 0.86)
    omega = V / (r * (1.0 - s_cmd))
    x = np.concatenate([[0.0], np.cumsum(0.5 * (V[1:] + V[:-1]) * dt)])
    x_end = float(x[-1])

    # rolling / contact radius and extra rim mass
    if case == "tyre_deflection":
        r_roll = np.full(n, float(p["r_roll"]))
        r_cont = np.full(n, r)
        m_mud = np.zeros(n)
    elif case == "mud_buildup":
        g = x / x_end
        r_roll = r + p["dr"] * g
        r_cont = r_roll.copy()
        m_mud = p["dm"] * g
    else:
        r_roll = np.full(n, r)
        r_cont = np.full(n, r)
        m_mud = np.zeros(n)
    s_true = 1.0 - (1.0 - s_cmd) * r / r_roll
    I_tot = I_w + m_mud * r_cont ** 2
    dLdt = np.gradient(I_tot * omega, dt)          # d(I omega)/dt
    domegadt = np.gradient(omega, dt)
    angle = np.concatenate([[0.0], np.cumsum(0.5 * (omega[1:] + omega[:-1]) * dt)])
    angle0 = float(r_proc.uniform(0, 2 * np.pi))

    # ---------------- soil along the track ----------------
    Lc = float(setup["soil_corr_len_m"])
    fk = random_field(r_soil, x, Lc)
    fc = random_field(r_soil, x, Lc)
    fp = random_field(r_soil, x, Lc)
    sk, sc_, sp = setup["soil_sigma_k"], setup["soil_sigma_c"], setup["soil_sigma_phi_deg"]
    mult_k = np.exp(sk * fk - 0.5 * sk * sk)
    mult_c = np.exp(sc_ * fc - 0.5 * sc_ * sc_)
    add_phi = np.radians(sp) * fp
    if case == "drift":
        if p["mode"] == "linear":
            drift_f = 1.0 + (p["factor"] - 1.0) * (x / x_end)
        elif p["mode"] == "step":
            xs = p["step_at"] * x_end
            drift_f = 1.0 + (p["factor"] - 1.0) * 0.5 * (1 + np.tanh((x - xs) / (0.5 * p["step_width_m"])))
        else:
            raise SystemExit("drift mode must be linear or step")
    else:
        drift_f = np.ones(n)

    # tow force -> load transfer (rope at hitch height pulls the front)
    tbl_s = np.linspace(0.0, 0.9, 31)
    tbl_dp = np.array([wheel_forces(max(si, 0.0), W0, soil_case, r, b, ph, V0, with_w7=False)["Dp"]
                       for si in tbl_s])
    Rc_front = wheel_forces(0.0, setup["front_load_N"], lab, r, b, Physics(), V0, with_w7=False)["Rc"]
    dp_rear = np.interp(np.clip(s_true, 0.0, 0.9), tbl_s, tbl_dp)
    F_rope = (smoothstep(x / 0.4) * smoothstep(V / 0.1) * (2.0 * Rc_front - 2.0 * dp_rear)
              + setup["vehicle_mass_kg"] * dVdt)
    dW_tow = -setup["hitch_height_m"] * F_rope / (2.0 * setup["wheelbase_m"])
    w_slow = gaussian_filter1d(r_noise.normal(0, 1, n), 3000.0, mode="wrap")
    w_slow *= 80.0 / max(w_slow.std(), 1e-12)
    W_soil = W0 + dW_tow + w_slow

    # ---------------- soil-wheel model at 50 Hz ----------------
    i50 = np.arange(0, n, 20)
    t50 = t[i50]
    Dp50 = np.zeros(i50.size)
    T50 = np.zeros(i50.size)
    Fy50 = np.zeros(i50.size)
    Z50 = np.zeros(i50.size)
    lab_d = lab.__dict__
    base_d = soil_case.__dict__
    for j, i in enumerate(i50):
        soil = Soil(c=base_d["c"] * mult_c[i], phi=base_d["phi"] + add_phi[i], K=base_d["K"],
                    n=base_d["n"], kc=base_d["kc"] * mult_k[i], kphi=base_d["kphi"] * mult_k[i])
        if case == "drift" and drift_f[i] != 1.0:
            soil = drift_soil(soil, p["param"], float(drift_f[i]))
        if V[i] < 0.01:
            Z50[j] = static_sinkage(W_soil[i], soil, float(r_cont[i]), b)
            continue
        o = wheel_forces(float(max(s_true[i], 0.0)), float(W_soil[i]), soil, float(r_cont[i]), b, ph,
                         float(V[i]), with_w7=False)
        Dp50[j], T50[j], Fy50[j], Z50[j] = o["Dp"], o["T"], o["Fy"], o["Z"]
    del lab_d
    # start-up (soil not yet sheared over the contact length) and stop transients
    wgt = smoothstep(x / 0.4) * smoothstep(V / 0.1)
    wgt50 = wgt[i50]
    Dp50 *= wgt50
    T50 *= wgt50
    Fy50 *= wgt50

    # ---------------- WFT samples (500 Hz, own clock) ----------------
    ppm = setup["wft_ppm"] * 1e-6
    tw0 = float(r_bus.uniform(0.0, 0.002))
    kmax = int((D - 0.01 - tw0) / (0.002 * (1 + ppm)))
    tk = tw0 + np.arange(kmax) * 0.002 * (1 + ppm)
    nk = tk.size
    Dp_k = CubicSpline(t50, Dp50)(tk)
    T_k = CubicSpline(t50, T50)(tk)
    Fy_k = CubicSpline(t50, Fy50)(tk)
    Z_k = np.interp(tk, t50, Z50)
    interp = lambda arr: np.interp(tk, t, arr)  # noqa: E731
    a_k = interp(angle) + angle0
    om_k = interp(omega)
    V_k = interp(V)
    W_k = interp(W_soil)
    fs = 500.0
    # soil texture (clods, roots) and vehicle heave, band-limited
    tex_fx = band_noise(r_noise, nk, fs, 2.0, 15.0, 30.0)
    tex_my = band_noise(r_noise, nk, fs, 2.0, 15.0, 10.0)
    heave = band_noise(r_noise, nk, fs, 1.3, 2.6, 0.012 * W0)
    tex_fz = band_noise(r_noise, nk, fs, 2.0, 20.0, 60.0)
    mov = smoothstep(V_k / 0.3)
    # tread lugs: 20 lugs per revolution
    n_lug = 20
    lug_ph = float(r_noise.uniform(0, 2 * np.pi))
    lug = np.sin(n_lug * a_k + lug_ph)
    Fx_hub = (Dp_k - (m_w + interp(m_mud)) * interp(dVdt)
              + mov * (tex_fx + 0.02 * 3300.0 * lug))
    Fz_hub = W_k - interp(m_mud) * G + mov * (heave + tex_fz + 0.008 * W0 * lug)
    My_hub = T_k + I_w * interp(domegadt) + (interp(dLdt) - I_w * interp(domegadt)) \
        + mov * (tex_my + 0.01 * 1600.0 * lug)
    fy_slow = gaussian_filter1d(r_noise.normal(0, 1, nk), 1500.0, mode="wrap")
    fy_slow *= 60.0 / max(fy_slow.std(), 1e-12)
    Fy_hub = Fy_k + mov * fy_slow
    Mx_hub = -Fy_hub * (r - Z_k / 2) + mov * band_noise(r_noise, nk, fs, 0.0, 1.0, 20.0)
    Mz_hub = mov * band_noise(r_noise, nk, fs, 0.0, 0.5, 15.0)
    if case == "torque_drift":
        My_hub = My_hub + p["drift_Nm"] * (1.0 - np.exp(-tk / p["tau_s"]))
    # into the rotating frame: Fx = Fx_w cos a + Fz_w sin a, Fz = -Fx_w sin a + Fz_w cos a
    ca, sa = np.cos(a_k), np.sin(a_k)
    Fx_w = Fx_hub * ca - Fz_hub * sa
    Fz_w = Fx_hub * sa + Fz_hub * ca
    Mx_w = Mx_hub * ca - Mz_hub * sa
    Mz_w = Mx_hub * sa + Mz_hub * ca
    # bridge calibration residual (angle dependent gain), zero offsets, white noise
    g1, g2 = r_noise.uniform(0, 2 * np.pi, 2)
    Fx_w = Fx_w * (1 + 0.0025 * np.sin(a_k + g1)) + r_noise.normal(0, 10.0) + r_noise.normal(0, 8.0, nk)
    Fz_w = Fz_w * (1 + 0.0025 * np.sin(a_k + g2)) + r_noise.normal(0, 10.0) + r_noise.normal(0, 15.0, nk)
    Fy_w = Fy_hub + r_noise.normal(0, 5.0) + r_noise.normal(0, 8.0, nk)
    Mx_w = Mx_w + r_noise.normal(0, 1.5, nk)
    Mz_w = Mz_w + r_noise.normal(0, 1.5, nk)
    My_w = My_hub + r_noise.normal(0, 2.0) + r_noise.normal(0, 1.2, nk)
    if case == "wft_crosstalk":
        Fx_w = Fx_w + p["k"] * Fz_w
    ang_rep = a_k + (math.radians(p["deg"]) if case == "encoder_offset" else 0.0)
    ang_deg = np.degrees(ang_rep) % 360.0
    ang_raw = np.round(ang_deg / (360.0 / 65536)).astype(np.int64) % 65536

    # ---------------- CAN frames ----------------
    dbw = cantools.database.load_file(os.path.join(DBC_DIR, "wft.dbc"), strict=True)
    dbs = cantools.database.load_file(os.path.join(DBC_DIR, "wheel_speed.dbc"), strict=True)
    dbg = cantools.database.load_file(os.path.join(DBC_DIR, "gps_rt_speedbox.dbc"), strict=True)
    mF, mM, mA, mD = (dbw.get_message_by_name(x) for x in
                      ("WFT_RL_Force", "WFT_RL_Moment", "WFT_RL_Angle", "WFT_RL_Diag"))
    mW, mS = dbs.get_message_by_name("WSS_WheelSpeeds"), dbs.get_message_by_name("WSS_Status")
    mGT, mGS, mIV, mGST = (dbg.get_message_by_name(x) for x in
                           ("RT_SB_GPS_Time", "RT_SB_GPS_Speed", "RT_SB_INS_Vel_Body_Axes",
                            "RT_SB_GPS_Status"))

    def q(v, scale, lo, hi):
        raw = np.round(np.asarray(v, float) / scale)
        over = (raw * scale < lo) | (raw * scale > hi)
        return np.clip(raw * scale, lo, hi), over

    fxq, o1 = q(Fx_w, 0.5, -16384, 16383.5)
    fyq, o2 = q(Fy_w, 0.5, -16384, 16383.5)
    fzq, o3 = q(Fz_w, 1.0, -32768, 32767)
    mxq, o4 = q(Mx_w, 0.25, -8192, 8191.75)
    myq, o5 = q(My_w, 0.25, -8192, 8191.75)
    mzq, o6 = q(Mz_w, 0.25, -8192, 8191.75)
    status = np.where(o1 | o2 | o3 | o4 | o5 | o6, 1, 0)
    n_overload = int(status.sum())
    counter = np.arange(nk) % 256

    can0 = []   # (t_queue, prio, arb_id, ext, data)
    for k in range(nk):
        tq = tk[k] + 0.0002
        st = int(status[k])
        c = int(counter[k])
        can0.append((tq, 0, 0x120, False, mF.encode(
            {"Fx_w": float(fxq[k]), "Fy_w": float(fyq[k]), "Fz_w": float(fzq[k]),
             "Counter": c, "Status": st}, strict=True)))
        can0.append((tq, 1, 0x121, False, mM.encode(
            {"Mx_w": float(mxq[k]), "My": float(myq[k]), "Mz_w": float(mzq[k]),
             "Counter": c, "Status": st}, strict=True)))
        can0.append((tq, 2, 0x122, False, mA.encode(
            {"WheelAngle": float(ang_raw[k]) * (360.0 / 65536), "Counter": c, "Status": st},
            strict=True)))
    # diag 1 Hz per mux value
    serial = int(r_setup.integers(100000, 999999))
    calid = int(r_setup.integers(1000, 9999))
    temp_tau = p["tau_s"] if case == "torque_drift" else 80.0
    for kd in range(int(D)):
        for mux, off in ((0, 0.1), (1, 0.433), (2, 0.766)):
            td = (kd + off) * (1 + ppm)
            if td >= D - 0.01:
                continue
            if mux == 0:
                temp = setup["bridge_temp0_C"] + setup["bridge_temp_rise_C"] * (1 - math.exp(-td / temp_tau))
                sig = {"DiagMux": 0, "BridgeTemp": round(temp + r_noise.normal(0, 0.03), 2),
                       "SupplyVoltage": round(12.0 + r_noise.normal(0, 0.015), 3)}
            elif mux == 1:
                sig = {"DiagMux": 1, "SerialNumber": serial}
            else:
                sig = {"DiagMux": 2, "FirmwareMajor": 3, "FirmwareMinor": 2, "CalibrationId": calid}
            can0.append((td, 3, 0x123, False, mD.encode(sig, strict=True)))

    # ---------------- wheel speed module (100 Hz, own clock) ----------------
    wppm = setup["wss_ppm"] * 1e-6
    NT = int(setup["n_teeth"])
    pitch = 2 * np.pi / NT
    ts0 = float(r_bus.uniform(0.0, 0.01))
    tj = ts0 + np.arange(int((D - 0.02 - ts0) / (0.01 * (1 + wppm)))) * 0.01 * (1 + wppm)
    omega_front = V / (r * (1.0 - setup["front_skid"]))
    wheel_ang = {"RL": angle, "RR": angle, "FL": None, "FR": None}
    ang_front = np.concatenate([[0.0], np.cumsum(0.5 * (omega_front[1:] + omega_front[:-1]) * dt)])
    wheel_ang["FL"] = ang_front
    wheel_ang["FR"] = ang_front
    rpm = {}
    for wname, ph_ in wheel_ang.items():
        tooth_err = r_bus.normal(0.0, 0.002 * pitch, NT)       # pitch errors of the tone wheel
        ph0 = float(r_bus.uniform(0, pitch))
        phi_w = ph_ + ph0 + 1e-9 * t                            # strictly increasing
        m_max = int(phi_w[-1] / pitch)
        edges_ang = np.arange(1, m_max + 1) * pitch + tooth_err[np.arange(1, m_max + 1) % NT]
        edges_ang = np.sort(edges_ang)
        et = np.interp(edges_ang, phi_w, t)
        et = np.round(et * 1e6) / 1e6                              # 1 us timer
        il = np.searchsorted(et, tj, side="right") - 1
        iff = np.searchsorted(et, tj - 0.010, side="right")
        w = np.zeros(tj.size)
        ok = il >= 1
        nwin = il - iff
        use_win = ok & (nwin >= 1) & (iff >= 0)
        a_i = np.where(use_win, iff, np.maximum(il - 1, 0))
        num = np.where(use_win, nwin, 1)
        dtt = et[np.clip(il, 0, None)] - et[np.clip(a_i, 0, None)]
        valid = ok & (dtt > 0) & (tj - et[np.clip(il, 0, None)] < 0.25)
        w[valid] = num[valid] * pitch / dtt[valid]
        rpm[wname] = np.clip(np.round(w * 60 / (2 * np.pi) / 0.01) * 0.01, 0, 655.35)
    can1 = []
    for j in range(tj.size):
        can1.append((tj[j] + 0.0003, 1, 0x300, False, mW.encode(
            {"WheelSpeed_FL": float(rpm["FL"][j]), "WheelSpeed_FR": float(rpm["FR"][j]),
             "WheelSpeed_RL": float(rpm["RL"][j]), "WheelSpeed_RR": float(rpm["RR"][j])}, strict=True)))
        if j % 10 == 5:
            can1.append((tj[j] + 0.0006, 2, 0x301, False, mS.encode(
                {"RollingCounter": (j // 10) % 16, "SensorFault_FL": 0, "SensorFault_FR": 0,
                 "SensorFault_RL": 0, "SensorFault_RR": 0}, strict=True)))

    # ---------------- GNSS / INS (20 Hz, GPS time grid, latency) ----------------
    host0 = round(float(setup["start_unix"]), 6)
    gps_minus_unix = -315964800.0 + 16.0            # GPS-UTC = 16 s in Dec 2014
    # host clock = true UTC + host_clock_error; GPS time = true UTC + gps_minus_unix
    gps0 = host0 - setup["host_clock_error_s"] + gps_minus_unix   # GPS time at host t = 0
    L = float(setup["gnss_latency_s"])
    e0 = math.ceil(gps0 / 0.05)
    ep_gps = np.arange(e0, int((gps0 + D - L - 0.05) / 0.05)) * 0.05
    ep_t = ep_gps - gps0                               # host-relative fix times
    crab = math.radians(p["deg"]) if case == "crab_angle" else 0.0
    yaw_small = np.radians(gaussian_filter1d(r_gnss.normal(0, 1, n), 2000, mode="wrap"))
    yaw_small *= math.radians(0.4) / max(yaw_small.std(), 1e-12)
    Vx_e = np.interp(ep_t, t, V)
    vside_e = Vx_e * np.tan(crab + np.interp(ep_t, t, yaw_small))
    vz_e = gaussian_filter1d(r_gnss.normal(0, 0.03, ep_t.size), 3, mode="nearest")
    cor = gaussian_filter1d(r_gnss.normal(0, 1, ep_t.size), 20, mode="wrap")
    cor *= 0.008 / max(cor.std(), 1e-12)
    gps2d = np.hypot(Vx_e, vside_e) + cor + r_gnss.normal(0, 0.015, ep_t.size)
    gps2d = np.abs(gps2d)
    gps3d = np.hypot(gps2d, vz_e)
    # INS velocity bias: first-order Gauss-Markov, sd 5 mm/s, tau 30 s
    ins_b = np.zeros(ep_t.size)
    phi_gm = math.exp(-0.05 / 30.0)
    wn = r_gnss.normal(0, 0.005 * math.sqrt(1 - phi_gm ** 2), ep_t.size)
    ins_b[0] = r_gnss.normal(0, 0.005)
    for e in range(1, ep_t.size):
        ins_b[e] = phi_gm * ins_b[e - 1] + wn[e]
    insf = Vx_e + ins_b + r_gnss.normal(0, 0.008, ep_t.size)
    inss = vside_e + r_gnss.normal(0, 0.008, ep_t.size)
    week = int(ep_gps[0] // 604800)
    lat_j = L + np.abs(r_gnss.normal(0, 0.0015, ep_t.size))
    for e in range(ep_t.size):
        tq = ep_t[e] + lat_j[e]
        tow_ms = int(round(ep_gps[e] * 1000)) - week * 604800000
        if tow_ms >= 604800000:
            continue
        can1.append((tq, 0, 0x9566D22, True, mGT.encode(
            {"GPS_Week": week, "GPS_Time": tow_ms / 1000.0, "Accuracy_GPS_Time": 10,
             "Validity_GPS_Week": 1, "Validity_GPS_Time": 1}, strict=True)))
        can1.append((tq + 0.0004, 0, 0x9567C22, True, mGS.encode(
            {"GPS_Speed_3D": round(float(gps3d[e]), 4), "GPS_Speed_2D": round(float(gps2d[e]), 4),
             "Accuracy_GPS_Speed": 3, "Validity_GPS_Speed_3D": 1, "Validity_GPS_Speed_2D": 1},
            strict=True)))
        can1.append((tq + 0.0008, 0, 0x9588322, True, mIV.encode(
            {"INS_Vel_Sideways_2D": round(float(inss[e]), 4), "INS_Vel_Forwards_2D": round(float(insf[e]), 4),
             "Accuracy_INS_Vel_Body": 4, "Validity_INS_Vel_Sideways": 1, "Validity_INS_Vel_Forwards": 1},
            strict=True)))
    nsv = int(r_gnss.integers(8, 13))
    for ks in range(int(D)):
        ts_ = ks + 0.55
        if r_gnss.uniform() < 0.05:
            nsv = int(np.clip(nsv + r_gnss.choice([-1, 1]), 6, 14))
        can1.append((ts_, 0, 0x9566C22, True, mGST.encode(
            {"RTK_Status": 0, "GPS_nSv_RTK": 0, "GPS_nSv_2": 0, "GPS_nSv": nsv,
             "Firmware_Version_Minor": 7, "Firmware_Version_Intermediate": 2,
             "Firmware_Version_Major": 1, "GPS_Status": 12}, strict=True)))

    # ---------------- bus arbitration, host timestamps, losses ----------------
    def bits(ext, dlen):
        return (67 if ext else 47) + 8 * dlen + 10

    def schedule(frames, bitrate, usb, loss_p, rng, burst=None):
        frames.sort(key=lambda f: (f[0], f[1]))
        out = []
        t_free = -1.0
        last_host = -1.0
        lost = 0
        for (tq, _pr, aid, ext, data) in frames:
            start = max(tq, t_free)
            end = start + bits(ext, len(data)) / bitrate
            t_free = end + 3.0 / bitrate
            if usb:
                base = end + 50e-6
                host = (math.floor(base / 1e-3) + 1) * 1e-3 + abs(rng.normal(0, 15e-6))
            else:
                host = end + 25e-6 + rng.exponential(15e-6)
            host = round(host * 1e6) / 1e6            # kernel timestamps in whole microseconds
            host = max(host, last_host + 1e-6)
            host = round(host * 1e6) / 1e6
            last_host = host
            if rng.uniform() < loss_p or (burst is not None and burst[0] <= tq < burst[1] and aid != 0x123):
                lost += 1
                continue
            out.append((host, aid, ext, data))
        return out, lost

    burst = None
    if setup["wft_burst"]:
        b0 = float(r_bus.uniform(20.0, D - 20.0))
        burst = (b0, b0 + 0.002 * int(r_bus.integers(10, 60)))
    f0, lost0 = schedule(can0, 1e6, False, setup["wft_loss_prob"], r_bus, burst)
    f1, lost1 = schedule(can1, 500e3, True, setup["can1_loss_prob"], r_bus)
    allf = [(h, 0, a, e, d) for (h, a, e, d) in f0] + [(h, 1, a, e, d) for (h, a, e, d) in f1]
    allf.sort(key=lambda f: f[0])

    # ---------------- write the log ----------------
    os.makedirs(outdir, exist_ok=True)
    ext_ = {"asc": ".asc", "blf": ".blf", "log": ".log"}[fmt]
    path = os.path.join(outdir, name + ext_)
    if fmt == "asc":
        wr = can.ASCWriter(path)
    elif fmt == "blf":
        wr = can.BLFWriter(path)
    else:
        wr = can.CanutilsLogWriter(path)
    chans = ("can0", "can1")
    counts: dict[str, int] = {}
    host0_us = int(round(host0 * 1e6))
    for (h, bus, aid, ext, data) in allf:
        wr.on_message_received(can.Message(timestamp=(host0_us + int(round(h * 1e6))) / 1e6, arbitration_id=aid, is_extended_id=ext,
                                           data=data, channel=chans[bus], is_rx=True))
        key = f"{chans[bus]}:0x{aid:X}"
        counts[key] = counts.get(key, 0) + 1
    wr.stop()

    # counter gaps actually present in the written force frames
    wft_seen = [c for (h, bus, aid, ext, data) in allf if bus == 0 and aid == 0x120 for c in [data[6]]]
    gaps = int(sum(1 for a_, b_ in zip(wft_seen, wft_seen[1:]) if (b_ - a_) % 256 != 1))

    # ---------------- truth ----------------
    moving = V > 0.5
    i_mov = np.nonzero(moving)[0]
    Vmean = float(V[moving].mean())
    eff = effect_sizes(case, p, W0, Vmean, lab, r, b, soil_case, ph)
    verdicts = list(spec["verdicts"])
    small = (eff["effect_max_abs_dDp_N_s0.1_0.85"] < 50.0 and eff["effect_max_abs_dT_Nm_s0.1_0.85"] < 25.0)
    if small and "none" not in verdicts:
        verdicts.append("none")
    i5 = np.arange(0, n, 200)
    series = {
        "t_s": np.round(t[i5], 3).tolist(),
        "V_mps": np.round(V[i5], 4).tolist(),
        "slip_r047": np.round(s_cmd[i5], 4).tolist(),
        "slip_true": np.round(s_true[i5], 4).tolist(),
        "Dp_N": np.round(np.interp(t[i5], t50, Dp50), 1).tolist(),
        "T_Nm": np.round(np.interp(t[i5], t50, T50), 1).tolist(),
        "W_soil_N": np.round(W_soil[i5], 1).tolist(),
        "Z_m": np.round(np.interp(t[i5], t50, Z50), 5).tolist(),
        "F_tow_N": np.round(F_rope[i5], 1).tolist(),
    }
    truth = {
        "case": case, "seed": seed, "effect": spec["effect"],
        "in_list": spec["effect"] in IN_LIST,
        "acceptable_verdicts": verdicts,
        "description": spec["doc"],
        "model": model_description(case, p, soil_case, ph),
        "params": p,
        "gnss_latency_s": L,
        "wheel_radius_m": r, "wheel_width_m": b,
        "terrain": {"name": "clay", **CLAY_TABLE,
                    "units": {"c": "kPa", "phi": "deg", "K": "m", "n": "-",
                              "kc": "kN/m^(n+1)", "kphi": "kN/m^(n+2)"}},
        "effect_size_at_s0.5": eff["effect_size_at_s0.5"],
        "effect_details": eff,
        "setup": setup,
        "run": {
            "duration_s": D,
            "procedure": ("towed: a tractor pulls the test vehicle on a rope at a controlled, slowly varying "
                          "speed; rear axle driven (rear diff locked, front axle disengaged, front wheels "
                          "free-rolling); the driver sweeps slip (w.r.t. r = 0.47 m) in held plateaus "
                          "and slow ramps"),
            "slip_program_segments": segments,
            "moving_window_s": [float(t[i_mov[0]]), float(t[i_mov[-1]])] if i_mov.size else None,
            "slip_range": [float(s_cmd[moving].min()), float(s_cmd[moving].max())],
            "slip_true_range": [float(s_true[moving].min()), float(s_true[moving].max())],
            "speed_range_mps": [float(V[moving].min()), float(V[moving].max())],
            "speed_mean_mps": Vmean,
            "distance_m": x_end,
            "W_soil_range_N": [float(W_soil[moving].min()), float(W_soil[moving].max())],
            "tow_force_range_N": [float(F_rope[moving].min()), float(F_rope[moving].max())],
            "frames": counts,
            "frames_total": len(allf),
            "wft_frames_lost": lost0, "can1_frames_lost": lost1,
            "wft_force_counter_gaps": gaps,
            "wft_burst_loss_s": list(burst) if burst else None,
            "wft_overload_samples": n_overload,
            "host_start_unix": host0,
            "gps_minus_host_s_at_start": gps0 - host0,
            "host_clock_error_s": setup["host_clock_error_s"],
            "channels": {"can0": "WFT bus, 1 Mbit/s (ASC/BLF channel 1)",
                         "can1": "wheel speed + GNSS bus, 500 kbit/s (ASC/BLF channel 2)"},
            "format": fmt, "log_file": os.path.basename(path),
            "note_low_speed": "forces are blended in over the first 0.4 m of travel and out below 0.1 m/s; "
                              "analyse V > 0.5 m/s",
        },
        "series_5Hz": series,
    }
    tpath = os.path.join(outdir, name + "_truth.json")
    with open(tpath, "w") as fh:
        json.dump(truth, fh, indent=1, default=float)
    truth["_wall_s"] = time.time() - wall0
    truth["_path"] = path
    return truth


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("case", nargs="?")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--out", default=None)
    ap.add_argument("--outdir", default=".")
    ap.add_argument("--p", action="append", default=[], metavar="key=value")
    ap.add_argument("--format", choices=["asc", "blf", "log"], default="log")
    ap.add_argument("--list", action="store_true")
    a = ap.parse_args(argv)
    if a.list or not a.case:
        for c in CASE_ORDER:
            sp = CASES[c]
            print(f"{c:16s} effect={sp['effect']:20s} verdicts={','.join(sp['verdicts']):28s} "
                  f"defaults={json.dumps(sp['defaults'])}")
            print(f"{'':16s} {sp['doc']}")
        print("\ncommon --p keys (default: drawn from the seed): duration_s W0_N V0_mps gnss_latency_s "
              "soil_sigma_k soil_sigma_c soil_sigma_phi_deg soil_corr_len_m r b host_clock_error_s ...")
        return 0
    over = {}
    for kv in a.p:
        k, _, v = kv.partition("=")
        over[k] = parse_value(v)
    name = a.out or f"{a.case}_{a.seed}"
    tr = simulate(a.case, a.seed, over, a.format, a.outdir, name)
    print(f"{tr['_path']}  {tr['run']['duration_s']:.1f} s  frames={tr['run']['frames_total']}  "
          f"effect_size_at_s0.5={tr['effect_size_at_s0.5']:+.3f}  verdicts={tr['acceptable_verdicts']}  "
          f"wall={tr['_wall_s']:.1f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
