#!/usr/bin/env python
"""foreign14 generator: anchored-winch drawbar-pull ramps of a 4x4 (see README.md).

gen.py CASE --seed S --out NAME --outdir DIR [--p key=value ...]
writes DIR/NAME.<log|asc|blf> and DIR/NAME_truth.json.  A run the vehicle cannot drive is
refused: prints "REFUSED: reason" and exits 2.
"""
import argparse
import json
import math
import os
import sys
import time
import tomllib

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
from physics import wheel_forces, soil_si  # noqa: E402

G = 9.81
# --- the instrumented wheel (left rear), my own choice: 14.5R20-class off-road tyre on a steel rim
WHEEL = dict(r=0.53, b=0.36, m=92.0, I=14.0)
# --- the vehicle: 4x4, both axles driven, all differentials locked
VEH = dict(mass=3600.0, front_frac=0.48, wheelbase=3.30, h_cg=1.05, h_hitch=0.55)
CABLE_M = 300.0          # winch cable length
F_SLACK = 250.0          # cable drag on the ground with the winch brake released, N

IN_CASES = ["none", "vasilev", "lyasko", "ding", "terrain_mismatch", "stress_distribution",
            "terrain_drift"]
OUT_CASES = ["eccentric_rim", "fx_sign_flip", "vegetation_drag", "fz_clip", "tyre_chain",
             "moisture_squeeze", "flooded_lane"]
CASES = IN_CASES + OUT_CASES
VERDICT = {"none": "none", "vasilev": "slip_sinkage", "lyasko": "slip_sinkage",
           "ding": "slip_sinkage", "terrain_mismatch": "terrain_mismatch",
           "stress_distribution": "stress_distribution", "terrain_drift": "terrain_drift"}
SOIL_KEYS = ["c_kpa", "phi_deg", "K_m", "n", "k_eq"]


class Refused(Exception):
    pass


def load_lab(name):
    path = os.path.join(HERE, f"lab_{name}.toml")
    with open(path, "rb") as f:
        lab = tomllib.load(f)
    return lab, os.path.relpath(path, os.path.dirname(os.path.dirname(HERE)))


def shift_soil(lab, b, z):
    """Lab soil shifted by z (dict of lab-sd multiples for SOIL_KEYS)."""
    u = lab["uncertainty"]
    s = dict(c_kpa=lab["c_kpa"] + z.get("c_kpa", 0.0) * u["c_kpa"],
             phi_deg=lab["phi_deg"] + z.get("phi_deg", 0.0) * u["phi_deg"],
             K_m=lab["K_m"] + z.get("K_m", 0.0) * u["K_m"],
             n=lab["n"] + z.get("n", 0.0) * u["n"],
             kc=lab["kc"], kphi=lab["kphi"])
    f = 1.0 + z.get("k_eq", 0.0) * u["k_eq_rel"]          # k_eq = kc/b + kphi scaled as a whole
    s["kc"] *= f
    s["kphi"] *= f
    s["k_eq"] = s["kc"] / b + s["kphi"]
    if s["c_kpa"] < 0 or s["K_m"] <= 0.002 or s["n"] <= 0.2 or f <= 0.1:
        raise Refused(f"soil parameters out of range {s}")
    return s


def draw_params(case, seed, over):
    """Every knob of a run, drawn from the seed; overrides replace the drawn values."""
    rng = np.random.default_rng(seed)
    p = {}
    p["soil"] = str(rng.choice(["loam", "sand"]))
    p["fmt"] = str(rng.choice(["log", "asc", "blf"]))
    p["duration_s"] = round(float(rng.uniform(120.0, 200.0)), 1)
    p["gnss_latency_s"] = round(float(rng.uniform(0.03, 0.2)), 4)
    p["ballast_kg"] = round(float(rng.uniform(0.0, 500.0)), 0)
    p["soil_offset_sd"] = {k: round(float(np.clip(rng.normal(0, 0.5), -1, 1)), 3) for k in SOIL_KEYS}
    ps = rng.uniform(0.25, 0.85, 12)
    ps[1] = rng.uniform(0.75, 0.88)
    p["peak_slip"] = [round(float(x), 3) for x in ps]
    p["speed_set_mps"] = [round(float(x), 3) for x in rng.uniform(0.8, 1.5, 12)]
    p["ramp_s"] = [round(float(x), 2) for x in rng.uniform(14.0, 22.0, 12)]
    p["droop"] = 0.05
    e = {}
    if case == "vasilev":
        e["H"] = round(float(rng.uniform(0.015, 0.04)), 4)
    elif case == "lyasko":
        e["m1"] = round(float(rng.uniform(0.3, 0.7)), 3)
        e["m2"] = round(float(rng.uniform(0.03, 0.08)), 3)
    elif case == "ding":
        e["n1"] = round(float(rng.uniform(0.45, 0.65)), 3)
    elif case == "terrain_mismatch":
        keys = list(rng.choice(SOIL_KEYS, size=int(rng.integers(1, 3)), replace=False))
        e["mismatch_sd"] = {str(k): round(float(rng.choice([-1, 1]) * rng.uniform(2.5, 4.0)), 3)
                            for k in keys}
        if "k_eq" in e["mismatch_sd"]:       # keep k_eq positive: lower it at most 3.5 sd
            e["mismatch_sd"]["k_eq"] = max(e["mismatch_sd"]["k_eq"], -3.5)
    elif case == "stress_distribution":
        e["a1"] = round(float(rng.uniform(0.20, 0.30)), 3)
        e["a2"] = round(float(rng.uniform(0.05, 0.20)), 3)
    elif case == "terrain_drift":
        keys = list(rng.choice(["phi_deg", "k_eq", "c_kpa"], size=int(rng.integers(1, 3)), replace=False))
        e["drift_sd"] = {str(k): round(float(rng.choice([-1, 1]) * rng.uniform(3.0, 5.0)), 3) for k in keys}
        if "k_eq" in e["drift_sd"]:
            e["drift_sd"]["k_eq"] = max(e["drift_sd"]["k_eq"], -3.5)
    elif case == "eccentric_rim":
        e["runout_m"] = round(float(rng.uniform(0.010, 0.018)), 4)
        e["runout_phase_deg"] = round(float(rng.uniform(0, 360)), 1)
        e["k_vert_n_per_m"] = 120000.0
    elif case == "fx_sign_flip":
        e["t_flip_frac"] = round(float(rng.uniform(0.35, 0.65)), 3)
    elif case == "vegetation_drag":
        e["drag_n_per_mps"] = round(float(rng.uniform(180.0, 320.0)), 1)
    elif case == "fz_clip":
        e["clip_frac"] = round(float(rng.uniform(0.85, 0.93)), 3)
    elif case == "tyre_chain":
        e["n_links"] = int(rng.choice([8, 10, 12]))
        e["f_link_n"] = round(float(rng.uniform(600.0, 1000.0)), 1)
        e["s0"] = 0.12
    elif case == "moisture_squeeze":
        e["beta"] = round(float(rng.uniform(0.60, 0.75)), 3)
        e["sig_d_kpa"] = round(float(rng.uniform(40.0, 60.0)), 1)
    elif case == "flooded_lane":
        e["depth_m"] = round(float(rng.uniform(0.2, 0.3)), 3)
        e["cd"] = 1.5
        starts = np.sort(rng.uniform(15.0, 120.0, 3))
        e["patches_m"] = [[round(float(a), 1), round(float(a + rng.uniform(10.0, 22.0)), 1)] for a in starts]
        e["wet"] = {"c_factor": 0.5, "dphi_deg": -4.0, "k_eq_factor": 0.7}
    p.update(e)
    for k, v in over.items():
        p[k] = v
    p["seed"] = seed
    return p


class Run:
    def __init__(self, case, seed, over):
        if case not in CASES:
            raise SystemExit(f"unknown case {case}; cases: {CASES}")
        self.case, self.seed = case, seed
        self.p = p = draw_params(case, seed, over)
        self.rng = np.random.default_rng(seed + 7919)
        self.lab, self.lab_path = load_lab(p["soil"])
        r, b = WHEEL["r"], WHEEL["b"]
        z = dict(p["soil_offset_sd"])
        if case == "terrain_mismatch":
            for k, v in p["mismatch_sd"].items():
                z[k] = v                      # the deliberate change replaces the random offset
        self.soil0 = shift_soil(self.lab, b, z)
        self.soil1 = self.soil0
        if case == "terrain_drift":
            z1 = dict(z)
            for k, v in p["drift_sd"].items():
                z1[k] = z[k] + v
            self.soil1 = shift_soil(self.lab, b, z1)
        if case == "flooded_lane":
            w = p["wet"]
            s1 = dict(self.soil0)
            s1["c_kpa"] *= w["c_factor"]
            s1["phi_deg"] += w["dphi_deg"]
            s1["kc"] *= w["k_eq_factor"]
            s1["kphi"] *= w["k_eq_factor"]
            s1["k_eq"] = s1["kc"] / b + s1["kphi"]
            self.soil1 = s1
        self.model, self.mp = "wong", {}
        if case in ("vasilev", "lyasko", "ding"):
            self.model = case
            self.mp = {k: p[k] for k in {"vasilev": ["H"], "lyasko": ["m1", "m2"], "ding": ["n1"]}[case]}
        elif case == "stress_distribution":
            self.model, self.mp = "stress", {"a1": p["a1"], "a2": p["a2"]}
        elif case == "moisture_squeeze":
            self.model, self.mp = "moisture", {"beta": p["beta"], "sig_d": p["sig_d_kpa"] * 1e3}
        M = VEH["mass"] + p["ballast_kg"]
        self.M = M
        self.Wf0 = VEH["mass"] * G * VEH["front_frac"] / 2
        self.Wr0 = (VEH["mass"] * G * (1 - VEH["front_frac"]) + p["ballast_kg"] * G) / 2

    # ---------------------------------------------------------------- soil along the lane
    def soil_at(self, g):
        """Soil (SI dict) at blend level g in [0, 1] between soil0 and soil1 (arrays allowed)."""
        g = np.asarray(g, float)
        out = {}
        for k in ("c_kpa", "phi_deg", "K_m", "n"):
            out[k] = self.soil0[k] + g * (self.soil1[k] - self.soil0[k])
        # k_eq blended geometrically, split kc/kphi in the lab ratio
        f = (self.soil1["k_eq"] / self.soil0["k_eq"]) ** g
        out["kc"] = self.soil0["kc"] * f
        out["kphi"] = self.soil0["kphi"] * f
        return soil_si(out)

    def g_of_x(self, x):
        x = np.asarray(x, float)
        if self.case == "terrain_drift":
            return np.clip(x / self.lane_len, 0.0, 1.0)
        if self.case == "flooded_lane":
            g = np.zeros_like(x)
            for a, bnd in self.p["patches_m"]:
                g = np.maximum(g, np.clip(np.minimum(x - a, bnd - x) / 1.0 + 0.5, 0.0, 1.0))
            return g
        return np.zeros_like(x)

    def ext_drag(self, V, g):
        """External (non-soil) drag on one wheel at axle height, N."""
        if self.case == "vegetation_drag":
            return self.p["drag_n_per_mps"] * V
        if self.case == "flooded_lane":
            return 0.5 * 1000.0 * self.p["cd"] * WHEEL["b"] * self.p["depth_m"] * V * V * g
        return 0.0 * V

    def chain_mean(self, s, th1=0.55):
        if self.case != "tyre_chain":
            return 0.0 * s
        duty = min(1.0, th1 / (2 * math.pi / self.p["n_links"])) * 2 / math.pi
        return self.p["f_link_n"] * duty * (1 - np.exp(-np.maximum(s, 0) / self.p["s0"]))

    # ---------------------------------------------------------------- tables for the vehicle ODE
    def build_tables(self):
        r, b = WHEEL["r"], WHEEL["b"]
        self.sg = np.linspace(-0.1, 1.0, 221)
        self.gg = np.linspace(0, 1, 9) if self.case in ("terrain_drift", "flooded_lane") else np.array([0.0])
        self.tabs = []
        for W0 in (self.Wf0, self.Wr0):
            wg = np.linspace(0.4 * W0, 1.8 * W0, 11)
            tab = np.zeros((len(self.gg), len(wg), len(self.sg)))
            S, Wm = np.meshgrid(self.sg, wg)
            for i, g in enumerate(self.gg):
                so = self.soil_at(np.full(S.size, g))
                Dp, _ = wheel_forces(S.ravel(), Wm.ravel(), r, b, so, self.model, self.mp)
                tab[i] = Dp.reshape(S.shape)
            self.tabs.append((wg, tab))

    def dp_tab(self, k, s, W, g):
        """Table Dp of wheel type k (0 front, 1 rear) and its slope dDp/ds (scalars)."""
        wg, tab = self.tabs[k]
        sg, gg = self.sg, self.gg
        fs = (min(max(s, sg[0]), sg[-1] - 1e-9) - sg[0]) / (sg[1] - sg[0])
        i = int(fs); u = fs - i
        fw = (min(max(W, wg[0]), wg[-1] - 1e-6) - wg[0]) / (wg[1] - wg[0])
        j = int(fw); v = fw - j
        if len(gg) > 1:
            fg = min(max(g, 0.0), 1.0 - 1e-9) * (len(gg) - 1)
            m = int(fg); w = fg - m
            t = tab[m] * (1 - w) + tab[m + 1] * w if w > 0 else tab[m]
        else:
            t = tab[0]
        a0 = t[j, i] * (1 - v) + t[j + 1, i] * v
        a1 = t[j, i + 1] * (1 - v) + t[j + 1, i + 1] * v
        return a0 + (a1 - a0) * u, (a1 - a0) / (sg[1] - sg[0])

    # ---------------------------------------------------------------- procedure
    def schedule(self):
        """Cycle plan: launch, then winch-brake ramps; returns piecewise description."""
        p = self.p
        t_launch, t_spin = 1.0, 3.0
        self.t_launch, self.t_spin = t_launch, t_spin
        T = p["duration_s"]
        cycles = []
        t = t_launch + t_spin + 4.0
        k = 0
        while True:
            ramp = p["ramp_s"][k % len(p["ramp_s"])]
            t_end = t + ramp + 4.0 + 1.5 + 6.0
            if t_end > T - 1.0:
                break
            cycles.append(dict(t0=t, ramp=ramp, hold=4.0, rel=1.5, slack=6.0,
                               v_next=p["speed_set_mps"][(k + 1) % len(p["speed_set_mps"])]))
            t = t_end
            k += 1
        if not cycles:
            raise Refused("run too short for one pull")
        self.cycles = cycles

    def pull_at(self, v_set, s_t, g_plan=None):
        """Quasi-static tether pull that holds the vehicle at slip s_t (load transfer included),
        and the largest pull the vehicle can hold at any slip <= 0.95 (worst soil of the lane)."""
        F_t, F_max = np.inf, np.inf
        gl = [0.0, 1.0] if len(self.gg) > 1 else [0.0]
        if g_plan is not None:
            gl = [g_plan]
        for g in gl:
            F = 0.0
            for _ in range(5):
                dW = F * VEH["h_hitch"] / VEH["wheelbase"] / 2
                ss = np.linspace(0.05, 0.95, 91)
                tot = np.array([2 * self.dp_tab(0, s, self.Wf0 - dW, g)[0] + 2 * self.dp_tab(1, s, self.Wr0 + dW, g)[0]
                                for s in ss]) + self.chain_mean(ss)
                tot -= 4 * self.ext_drag(v_set * (1 - ss), g)
                Fm = float(np.max(tot))
                F = min(float(np.interp(s_t, ss, tot)), 0.995 * Fm)
            F_t, F_max = min(F_t, F), min(F_max, Fm)
        return F_t, F_max

    def g_plan(self, t):
        if getattr(self, "dyn", None) is None:
            return 0.0
        return float(self.g_of_x(np.interp(t, self.dyn["t"], self.dyn["x"])))

    def plan_pulls(self):
        peaks = []
        for k, c in enumerate(self.cycles):
            v_set = self.p["speed_set_mps"][k % len(self.p["speed_set_mps"])]
            s_t = float(self.p["peak_slip"][k % len(self.p["peak_slip"])])
            if not 0.0 < s_t < 0.95:
                raise Refused(f"peak slip {s_t} not in (0, 0.95): the vehicle would stall")
            if self.case == "terrain_drift":
                F, Fm = self.pull_at(v_set, s_t, self.g_plan(c["t0"] + c["ramp"]))
            elif self.case == "flooded_lane":
                F, _ = self.pull_at(v_set, s_t, 0.0)
                Fm = self.pull_at(v_set, 0.5, 1.0)[1]
                F = min(F, 0.97 * Fm)
            else:
                F, Fm = self.pull_at(v_set, s_t)
            if Fm <= F_SLACK + 200.0:
                raise Refused(f"vehicle cannot pull: largest drawbar pull {Fm:.0f} N")
            if "peak_pull_kN" in self.p:
                F = float(self.p["peak_pull_kN"]) * 1e3
                if F > Fm:
                    raise Refused(f"requested winch pull {F:.0f} N exceeds the largest drawbar pull "
                                  f"{Fm:.0f} N the vehicle can hold (it would stall)")
            c["F_peak"] = F
            peaks.append(round(F, 1))
        self.p["peak_pull_N"] = peaks

    def controls(self, t):
        """Wheel speed set point r*omega (m/s, before droop) and tether tension F at time t."""
        p = self.p
        v0 = p["speed_set_mps"][0]
        if t < self.t_launch:
            return 0.0, 0.0
        if t < self.t_launch + self.t_spin:
            x = (t - self.t_launch) / self.t_spin
            return v0 * (0.5 - 0.5 * math.cos(math.pi * x)), F_SLACK * x
        v_set, F = v0, F_SLACK
        for k, c in enumerate(self.cycles):
            if t < c["t0"]:
                break
            v_set = p["speed_set_mps"][k % len(p["speed_set_mps"])]
            tt = t - c["t0"]
            Fp = c["F_peak"]
            if tt < c["ramp"]:
                x = tt / c["ramp"]
                F = F_SLACK + (Fp - F_SLACK) * (x - math.sin(2 * math.pi * x) / (2 * math.pi) * 0.3)
            elif tt < c["ramp"] + c["hold"]:
                F = Fp
            elif tt < c["ramp"] + c["hold"] + c["rel"]:
                x = (tt - c["ramp"] - c["hold"]) / c["rel"]
                F = Fp + (F_SLACK - Fp) * (0.5 - 0.5 * math.cos(math.pi * x))
            else:
                F = F_SLACK
                ts = tt - c["ramp"] - c["hold"] - c["rel"]
                if ts > 1.0:          # driver changes the engine speed for the next pull
                    x = min(1.0, (ts - 1.0) / 2.5)
                    v_set = v_set + (c["v_next"] - v_set) * (0.5 - 0.5 * math.cos(math.pi * x))
        return v_set, F

    # ---------------------------------------------------------------- vehicle ODE
    def simulate_vehicle(self):
        p = self.p
        dt = 0.004
        n = int(round(p["duration_s"] / dt)) + 1
        t = np.arange(n) * dt
        Fmax = max(c["F_peak"] for c in self.cycles)
        ph = self.rng.uniform(0, 2 * math.pi)
        V = np.zeros(n); x = np.zeros(n); a = np.zeros(n); F = np.zeros(n); rw = np.zeros(n)
        Wf = np.zeros(n); Wr = np.zeros(n); s_arr = np.zeros(n)
        Vc, xc, ac = 0.0, 0.0, 0.0
        M = self.M
        r = WHEEL["r"]
        stall = 0.0
        for i in range(n):
            ti = t[i]
            vset, Fi = self.controls(ti)
            rwi = vset * (1 - p["droop"] * Fi / Fmax) * (1 + 0.003 * math.sin(2 * math.pi * 2.4 * ti + ph))
            dW = (Fi * VEH["h_hitch"] + M * ac * VEH["h_cg"]) / VEH["wheelbase"] / 2
            wf, wr = self.Wf0 - dW, self.Wr0 + dW
            g = float(self.g_of_x(xc)) if len(self.gg) > 1 else 0.0
            V[i], x[i], a[i], F[i], rw[i], Wf[i], Wr[i] = Vc, xc, ac, Fi, rwi, wf, wr
            if rwi <= 1e-4 and Vc <= 1e-6:
                ac = 0.0
                continue
            den = max(rwi, 0.05)
            s = min(max((rwi - Vc) / den, -0.2), 1.0)
            s_arr[i] = s
            d0, k0 = self.dp_tab(0, s, wf, g)
            d1, k1 = self.dp_tab(1, s, wr, g)
            ch = float(self.chain_mean(s))
            drag = 4 * float(self.ext_drag(Vc, g))
            ddrag = 4 * float(self.ext_drag(Vc + 1e-3, g) - self.ext_drag(Vc, g)) / 1e-3
            f = (2 * d0 + 2 * d1 + ch - Fi - drag) / M
            fp = (-(2 * k0 + 2 * k1) / den - ddrag) / M
            dv = dt * f / (1 - dt * min(fp, 0.0))
            Vn = max(Vc + dv, 0.0)
            ac = (Vn - Vc) / dt
            xc += 0.5 * (Vc + Vn) * dt
            Vc = Vn
            if ti > self.t_launch + self.t_spin + 2 and Vc < 0.03:
                stall += dt
                if stall > 1.0:
                    raise Refused(f"vehicle stalled at t={ti:.1f} s (winch pull {Fi:.0f} N exceeds traction)")
            else:
                stall = 0.0
            if xc > CABLE_M:
                raise Refused(f"run longer than the winch cable ({CABLE_M:.0f} m)")
        # smooth acceleration for the inertia term (the ODE's a is the exact step derivative)
        self.dyn = dict(t=t, V=V, x=x, a=a, F=F, rw=rw, Wf=Wf, Wr=Wr, s=s_arr)

    # ---------------------------------------------------------------- the instrumented wheel
    def wheel_signals(self, tw):
        d = self.dyn
        p = self.p
        r, b = WHEEL["r"], WHEEL["b"]
        V = np.interp(tw, d["t"], d["V"])
        rw = np.interp(tw, d["t"], d["rw"])
        W = np.interp(tw, d["t"], d["Wr"])
        x = np.interp(tw, d["t"], d["x"])
        dVdt = np.interp(tw, d["t"], d["a"])
        om = rw / r
        # d omega / dt from the (smooth) schedule on the fine ODE grid
        dom = np.gradient(d["rw"] / r, d["t"])
        domdt = np.interp(tw, d["t"], dom)
        ang = np.interp(tw, d["t"], np.concatenate([[0.0], np.cumsum(0.5 * (d["rw"][1:] + d["rw"][:-1]) / r * np.diff(d["t"]))]))
        ang = ang + self.ang0
        reff = np.full_like(V, r)
        if self.case == "eccentric_rim":
            cphase = np.cos(ang - math.radians(p["runout_phase_deg"]))
            reff = r + p["runout_m"] * cphase
            W = W + p["k_vert_n_per_m"] * p["runout_m"] * cphase
        moving = om * reff > 1e-3
        s = np.where(moving, np.clip((om * reff - V) / np.maximum(om * reff, 0.05), -0.2, 1.0), 0.0)
        g = self.g_of_x(x)
        soil = self.soil_at(g)
        Dp, T, Z, th1, _ = wheel_forces(s, W, reff, b, soil, self.model, self.mp, return_all=True)
        Dp = np.where(moving, Dp, 0.0)
        T = np.where(moving, T, 0.0)
        if self.case == "tyre_chain":
            nl = p["n_links"]
            thr = np.zeros_like(s)
            for kk in range(nl):
                psi = -(ang + 2 * math.pi * kk / nl)          # link position angle, + ahead of BDC
                psi = (psi + math.pi) % (2 * math.pi) - math.pi
                inside = (psi >= 0) & (psi <= th1)
                thr += np.where(inside, np.sin(math.pi * np.clip(psi / th1, 0, 1)), 0.0)
            fl = p["f_link_n"] * (1 - np.exp(-np.maximum(s, 0) / p["s0"])) * thr
            Dp = Dp + np.where(moving, fl, 0.0)
            T = T + np.where(moving, fl * reff, 0.0)
        drag = self.ext_drag(V, g)
        Fx = Dp - drag - WHEEL["m"] * dVdt
        My = T + WHEEL["I"] * domdt
        return dict(Fx=Fx, Fz=W, My=My, ang=ang, s=s, Dp=Dp, T=T, Z=Z, V=V, om=om, drag=drag)


def encode_and_write(run, path):
    import can
    import cantools
    p = run.p
    rng = run.rng
    dbcdir = os.path.join(HERE, "dbc")
    db_wft = cantools.database.load_file(os.path.join(dbcdir, "wft.dbc"))
    db_wss = cantools.database.load_file(os.path.join(dbcdir, "wheel_speed.dbc"))
    db_gps = cantools.database.load_file(os.path.join(dbcdir, "gps_rt_speedbox.dbc"))
    T = p["duration_s"]
    t_abs0 = 1773900000.0 + (run.seed % 200) * 86400.0 + 3600.0 * 9   # host clock of t = 0
    frames = []   # (t, channel, id, ext, bytes)

    # ---- WFT, 500 Hz on can0
    t0w = rng.uniform(0, 0.002)
    nw = int((T - t0w) / 0.002)
    tw = t0w + np.arange(nw) * 0.002
    sig = run.wheel_signals(tw)
    nW = nw
    Fx = sig["Fx"] + rng.normal(0, 12.0, nW)
    Fz = sig["Fz"] + rng.normal(0, 20.0, nW)
    My = sig["My"] + rng.normal(0, 2.5, nW)
    Fy = 60.0 * np.sin(2 * np.pi * 0.07 * tw) + rng.normal(0, 25.0, nW)
    Mx = -0.02 * sig["Fz"] + rng.normal(0, 3.0, nW)
    Mz = rng.normal(0, 3.0, nW)
    a = sig["ang"]
    ca, sa = np.cos(a), np.sin(a)
    Fx_w = Fx * ca - Fz * sa
    Fz_w = Fx * sa + Fz * ca
    Mx_w = Mx * ca - Mz * sa
    Mz_w = Mx * sa + Mz * ca
    if run.case == "fx_sign_flip":
        Fx_w = np.where(tw > p["t_flip_frac"] * T, -Fx_w, Fx_w)
    if run.case == "fz_clip":
        L = p["clip_frac"] * run.Wr0
        Fz_w = np.clip(Fz_w, -L, L)
    cnt = (np.arange(nW) % 256).astype(np.uint8)

    def i16(v, scale):
        return np.clip(np.round(v / scale), -32768, 32767).astype("<i2")

    force = np.zeros((nW, 8), np.uint8)
    force[:, 0:2] = i16(Fx_w, 0.5).view(np.uint8).reshape(-1, 2)
    force[:, 2:4] = i16(Fy, 0.5).view(np.uint8).reshape(-1, 2)
    force[:, 4:6] = i16(Fz_w, 1.0).view(np.uint8).reshape(-1, 2)
    force[:, 6] = cnt
    mom = np.zeros((nW, 8), np.uint8)
    mom[:, 0:2] = i16(Mx_w, 0.25).view(np.uint8).reshape(-1, 2)
    mom[:, 2:4] = i16(My, 0.25).view(np.uint8).reshape(-1, 2)
    mom[:, 4:6] = i16(Mz_w, 0.25).view(np.uint8).reshape(-1, 2)
    mom[:, 6] = cnt
    angd = np.degrees(a) % 360.0
    araw = (np.round(angd / 0.0054931640625).astype(np.int64) % 65536).astype("<u2")
    angf = np.zeros((nW, 4), np.uint8)
    angf[:, 0:2] = araw.view(np.uint8).reshape(-1, 2)
    angf[:, 2] = cnt
    jit = rng.normal(0, 15e-6, (nW, 3)).clip(-40e-6, 40e-6)
    tf = tw[:, None] + np.array([0.00012, 0.00024, 0.00034])[None, :] + jit
    wft_frames = (tf, force, mom, angf)

    # ---- WSS 100 Hz, can1
    d = run.dyn
    ts = rng.uniform(0, 0.01) + np.arange(int((T - 0.01) / 0.01)) * 0.01
    om = np.interp(ts, d["t"], d["rw"]) / WHEEL["r"]
    rpm = om * 60 / (2 * np.pi)
    wss = np.zeros((len(ts), 8), np.uint8)
    for k in range(4):
        v = np.clip(np.round((rpm + rng.normal(0, 0.04, len(ts))) / 0.01), 0, 65535).astype(">u2")
        v = np.where(rpm > 0.05, v, 0).astype(">u2")
        wss[:, 2 * k:2 * k + 2] = v.view(np.uint8).reshape(-1, 2)
    ts_rx = ts + 0.0003 + rng.normal(0, 20e-6, len(ts)).clip(-60e-6, 60e-6)
    for i, tt in enumerate(ts_rx):
        frames.append((tt, "can1", 0x300, False, bytes(wss[i])))
    m_st = db_wss.get_message_by_name("WSS_Status")
    for k, tt in enumerate(np.arange(0.0037, T, 0.1)):
        frames.append((tt, "can1", m_st.frame_id, False,
                       m_st.encode({"RollingCounter": k % 16, "SensorFault_FL": 0, "SensorFault_FR": 0,
                                    "SensorFault_RL": 0, "SensorFault_RR": 0})))
    # ---- GNSS 20 Hz epochs on the receiver clock, arriving late by the latency
    lat = p["gnss_latency_s"]
    te = rng.uniform(0, 0.05) + np.arange(int((T - 0.3) / 0.05)) * 0.05
    Vt = np.interp(te, d["t"], d["V"])
    tow0 = 302400.0 + (run.seed % 97) * 60.0
    m_sp = db_gps.get_message_by_name("RT_SB_GPS_Speed")
    m_iv = db_gps.get_message_by_name("RT_SB_INS_Vel_Body_Axes")
    m_ti = db_gps.get_message_by_name("RT_SB_GPS_Time")
    m_gs = db_gps.get_message_by_name("RT_SB_GPS_Status")
    v2 = np.abs(Vt + rng.normal(0, 0.012, len(te)))
    vf = Vt + rng.normal(0, 0.008, len(te))
    vs = rng.normal(0, 0.01, len(te))
    for i, tt in enumerate(te):
        tr = tt + lat + rng.normal(0, 0.0015)
        frames.append((tr, "can1", m_sp.frame_id, True, m_sp.encode(
            {"GPS_Speed_3D": round(float(v2[i]) + 0.0004, 4), "GPS_Speed_2D": round(float(v2[i]), 4),
             "Accuracy_GPS_Speed": 8, "Validity_GPS_Speed_3D": 1, "Validity_GPS_Speed_2D": 1})))
        frames.append((tr + 0.00026, "can1", m_iv.frame_id, True, m_iv.encode(
            {"INS_Vel_Sideways_2D": round(float(vs[i]), 4), "INS_Vel_Forwards_2D": round(float(vf[i]), 4),
             "Accuracy_INS_Vel_Body": 6, "Validity_INS_Vel_Sideways": 1, "Validity_INS_Vel_Forwards": 1})))
        frames.append((tr + 0.00052, "can1", m_ti.frame_id, True, m_ti.encode(
            {"GPS_Week": 2410, "GPS_Time": round(tow0 + tt, 3), "Accuracy_GPS_Time": 5,
             "Validity_GPS_Week": 1, "Validity_GPS_Time": 1})))
    for k, tt in enumerate(np.arange(0.41, T, 1.0)):
        frames.append((tt, "can1", m_gs.frame_id, True, m_gs.encode(
            {"RTK_Status": 0, "GPS_nSv_RTK": 0, "GPS_nSv_2": 0, "GPS_nSv": int(13 + (k // 17) % 3),
             "Firmware_Version_Minor": 4, "Firmware_Version_Intermediate": 2, "Firmware_Version_Major": 3,
             "GPS_Status": 12})))
    # ---- WFT diag, 1 Hz per mux value, can0
    m_dg = db_wft.get_message_by_name("WFT_RL_Diag")
    for k, tt in enumerate(np.arange(0.1011, T, 1.0)):
        frames.append((tt, "can0", m_dg.frame_id, False, m_dg.encode(
            {"DiagMux": 0, "BridgeTemp": round(24.0 + 4.0 * tt / T, 2), "SupplyVoltage": 12.05})))
        frames.append((tt + 0.3333, "can0", m_dg.frame_id, False, m_dg.encode({"DiagMux": 1, "SerialNumber": 140711})))
        frames.append((tt + 0.6667, "can0", m_dg.frame_id, False, m_dg.encode(
            {"DiagMux": 2, "FirmwareMajor": 2, "FirmwareMinor": 3, "CalibrationId": 1417})))

    # ---- merge and write
    tf, force, mom, angf = wft_frames
    t_all = np.concatenate([tf[:, 0], tf[:, 1], tf[:, 2], np.array([f[0] for f in frames])])
    kind = np.concatenate([np.zeros(nW, int), np.ones(nW, int), np.full(nW, 2), np.full(len(frames), 3)])
    idx = np.concatenate([np.arange(nW)] * 3 + [np.arange(len(frames))])
    order = np.argsort(t_all, kind="stable")
    ext = os.path.splitext(path)[1]
    if ext == ".log":
        w = can.CanutilsLogWriter(path)
    elif ext == ".asc":
        w = can.ASCWriter(path)
    else:
        w = can.BLFWriter(path)
    ids = (0x120, 0x121, 0x122)
    arrs = (force, mom, angf)
    for o in order:
        kd, ix = kind[o], idx[o]
        tt = float(t_all[o]) + t_abs0
        if kd < 3:
            msg = can.Message(timestamp=tt, arbitration_id=ids[kd], is_extended_id=False,
                              data=arrs[kd][ix].tobytes(), channel="can0")
        else:
            f = frames[ix]
            msg = can.Message(timestamp=tt, arbitration_id=f[2], is_extended_id=f[3], data=f[4], channel=f[1])
        w.on_message_received(msg)
    w.stop()
    if ext == ".asc":     # python-can writes the wall-clock date into the header: make it the log's
        from datetime import datetime
        with open(path) as fh:
            lines = fh.readlines()
        dt0 = datetime.fromtimestamp(t_abs0)
        lines[0] = "date " + can.ASCWriter._format_header_datetime(can.ASCWriter, dt0) + "\n"
        with open(path, "w") as fh:
            fh.writelines(lines)
    return sig, tw, t_abs0


def main(argv=None):
    ap = argparse.ArgumentParser()
    ap.add_argument("case")
    ap.add_argument("--seed", type=int, required=True)
    ap.add_argument("--out", required=True)
    ap.add_argument("--outdir", required=True)
    ap.add_argument("--p", action="append", default=[], metavar="key=value")
    a = ap.parse_args(argv)
    over = {}
    for kv in a.p:
        k, _, v = kv.partition("=")
        try:
            over[k] = json.loads(v)
        except json.JSONDecodeError:
            over[k] = v
    t_start = time.time()
    try:
        run = Run(a.case, a.seed, over)
        run.ang0 = float(run.rng.uniform(0, 2 * math.pi))
        run.lane_len = 0.0
        run.build_tables()
        run.schedule()
        run.plan_pulls()
        # lane length for the drift: the distance of the run, estimated from the plan (re-run once)
        run.dyn = None
        if a.case == "terrain_drift":
            run.lane_len = 1e9
            run.simulate_vehicle()
            run.lane_len = max(float(run.dyn["x"][-1]), 1.0)
            run.plan_pulls()
        run.simulate_vehicle()
        if a.case == "terrain_drift":
            run.p["drift_g_end"] = round(float(run.g_of_x(run.dyn["x"][-1])), 4)
    except Refused as e:
        print(f"REFUSED: {e}")
        return 2
    p = run.p
    os.makedirs(a.outdir, exist_ok=True)
    fname = f"{a.out}.{p['fmt']}"
    sig, tw, t_abs0 = encode_and_write(run, os.path.join(a.outdir, fname))
    d = run.dyn
    mv = d["rw"] > 0.2
    p["distance_m"] = round(float(d["x"][-1]), 1)
    p["slip_range"] = [round(float(np.min(sig["s"][sig["om"] > 0.5])), 3), round(float(np.max(sig["s"])), 3)]
    p["lab_terrain"] = run.lab_path
    p["wheel"] = dict(WHEEL)
    p["vehicle"] = dict(VEH, mass_total_kg=run.M, W_front_static_N=round(run.Wf0, 1),
                        W_rear_static_N=round(run.Wr0, 1))
    p["sinkage"] = "eq10"
    p["true_soil"] = {k: round(float(v), 6) for k, v in run.soil0.items()}
    if run.soil1 is not run.soil0:
        p["true_soil_end" if a.case == "terrain_drift" else "true_soil_wet"] = \
            {k: round(float(v), 6) for k, v in run.soil1.items()}
    if a.case == "terrain_drift":
        p["drift_profile"] = "linear in distance from the start (soil0) to the end of the run (soil_end)"
    if a.case == "fx_sign_flip":
        p["t_flip_s"] = round(p["t_flip_frac"] * p["duration_s"], 3)
    if a.case == "fz_clip":
        p["clip_level_N"] = round(p["clip_frac"] * run.Wr0, 1)
    p["host_t0"] = t_abs0
    r = WHEEL
    truth = {
        "name": a.out,
        "case": a.case,
        "family": "in" if a.case in IN_CASES else "out",
        "acceptable_verdicts": [VERDICT[a.case]] if a.case in IN_CASES else ["unexplained"],
        "form": a.case if a.case in ("vasilev", "lyasko", "ding") else None,
        "params": p,
        "fit_args": [fname, "--terrain", run.lab_path, "--wheel-radius", str(r["r"]),
                     "--wheel-width", str(r["b"]), "--wheel-mass", str(r["m"]),
                     "--wheel-inertia", str(r["I"]), "--sinkage", "eq10"],
        "generator": "foreign14",
        "runtime_s": round(time.time() - t_start, 2),
    }
    with open(os.path.join(a.outdir, f"{a.out}_truth.json"), "w") as f:
        json.dump(truth, f, indent=1, sort_keys=False)
    print(f"{a.out}: {a.case} -> {fname} ({p['duration_s']} s, {p['distance_m']} m, slip "
          f"{p['slip_range'][0]}..{p['slip_range'][1]}, {truth['runtime_s']} s)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
