#!/usr/bin/env python
"""foreign5: independent synthetic field-run generator (towed dynamometer-car procedure).

usage: gen.py CASE --seed S --out NAME --outdir DIR --format {log,asc,blf,trc} [--p key=value ...]

Writes DIR/NAME.<fmt> (both CAN buses) and DIR/NAME_truth.json.
"""
import argparse
import json
import logging
import math
import os
import sys
import time
import tomllib

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
import terra  # noqa: E402

logging.getLogger("can").setLevel(logging.ERROR)

# ---------------------------------------------------------------- wheel / vehicle
WHEEL = dict(r=0.43, b=0.285, m=68.0, I=8.6)          # 34x11.50R16 on a WFT adapter rim
VEH = dict(M=3600.0 + 400.0,     # test vehicle + 2x200 kg ballast over the rear axle
           L=3.30, h_cg=0.95, h_hitch=0.55,
           M_lc=5200.0, F_rr_lc=800.0,   # load (dynamometer) car, rolls on the paved service road beside the plot
           x_rear=0.50)                 # static rear-axle share incl. ballast
G = 9.81
DT = 0.01                               # vehicle simulation step (100 Hz)
TERRAIN_FILE = "benchmarks/foreign5/lab_soil.toml"

# --------------------------------------------------------------------- cases
IN = ["none", "vasilev", "lyasko", "ding", "mismatch", "mismatch2", "wongreece",
      "drift_linear", "drift_step"]
OUT = ["strain_softening", "bead_slip", "encoder_steps", "ins_drift", "stones",
       "shear_cycling", "ridges"]
DEFAULTS = {
    "none": {},
    "vasilev": {"H": 0.03},
    "lyasko": {"m1": 0.25, "m2": 0.08},
    "ding": {"n1": 1.2},
    "mismatch": {"which": "k_eq", "factor": 0.45},        # which: k_eq|n|c|phi|K
    "mismatch2": {"phi_delta": -2.5, "K_factor": 1.35},
    "wongreece": {"a1": 0.10, "a2": 0.10},
    "drift_linear": {"which": "phi", "end_delta": -4.0},  # phi in deg; k_eq/K: end factor
    "drift_step": {"phi_delta": -2.5, "K_factor": 1.3, "at_frac": 0.5},
    "strain_softening": {"Kr": 0.70, "Kw": 0.030},
    "bead_slip": {"T_bead": 1900.0, "k_bead": 0.006},
    "encoder_steps": {"n_steps": 5, "step_deg": 2.0},
    "ins_drift": {"n_outages": 3, "outage_s": 16.0, "drift_mps2": 0.010},
    "stones": {"per_m": 0.6, "F_kN": 2.6, "length_m": 0.30},
    "shear_cycling": {"amp": 0.18, "lambda_m": 0.11},
    "ridges": {"period_m": 0.75, "keq_amp": 0.35, "W_amp": 0.07},
}
VERDICT = {"none": ["none"], "vasilev": ["slip_sinkage"], "lyasko": ["slip_sinkage"],
           "ding": ["slip_sinkage"], "mismatch": ["terrain_mismatch"],
           "mismatch2": ["terrain_mismatch"], "wongreece": ["stress_distribution"],
           "drift_linear": ["terrain_drift"], "drift_step": ["terrain_drift"],
           "strain_softening": ["unexplained"], "bead_slip": ["unexplained"],
           "encoder_steps": ["unexplained"], "ins_drift": ["unexplained"],
           "stones": ["unexplained"], "shear_cycling": ["unexplained", "none"],
           "ridges": ["unexplained", "none"]}
EFFECT = {"none": "none", "vasilev": "slip_sinkage:vasilev", "lyasko": "slip_sinkage:lyasko",
          "ding": "slip_sinkage:ding", "mismatch": "terrain_mismatch",
          "mismatch2": "terrain_mismatch", "wongreece": "stress_distribution:wong_reece",
          "drift_linear": "terrain_drift:linear", "drift_step": "terrain_drift:step"}
# log damage defaults (every run); override with --p
LOGDEF = {"gap_s": -1.0,        # <0: random 2-4 s; 0: no gap
          "clock_step_s": 0.0, "dup_rate": 3e-4, "n_error_frames": 8,
          "wft_loss": 6e-4, "extra_ids": 1, "gnss_latency_s": -1.0, "n_cycles": 5}


def parse_val(v):
    for f in (int, float):
        try:
            return f(v)
        except ValueError:
            pass
    return v


def load_lab(path=os.path.join(HERE, "lab_soil.toml")):
    with open(path, "rb") as fh:
        d = tomllib.load(fh)
    return d


# --------------------------------------------------------------- field soil
def modified(soil, b, **kw):
    s = dict(soil)
    if "k_eq_factor" in kw:
        s["kc"] *= kw["k_eq_factor"]; s["kphi"] *= kw["k_eq_factor"]
    if "n_delta" in kw:
        s["n"] += kw["n_delta"]
    if "c_delta_kpa" in kw:
        s["c"] += kw["c_delta_kpa"] * 1e3
    if "phi_delta" in kw:
        s["phi"] += math.radians(kw["phi_delta"])
    if "K_factor" in kw:
        s["K"] *= kw["K_factor"]
    return s


def mismatch_kw(which, factor):
    return {"k_eq": {"k_eq_factor": factor}, "n": {"n_delta": factor},
            "c": {"c_delta_kpa": factor}, "phi": {"phi_delta": factor},
            "K": {"K_factor": factor}}[which]


# ------------------------------------------------------------- procedure
def schedule(rng, n_cycles):
    """Driver/load-car command schedule: list of segments."""
    r = WHEEL["r"]
    s_free = 0.06
    vsets = rng.permutation([1.0, 1.3, 1.6, 1.9, 2.2, 1.45])[:n_cycles]
    segs = []
    t = 0.0
    segs.append(dict(kind="stand", t0=t, t1=t + 6.0)); t += 6.0
    w_prev = 0.0
    for k, v in enumerate(vsets):
        w_free = v / (r * (1 - s_free))
        dur = 4.0 if k == 0 else 3.0
        segs.append(dict(kind="free", t0=t, t1=t + dur, w0=w_prev, w1=w_free)); t += dur
        smax = float(rng.uniform(0.78, 0.85))
        tup = float(rng.uniform(14.0, 24.0))
        tdn = float(rng.uniform(5.0, 8.0))
        segs.append(dict(kind="settle", t0=t, t1=t + 2.5, V=v, s0=s_free, s1=0.08)); t += 2.5
        segs.append(dict(kind="up", t0=t, t1=t + tup, V=v, s0=0.08, s1=smax)); t += tup
        segs.append(dict(kind="hold", t0=t, t1=t + 1.5, V=v, s0=smax, s1=smax)); t += 1.5
        segs.append(dict(kind="down", t0=t, t1=t + tdn, V=v, s0=smax, s1=s_free)); t += tdn
        w_prev = w_free
    segs.append(dict(kind="stop", t0=t, t1=t + 4.0, V=float(vsets[-1]), w0=w_prev)); t += 4.0
    segs.append(dict(kind="stand", t0=t, t1=t + 4.0)); t += 4.0
    return segs, float(t)


def command(segs, t):
    """(omega_cmd, V_ref or None) at time t."""
    r = WHEEL["r"]
    for sg in segs:
        if sg["t0"] <= t < sg["t1"]:
            u = (t - sg["t0"]) / (sg["t1"] - sg["t0"])
            k = sg["kind"]
            if k == "stand":
                return 0.0, 0.0
            if k == "free":
                sm = 0.5 - 0.5 * math.cos(math.pi * min(1.0, u * 1.5))
                return sg["w0"] + (sg["w1"] - sg["w0"]) * sm, None
            if k in ("settle", "up", "hold", "down"):
                if k == "down":
                    u = 0.5 - 0.5 * math.cos(math.pi * u)
                s = sg["s0"] + (sg["s1"] - sg["s0"]) * u
                return sg["V"] / (r * (1 - s)), sg["V"]
            if k == "stop":
                f = max(0.0, 1.0 - 1.15 * u)
                return sg["w0"] * f, sg["V"] * f
    return 0.0, 0.0


# ------------------------------------------------------------- simulation
class Physics:
    """Field physics of the case: Dp, T and shear part for (s, W, x)."""

    def __init__(self, case, p, lab_soil):
        r, b = WHEEL["r"], WHEEL["b"]
        self.case = case; self.p = p
        model, mp, shear = "wong", None, None
        soil = dict(lab_soil)
        self.stations = None
        if case in ("vasilev", "lyasko", "ding", "wongreece"):
            model = case
            mp = {k: p[k] for k in {"vasilev": ["H"], "lyasko": ["m1", "m2"], "ding": ["n1"],
                                     "wongreece": ["a1", "a2"]}[case]}
        elif case == "mismatch":
            soil = modified(lab_soil, b, **mismatch_kw(p["which"], p["factor"]))
        elif case == "mismatch2":
            soil = modified(lab_soil, b, phi_delta=p["phi_delta"], K_factor=p["K_factor"])
        elif case == "strain_softening":
            shear = dict(kind="hump", Kr=p["Kr"], Kw=p["Kw"])
        self.model, self.mp, self.shear, self.soil = model, mp, shear, soil
        self.tab = terra.Table(soil, r, b, model, mp, shear)
        if case == "ridges":
            self.tab_lo = terra.Table(modified(lab_soil, b, k_eq_factor=1 - p["keq_amp"]), r, b)
            self.tab_hi = terra.Table(modified(lab_soil, b, k_eq_factor=1 + p["keq_amp"]), r, b)
        self.x_end = None

    def set_drift(self, x_end):
        """Drift cases: soil as a function of travelled distance x (m)."""
        r, b, p = WHEEL["r"], WHEEL["b"], self.p
        lab = self.soil
        self.x_end = x_end
        if self.case == "drift_linear":
            xs = np.linspace(0.0, x_end, 9)
            soils = []
            for f in np.linspace(0.0, 1.0, 9):
                w = p["which"]
                if w == "phi":
                    soils.append(modified(lab, b, phi_delta=f * p["end_delta"]))
                elif w == "k_eq":
                    soils.append(modified(lab, b, k_eq_factor=1 + f * (p["end_delta"] - 1)))
                elif w == "K":
                    soils.append(modified(lab, b, K_factor=1 + f * (p["end_delta"] - 1)))
                else:
                    raise SystemExit("drift_linear which must be phi|k_eq|K")
            self.stations = (xs, [terra.Table(s, r, b) for s in soils], soils)
        elif self.case == "drift_step":
            x0 = p["at_frac"] * x_end
            s2 = modified(lab, b, phi_delta=p["phi_delta"], K_factor=p["K_factor"])
            self.stations = (np.array([x0 - 0.4, x0 + 0.4]), [self.tab, terra.Table(s2, r, b)], [lab, s2])

    def __call__(self, s, W, x, what=("Dp", "T", "Dtau")):
        s = np.asarray(s, float); W = np.asarray(W, float); x = np.asarray(x, float)
        if self.stations is not None:
            xs, tabs, _ = self.stations
            xi = np.clip(x, xs[0], xs[-1])
            k = np.clip(np.searchsorted(xs, xi) - 1, 0, len(xs) - 2)
            u = (xi - xs[k]) / (xs[k + 1] - xs[k])
            out = [np.zeros(np.broadcast(s, W, x).shape) for _ in what]
            for kk in np.unique(k):
                m = k == kk
                a = tabs[kk](s[m] if s.ndim else s, W[m] if W.ndim else W, what)
                c = tabs[kk + 1](s[m] if s.ndim else s, W[m] if W.ndim else W, what)
                for o, aa, cc in zip(out, a, c):
                    o[m] = (1 - u[m]) * aa + u[m] * cc
            return out
        if self.case == "ridges":
            w = 0.5 * (1 + np.sin(2 * np.pi * x / self.p["period_m"]))
            a = self.tab_lo(s, W, what); c = self.tab_hi(s, W, what)
            return [(1 - w) * aa + w * cc for aa, cc in zip(a, c)]
        return self.tab(s, W, what)


def simulate(phys, segs, t_end, rng):
    """Vehicle at 100 Hz: V from traction of the four wheels against the load car."""
    r = WHEEL["r"]
    M, Mlc = VEH["M"], VEH["M_lc"]
    Wr0 = M * G * VEH["x_rear"] / 2; Wf0 = M * G * (1 - VEH["x_rear"]) / 2
    n = int(round(t_end / DT)) + 1
    T = np.arange(n) * DT
    V = np.zeros(n); X = np.zeros(n); OM = np.zeros(n); OMD = np.zeros(n)
    A = np.zeros(n); WR = np.zeros(n); WF = np.zeros(n); FB = np.zeros(n); H = np.zeros(n)
    v = x = om = integ = a_prev = 0.0
    tau_gov = 0.25
    Kp, Ki = 25000.0, 9000.0
    for i in range(n):
        t = T[i]
        wc, vref = command(segs, t)
        omd = (wc - om) / tau_gov
        # hitch force and load transfer (previous acceleration)
        if vref is None:
            fb = 0.0; integ = 0.0
        elif vref == 0.0 and v < 0.02:
            fb = None
        else:
            e = v - vref
            fb = Kp * e + integ
            if 0.0 < fb < 15000.0:
                integ += Ki * e * DT
            fb = min(max(fb, 0.0), 15000.0)
        hitch = (fb or 0.0) + VEH["F_rr_lc"] * (v > 0.01) + Mlc * a_prev
        dW = (hitch * VEH["h_hitch"] + M * a_prev * VEH["h_cg"]) / VEH["L"]
        wr = Wr0 + dW / 2; wf = Wf0 - dW / 2
        if om > 0.05 or v > 0.02:
            s = (r * om - v) / max(r * om, v, 0.05)
        else:
            s = 0.0
        dpr = phys.tab(s, wr, ("Dp",))[0] if phys.stations is None else phys(s, wr, x, ("Dp",))[0]
        dpf = phys.tab(s, wf, ("Dp",))[0] if phys.stations is None else phys(s, wf, x, ("Dp",))[0]
        ramp = min(1.0, max(r * om, v) / 0.05)       # forces vanish at standstill
        trac = 2 * (float(dpr) + float(dpf)) * ramp
        if fb is None:                               # parked: brakes hold
            acc = 0.0; v = 0.0
        else:
            acc = (trac - fb - VEH["F_rr_lc"] * (v > 0.01)) / (M + Mlc)
            if v <= 0.0 and acc < 0.0:
                acc = 0.0
        V[i], X[i], OM[i], OMD[i], A[i], WR[i], WF[i], FB[i], H[i] = v, x, om, omd, acc, wr, wf, fb or 0.0, hitch
        v = max(0.0, v + acc * DT); x += v * DT; om = max(0.0, om + omd * DT)
        a_prev = 0.9 * a_prev + 0.1 * acc
    return dict(t=T, V=V, x=X, om=OM, omd=OMD, a=A, Wr=WR, Wf=WF, Fb=FB, hitch=H)


# ------------------------------------------------------------- encoding helpers
def le16(vals, scale, signed=True):
    raw = np.round(np.asarray(vals) / scale).astype(np.int64)
    if signed:
        raw = np.clip(raw, -32768, 32767) & 0xFFFF
    else:
        raw = np.clip(raw, 0, 65535)
    return np.stack([raw & 0xFF, raw >> 8], axis=1).astype(np.uint8)


def gps_seconds(unix):
    return unix - 315964800.0 + 18.0


def main(argv=None):
    ap = argparse.ArgumentParser()
    ap.add_argument("case", choices=IN + OUT)
    ap.add_argument("--seed", type=int, required=True)
    ap.add_argument("--out", required=True)
    ap.add_argument("--outdir", required=True)
    ap.add_argument("--format", choices=["log", "asc", "blf", "trc"], default="log")
    ap.add_argument("--p", action="append", default=[], help="key=value")
    ap.add_argument("--debug", action="store_true", help="also write NAME_debug.npz (intended signals)")
    a = ap.parse_args(argv)
    t_wall = time.time()
    case = a.case
    p = dict(DEFAULTS[case]); lp = dict(LOGDEF)
    for kv in a.p:
        k, v = kv.split("=", 1)
        (lp if k in LOGDEF else p)[k] = parse_val(v)
    rng = np.random.default_rng(a.seed)
    r, b, mw, Iw = WHEEL["r"], WHEEL["b"], WHEEL["m"], WHEEL["I"]
    lab_d = load_lab()
    lab = terra.soil_from_field(lab_d)
    phys = Physics(case, p, lab)
    segs, t_end = schedule(rng, int(lp["n_cycles"]))
    if phys.case.startswith("drift"):
        # distance estimate: first pass without drift to get the run length
        phys.set_drift(1.0)
        phys.stations = None
        sim0 = simulate(phys, segs, t_end, np.random.default_rng(0))
        phys.set_drift(float(sim0["x"][-1]))
    # refuse runs where the vehicle cannot pull the load car
    soils = phys.stations[2] if phys.stations is not None else [phys.soil]
    Wr0 = VEH["M"] * G * VEH["x_rear"] / 2
    for so in soils:
        f = terra.forces(np.array([0.2, 0.3]), Wr0, so, r, b, phys.model, phys.mp, phys.shear)["Dp"]
        if 4 * f[0] < VEH["F_rr_lc"] + 200 or 4 * f[1] < VEH["F_rr_lc"] + 1500:
            raise SystemExit(f"refused: vehicle cannot pull the load car on this soil (4*Dp={4*f} N)")
    sim = simulate(phys, segs, t_end, rng)
    if phys.stations is not None:
        extra_drift = {"drift_station_time_host_rel_s": [float(np.interp(xx, sim["x"] + 1e-9 * np.arange(len(sim["x"])), sim["t"]))
                                                        for xx in phys.stations[0]]}
    else:
        extra_drift = {}

    # ---------------------------------------------------------- 500 Hz WFT samples
    ppm = rng.uniform(-50e-6, 50e-6)
    t_w0 = rng.uniform(0.0, 0.002)
    nS = int((t_end - 0.01) / 0.002)
    tw = t_w0 + np.arange(nS) * 0.002 * (1 + ppm)          # host-clock time of each sample
    ip = lambda key: np.interp(tw, sim["t"], sim[key])
    V, x, omh, omd, acc, Wr = ip("V"), ip("x"), ip("om"), ip("omd"), ip("a"), ip("Wr")
    # vertical dynamics: body bounce + lane roughness
    rough = np.convolve(rng.normal(0, 1, nS), np.ones(25) / 25, mode="same") * 5 * 120.0
    bounce = 0.022 * Wr * np.sin(2 * np.pi * 1.75 * tw + rng.uniform(0, 6.3)) * np.clip(V / 2.0, 0, 1)
    W = Wr + rough * np.clip(V / 1.0, 0, 1) + bounce
    if case == "ridges":
        W = W * (1 + p["W_amp"] * np.sin(2 * np.pi * x / p["period_m"] + 0.6))
    moving = np.clip(np.maximum(r * omh, V) / 0.05, 0, 1)
    om_t = omh.copy()                                        # tyre angular speed
    def slip(om):
        return np.where((om > 0.05) | (V > 0.02), (r * om - V) / np.maximum(np.maximum(r * om, V), 0.05), 0.0)
    Dp, Tq, Dtau = phys(slip(om_t), W, x)
    if case == "bead_slip":                                  # tyre slips on the rim above T_bead
        for _ in range(40):
            slip_rate = np.minimum(p["k_bead"] * np.maximum(Tq - p["T_bead"], 0.0), 0.4 * omh) * (V > 0.2)
            om_t = np.maximum(omh - slip_rate, 0.0) * 0.5 + om_t * 0.5
            Dp, Tq, Dtau = phys(slip(om_t), W, x)
    Dp = Dp * moving; Tq = Tq * moving; Dtau = Dtau * moving
    extra_truth = dict(extra_drift)
    if case == "shear_cycling":
        slipdist = np.cumsum(np.maximum(r * om_t - V, 0) * 0.002)
        ph = np.sin(2 * np.pi * slipdist / p["lambda_m"])
        Dp = Dp + p["amp"] * Dtau * ph
        Tq = Tq * (1 + p["amp"] * ph)
    if case == "stones":
        nst = rng.poisson(p["per_m"] * x[-1])
        xs = np.sort(rng.uniform(5.0, x[-1], nst))
        amp = rng.uniform(0.5, 1.5, nst) * p["F_kN"] * 1e3
        bump = np.zeros(nS)
        k0 = np.searchsorted(x, xs - p["length_m"] / 2); k1 = np.searchsorted(x, xs + p["length_m"] / 2)
        for j in range(nst):
            if k1[j] > k0[j]:
                u = (x[k0[j]:k1[j]] - (xs[j] - p["length_m"] / 2)) / p["length_m"]
                bump[k0[j]:k1[j]] += amp[j] * np.sin(np.pi * u)
        Dp = Dp - bump * np.sign(np.maximum(V, 0))
        W = W + 0.8 * bump
        Tq = Tq + 0.35 * r * bump
        extra_truth["n_stones"] = int(nst)
    Fx = Dp - mw * acc + rng.normal(0, 28.0, nS)
    Fz = W + rng.normal(0, 35.0, nS)
    My = Tq + Iw * omd + rng.normal(0, 5.0, nS)
    Fy = 60.0 + 0.02 * Dp + np.convolve(rng.normal(0, 1, nS), np.ones(50) / 50, "same") * 7 * 40 + rng.normal(0, 20.0, nS)
    Mx = -W * 0.025 + rng.normal(0, 6.0, nS)
    Mz = 0.03 * Dp + rng.normal(0, 5.0, nS)
    ang_true = np.degrees(np.cumsum(omh) * 0.002) + rng.uniform(0, 360)
    ca, sa = np.cos(np.radians(ang_true)), np.sin(np.radians(ang_true))
    Fx_w = ca * Fx - sa * Fz; Fz_w = sa * Fx + ca * Fz
    Mx_w = ca * Mx - sa * Mz; Mz_w = sa * Mx + ca * Mz
    ang_rep = ang_true.copy()
    if case == "encoder_steps":                               # encoder loses counts
        tk = np.sort(rng.uniform(25.0, t_end - 15.0, int(p["n_steps"])))
        dk = rng.choice([-1, 1], len(tk)) * p["step_deg"] * rng.uniform(0.7, 1.3, len(tk))
        for t0, d in zip(tk, dk):
            ang_rep[tw >= t0] += d
        extra_truth["encoder_steps"] = [[float(t0), float(d)] for t0, d in zip(tk, dk)]
    ang_rep = np.mod(ang_rep, 360.0)

    # ---------------------------------------------------------- host time base
    t0_host = 1795000000.0 + rng.uniform(0, 86400 * 20)
    frames = []   # (timestamp, channel, id, ext, bytes, err)

    def add(ts, ch, aid, ext, datas):
        for t_, d_ in zip(ts, datas):
            frames.append((float(t_), ch, aid, ext, bytes(d_), False))

    cnt = (np.arange(nS) % 256).astype(np.uint8)
    status = np.zeros(nS, np.uint8)
    over = (np.abs(Fx_w) > 16383.5) | (np.abs(Fy) > 16383.5) | (np.abs(Fz_w) > 32767) | (np.abs(My) > 8191.75)
    status[over] |= 1                                        # overload bit (values saturate)
    ffz = np.column_stack([le16(Fx_w, 0.5), le16(Fy, 0.5), le16(Fz_w, 1.0), cnt, status])
    fmo = np.column_stack([le16(Mx_w, 0.25), le16(My, 0.25), le16(Mz_w, 0.25), cnt, status])
    angraw = np.round(ang_rep / 0.0054931640625).astype(np.int64) % 65536
    fan = np.column_stack([(angraw & 0xFF).astype(np.uint8), (angraw >> 8).astype(np.uint8), cnt, status])
    jit = rng.exponential(4e-5, (nS, 3))
    base = tw + 3.5e-4
    keep = rng.random(nS) > lp["wft_loss"]                   # whole samples lost
    keepf = rng.random((nS, 3)) > lp["wft_loss"] / 3         # single frames lost
    for j, (aid, dat) in enumerate(((0x120, ffz), (0x121, fmo), (0x122, fan))):
        m = keep & keepf[:, j]
        add(base[m] + j * 1.3e-4 + jit[m, j], "can0", aid, False, dat[m])
    # WFT diag 1 Hz per mux value
    import cantools
    db = cantools.database.Database()
    for f in ("wft.dbc", "wheel_speed.dbc", "gps_rt_speedbox.dbc"):
        db.add_dbc_file(os.path.join("/work/shared/dbc", f))
    serial = int(rng.integers(100000, 999999))
    for k in range(int(t_end) - 1):
        for mux in range(3):
            sig = {0: dict(DiagMux=0, BridgeTemp=14.0 + 0.02 * k + rng.normal(0, 0.05), SupplyVoltage=12.1 + rng.normal(0, 0.01)),
                   1: dict(DiagMux=1, SerialNumber=serial),
                   2: dict(DiagMux=2, FirmwareMajor=3, FirmwareMinor=7, CalibrationId=4127)}[mux]
            add([0.3 + k + 0.0007 * mux], "can0", 0x123, False, [db.get_message_by_name("WFT_RL_Diag").encode(sig)])
    # wheel speeds 100 Hz (mean over the 10 ms window before the frame)
    tws = np.arange(0.013, t_end - 0.02, 0.01)
    cum = np.concatenate([[0.0], np.cumsum(sim["om"] * DT)])
    tc = np.concatenate([[-DT], sim["t"]]) + DT
    def om_mean(t1, t0):
        return (np.interp(t1, tc, cum) - np.interp(t0, tc, cum)) / (t1 - t0)
    om_rl = om_mean(tws, tws - 0.01)
    msg_ws = db.get_message_by_name("WSS_WheelSpeeds")
    rpm = lambda om_: np.clip(om_ * 60 / (2 * np.pi) + rng.normal(0, 0.04, len(tws)), 0, 655.35)
    sp = [rpm(om_rl * (1 + e)) for e in (0.004, -0.003, 0.0, 0.002)]
    keepw = rng.random(len(tws)) > 5e-4
    datas = [msg_ws.encode(dict(WheelSpeed_FL=a_, WheelSpeed_FR=b_, WheelSpeed_RL=c_, WheelSpeed_RR=d_))
             for a_, b_, c_, d_ in zip(*[np.round(q, 2) for q in sp])]
    add(tws[keepw] + 2.5e-4 + rng.exponential(6e-5, keepw.sum()), "can1", 0x300, False,
        [d for d, k in zip(datas, keepw) if k])
    msg_st = db.get_message_by_name("WSS_Status")
    tst = np.arange(0.047, t_end - 0.02, 0.1)
    add(tst, "can1", 0x301, False, [msg_st.encode(dict(RollingCounter=i % 16, SensorFault_FL=0, SensorFault_FR=0,
                                                         SensorFault_RL=0, SensorFault_RR=0)) for i in range(len(tst))])
    # ---------------------------------------------------------- GNSS / INS
    lat = lp["gnss_latency_s"] if lp["gnss_latency_s"] >= 0 else float(rng.uniform(0.04, 0.16))
    gps_off = float(rng.uniform(-0.6, 0.6))                  # receiver clock vs host (unknown)
    g0 = gps_seconds(t0_host) + gps_off
    first = math.ceil(g0 / 0.05) * 0.05
    fixg = first + np.arange(0, int((t_end - 0.5) / 0.05)) * 0.05      # GPS clock, fix epochs
    fix_h = fixg - g0                                         # host-relative time of the fix
    Vfix = np.interp(fix_h, sim["t"], sim["V"])
    Vmeas = Vfix + np.convolve(rng.normal(0, 1, len(fixg)), np.ones(3) / 3, "same") * 0.012
    nsv = np.full(len(fixg), 14)
    if case == "ins_drift":
        outs = []
        lo = 20.0
        for k in range(int(p["n_outages"])):
            t_o = float(rng.uniform(lo, lo + (t_end - 30 - lo) / (p["n_outages"] - k) - p["outage_s"]))
            outs.append(t_o); lo = t_o + p["outage_s"] + 5
            m = (fix_h >= t_o) & (fix_h < t_o + p["outage_s"])
            sgn = rng.choice([-1, 1])
            Vmeas[m] += sgn * p["drift_mps2"] * (fix_h[m] - t_o)
            nsv[m] = rng.integers(3, 5, m.sum())
        extra_truth["outages_host_rel_s"] = [[o, o + p["outage_s"]] for o in outs]
    Vmeas = np.where(Vfix < 0.005, np.abs(Vmeas) * 0.2, Vmeas)
    rx = fix_h + lat + rng.uniform(0.0005, 0.0025, len(fixg))
    keepg = rng.random(len(fixg)) > 2e-3
    m_sp = db.get_message_by_name("RT_SB_GPS_Speed")
    m_vb = db.get_message_by_name("RT_SB_INS_Vel_Body_Axes")
    m_tm = db.get_message_by_name("RT_SB_GPS_Time")
    side = rng.normal(0, 0.01, len(fixg))
    vz = rng.normal(0, 0.01, len(fixg))
    for i in np.nonzero(keepg)[0]:
        v2 = abs(Vmeas[i]); acc_f = 6 if nsv[i] > 8 else 40
        frames.append((float(rx[i]), "can1", m_sp.frame_id, True, bytes(m_sp.encode(dict(
            GPS_Speed_3D=round(math.hypot(v2, vz[i]), 4), GPS_Speed_2D=round(v2, 4), Accuracy_GPS_Speed=acc_f,
            Validity_GPS_Speed_3D=1, Validity_GPS_Speed_2D=1))), False))
        frames.append((float(rx[i] + 3e-4), "can1", m_vb.frame_id, True, bytes(m_vb.encode(dict(
            INS_Vel_Sideways_2D=round(side[i], 4), INS_Vel_Forwards_2D=round(Vmeas[i], 4), Accuracy_INS_Vel_Body=acc_f,
            Validity_INS_Vel_Sideways=1, Validity_INS_Vel_Forwards=1))), False))
        wk = int(fixg[i] // 604800); tow = fixg[i] - wk * 604800
        frames.append((float(rx[i] + 6e-4), "can1", m_tm.frame_id, True, bytes(m_tm.encode(dict(
            GPS_Week=wk, GPS_Time=round(tow, 3), Accuracy_GPS_Time=2, Validity_GPS_Week=1, Validity_GPS_Time=1))), False))
    m_gs = db.get_message_by_name("RT_SB_GPS_Status")
    for k in range(int(t_end) - 1):
        i = min(int(k / 0.05), len(nsv) - 1)
        frames.append((k + 0.61, "can1", m_gs.frame_id, True, bytes(m_gs.encode(dict(
            RTK_Status=3 if nsv[i] > 8 else 1, GPS_nSv_RTK=int(nsv[i]) - 2 if nsv[i] > 8 else 0, GPS_nSv_2=int(nsv[i]) - 1,
            GPS_nSv=int(nsv[i]), Firmware_Version_Minor=12, Firmware_Version_Intermediate=3, Firmware_Version_Major=2,
            GPS_Status=12 if nsv[i] > 8 else 11))), False))
    # ---------------------------------------------------------- other ECUs, damage
    dmg = {}
    if lp["extra_ids"]:
        te = np.arange(0.005, t_end, 0.01)                    # engine ECU, J1939 EEC1 100 Hz
        rpm_e = 900 + 2400 * np.interp(te, sim["t"], sim["om"]) / 30
        raw = np.clip(rpm_e / 0.125, 0, 65535).astype(int)
        add(te, "can1", 0x0CF00400, True, [bytes([0xF0, 0x7D, 0x82, r_ & 0xFF, r_ >> 8, 0, 0xF0, 0xFF]) for r_ in raw])
        tb = np.arange(0.021, t_end, 0.1)                     # body controller 10 Hz
        add(tb, "can1", 0x5A0, False, [bytes([i & 0xFF, 0x11, 0, 0]) for i in range(len(tb))])
        tc1 = np.arange(0.4, t_end, 1.0)                      # ambient temperature 1 Hz
        add(tc1, "can1", 0x18FEF500, True, [bytes([0xFF] * 3 + [0x60, 0x26, 0xFF, 0xFF, 0xFF]) for _ in tc1])
        th = np.arange(0.77, t_end, 1.0)                      # a WFT amplifier heartbeat on can0
        add(th, "can0", 0x70A, False, [bytes([0x05]) for _ in th])
        tq = np.arange(0.033, t_end, 0.1)                     # unknown 10 Hz id on can0
        add(tq, "can0", 0x1F0, False, [bytes([(i * 7) & 0xFF, 0, 0, 0, 0, 0]) for i in range(len(tq))])
        dmg["extra_ids"] = {"can0": ["0x1F0", "0x70A"], "can1": ["0x5A0", "0x0CF00400x", "0x18FEF500x"]}
    frames.sort(key=lambda f: f[0])
    # duplicated frames (adapter re-delivers)
    ndup = rng.binomial(len(frames), lp["dup_rate"])
    idx = rng.choice(len(frames), ndup, replace=False)
    for i in idx:
        f = frames[i]
        frames.append((f[0] + 2e-5, f[1], f[2], f[3], f[4], f[5]))
    dmg["duplicates"] = int(ndup)
    # error frames
    te = rng.uniform(5, t_end - 5, int(lp["n_error_frames"]))
    for t_ in te:
        frames.append((float(t_), "can1" if rng.random() < 0.7 else "can0", 0, False, b"", True))
    dmg["error_frames"] = int(len(te))
    frames.sort(key=lambda f: f[0])
    # logging gap (logger stall: nothing recorded on either bus)
    gap = lp["gap_s"] if lp["gap_s"] >= 0 else float(rng.uniform(2.0, 4.0))
    if gap > 0:
        g0t = float(rng.uniform(40.0, t_end - 40.0))
        frames = [f for f in frames if not (g0t <= f[0] < g0t + gap)]
        dmg["gap_host_rel_s"] = [g0t, g0t + gap]
    # host clock step (NTP slew-less correction), forward
    if lp["clock_step_s"]:
        cst = float(rng.uniform(50.0, t_end - 50.0))
        frames = [(f[0] + (lp["clock_step_s"] if f[0] >= cst else 0.0),) + f[1:] for f in frames]
        dmg["clock_step"] = {"at_host_rel_s": cst, "step_s": lp["clock_step_s"]}
    dmg["wft_sample_loss_rate"] = lp["wft_loss"]

    # ---------------------------------------------------------- write
    import can
    os.makedirs(a.outdir, exist_ok=True)
    path = os.path.join(a.outdir, f"{a.out}.{a.format}")
    W_ = {"log": can.CanutilsLogWriter, "asc": can.ASCWriter, "blf": can.BLFWriter, "trc": can.TRCWriter}[a.format]
    wr = W_(path)
    for ts, ch, aid, ext, data, err in frames:
        if err:
            msg = can.Message(timestamp=t0_host + ts, channel=ch, is_error_frame=True, dlc=0)
        else:
            msg = can.Message(timestamp=t0_host + ts, arbitration_id=aid, is_extended_id=ext,
                              data=data, channel=ch, is_rx=True)
        wr.on_message_received(msg)
    wr.stop()

    if a.debug:
        np.savez_compressed(os.path.join(a.outdir, f"{a.out}_debug.npz"), t_host0=t0_host, tw=tw, cnt=cnt,
                            Fx=Fx, Fz=Fz, Fx_w=Fx_w, Fz_w=Fz_w, My=My, Fy=Fy, ang=np.mod(ang_rep, 360), Dp=Dp, T=Tq, W=W, V=V, om=omh,
                            om_t=om_t, acc=acc, omd=omd, tws=tws, rpm_rl=sp[2], fixg=fixg, fix_h=fix_h, Vmeas=Vmeas,
                            rx=rx, lat=lat, keep=keep & keepf.all(axis=1), x=x, sim_t=sim["t"], sim_Fb=sim["Fb"],
                            sim_V=sim["V"], sim_om=sim["om"])
    # ---------------------------------------------------------- truth
    s_meas = np.where(omh > 0.5, (r * omh - V) / np.maximum(r * omh, 1e-6), np.nan)
    mv = (V > 0.3) & (omh > 1.0)
    truth = dict(
        generator="foreign5", case=case, effect=EFFECT.get(case, "out_of_family:" + case),
        in_family=case in IN, params=p, log_params=lp, acceptable_verdicts=VERDICT[case],
        seed=a.seed, format=a.format, log_file=os.path.basename(path),
        terrain_file=TERRAIN_FILE,
        fit_command=(f"wheelsoil fit {path} --terrain {TERRAIN_FILE} --wheel-radius {r} --wheel-width {b} "
                     f"--wheel-mass {mw} --wheel-inertia {Iw}"),
        wheel=dict(radius_m=r, width_m=b, mass_kg=mw, inertia_kgm2=Iw),
        wheel_radius=r, wheel_width=b, wheel_mass=mw, wheel_inertia=Iw,
        gnss_latency_s=lat, gps_clock_offset_s=gps_off, wft_clock_ppm=ppm * 1e6,
        host_t0=t0_host, duration_s=t_end, first_frame_unix=t0_host + frames[0][0],
        channels={"can0": "WFT (asc/blf/trc channel 1)", "can1": "WSS + GNSS (asc/blf/trc channel 2)"},
        lab_soil=terra.soil_to_field(lab),
        field_soil=terra.soil_to_field(phys.soil) if phys.stations is None else
        [dict(x_m=float(xx), **terra.soil_to_field(ss)) for xx, ss in zip(phys.stations[0], phys.stations[2])],
        slip_range=[float(np.nanpercentile(s_meas[mv], 1)), float(np.nanpercentile(s_meas[mv], 99))],
        rl_load_N=dict(mean=float(W[mv].mean()), min=float(W[mv].min()), max=float(W[mv].max())),
        distance_m=float(x[-1]), damage=dmg, **extra_truth)
    truth.update(size_at_s05(case, p, lab, phys, float(W[mv].mean()), truth))
    truth["gen_seconds"] = round(time.time() - t_wall, 2)
    with open(os.path.join(a.outdir, f"{a.out}_truth.json"), "w") as fh:
        json.dump(truth, fh, indent=1, default=float)
    print(f"{path}: {len(frames)} frames, {t_end:.0f} s, slip {truth['slip_range'][0]:.2f}-{truth['slip_range'][1]:.2f}, "
          f"dDp(0.5)={truth['dp_change_s05_pct']}%, {truth['gen_seconds']} s")


def size_at_s05(case, p, lab, phys, Wm, truth):
    """Relative change of Dp at s = 0.5 (and 0.3) vs. the lab soil with Wong's model."""
    r, b = WHEEL["r"], WHEEL["b"]
    ss = np.array([0.3, 0.5])
    base = terra.forces(ss, Wm, lab, r, b)["Dp"]
    note = "field physics vs lab Wong, at the mean RL load"
    if phys.stations is not None:
        so = phys.stations[2][-1]
        dp = terra.forces(ss, Wm, so, r, b)["Dp"]; note = "soil at the end of the run vs lab"
    elif case in IN or case in ("strain_softening",):
        dp = terra.forces(ss, Wm, phys.soil, r, b, phys.model, phys.mp, phys.shear)["Dp"]
    elif case == "ridges":
        dp = 0.5 * (phys.tab_lo(ss, Wm)[0] + phys.tab_hi(ss, Wm)[0]); note = "mean over ridge/furrow (plus ripple)"
    elif case == "bead_slip":
        # measured slip 0.5 -> true slip lower: Dp at true slip
        sm = ss; st = sm.copy(); Vr = 1.6
        omh = Vr / (r * (1 - sm))
        for _ in range(80):
            T = terra.forces(st, Wm, lab, r, b)["T"]
            omt = omh - p["k_bead"] * np.maximum(T - p["T_bead"], 0)
            st = 0.5 * st + 0.5 * (1 - Vr / (r * omt))
        dp = terra.forces(st, Wm, lab, r, b)["Dp"]; note = "Dp at the tyre's true slip when the hub slip reads 0.3/0.5 (V 1.6 m/s)"
    elif case == "encoder_steps":
        steps = np.cumsum([d for _, d in truth.get("encoder_steps", [])])
        mx = float(np.max(np.abs(steps))) if len(steps) else 0.0
        dp = base - Wm * math.sin(math.radians(mx)); note = f"worst apparent bias, max |angle error| {mx:.1f} deg (sign varies)"
    elif case == "stones":
        dp = base - p["F_kN"] * 1e3 * p["per_m"] * p["length_m"] * 2 / math.pi; note = "mean extra resistance"
    elif case == "ins_drift":
        dv = p["drift_mps2"] * p["outage_s"]
        dp = base * np.nan; note = f"during outages V error up to {dv:.2f} m/s (slip error up to ~{dv/1.6:.2f}); outside: 0"
    else:
        dp = base; note = "zero-mean ripple"
    rel = (dp - base) / base * 100
    return dict(dp_change_s05_pct=None if np.isnan(rel[1]) else round(float(rel[1]), 1),
                dp_change_s03_pct=None if np.isnan(rel[0]) else round(float(rel[0]), 1),
                dp_lab_s05_N=round(float(base[1]), 1), dp_change_note=note)


if __name__ == "__main__":
    main()
