#!/usr/bin/env python
"""Self-check of the generator's cases (not used by gen.py): for a case's noise-free table,
how visible is it against lab soil + Wong, and how well can the IN-FAMILY hypotheses
(terrain mismatch in 1-2 parameters, Vasil'ev, Lyasko, Ding, Wong-Reece) mimic it?

usage: mimic.py ROUND.json [name ...]
Prints per case: rms of (effect - lab Wong) in noise sigmas ('visible'), and the best in-family
hypothesis with its rms residual in noise sigmas.  'z' = chi2 excess over the N residuals in units of sqrt(2N).  An out-of-family case with a small best
residual (z < 8) would be a case the in-family list could explain; such a case is flagged.
"""
import itertools
import json
import math
import sys

import numpy as np
from scipy.optimize import least_squares

import gen
import terra
from gen import WHEEL, SOILS, lab_soil

SL = [0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 0.9]


def table(case, p, key, loads):
    rows = []
    for W in loads:
        for s in SL:
            Z, Dp, T = gen.noise_free(case, p, key, W, s)
            rows.append((W, s, Z, Dp, T))
    return np.array(rows)


def sig(tab):
    W, Dp, T, Z = tab[:, 0], tab[:, 3], tab[:, 4], tab[:, 2]
    return (0.008 * W + 0.03 * abs(Dp), 0.008 * W * WHEEL.r + 0.02 * abs(T), 0.0004 + 0.03 * abs(Z))


def resid(model_tab, tab, use_T, use_Z):
    sD, sT, sZ = sig(tab)
    r = [(model_tab[:, 3] - tab[:, 3]) / sD]
    if use_T:
        r.append((model_tab[:, 4] - tab[:, 4]) / sT)
    if use_Z:
        r.append((model_tab[:, 2] - tab[:, 2]) / sZ)
    return np.concatenate(r)


PKEYS = ["k", "n", "c", "phi", "K"]


def mm_change(x, keys):
    ch = {}
    for k, v in zip(keys, x):
        if k == "k":
            ch["k_rel"] = math.exp(v) - 1
        elif k == "n":
            ch["dn"] = v
        elif k == "c":
            ch["dc_kpa"] = v
        elif k == "phi":
            ch["dphi_deg"] = v
        elif k == "K":
            ch["K_rel"] = math.exp(v) - 1
    return ch


def hyps(key):
    c0 = SOILS[key]["lab"]["c_kpa"]
    out = []
    for pair in itertools.combinations(PKEYS, 2):
        lo = {"k": -1.5, "n": -0.4, "c": -c0 + 0.01, "phi": -12, "K": -1.5}
        hi = {"k": 1.5, "n": 0.4, "c": 8, "phi": 12, "K": 1.5}
        out.append(("mismatch:" + "+".join(pair), "terrain_mismatch",
                    lambda x, pair=pair: {"change": mm_change(x, pair)},
                    [0.0, 0.0], ([lo[k] for k in pair], [hi[k] for k in pair])))
    out.append(("vasilev", "vasilev", lambda x: {"H": x[0]}, [0.005], ([-0.02], [0.2])))
    out.append(("lyasko", "lyasko", lambda x: {"m1": x[0], "m2": x[1]}, [0.1, 0.02], ([-0.9, -0.5], [5.0, 0.9])))
    out.append(("ding", "ding", lambda x: {"n1": x[0]}, [0.05], ([-0.5], [1.5])))
    out.append(("wong-reece", "stress_distribution", lambda x: {"a1": x[0], "a2": x[1]}, [0.2, 0.05],
                ([0.01, 0.0], [0.6, 0.5])))
    return out


def analyse(entry):
    case, p = entry["case"], dict(gen.DEFAULTS)
    p.update(entry["params"])
    key = p["soil"]
    loads = p["loads"] or list(SOILS[key]["loads"])
    use_T, use_Z = bool(p["torque"]), bool(p["sinkage"])
    tab = table(case, p, key, loads)
    lab = table("none", {}, key, loads)
    vis = np.sqrt(np.mean(resid(lab, tab, use_T, use_Z) ** 2))
    best = (None, np.inf, None)
    for nm, hc, mk, x0, bnds in hyps(key):
        def f(x):
            try:
                return resid(table(hc, mk(x), key, loads), tab, use_T, use_Z)
            except Exception:
                return np.full(len(tab) * (1 + use_T + use_Z), 1e3)
        try:
            r = least_squares(f, x0, bounds=bnds, diff_step=1e-3, max_nfev=60)
        except Exception:
            continue
        rms = np.sqrt(np.mean(r.fun ** 2))
        if rms < best[1]:
            best = (nm, rms, r.x)
    nres = len(tab) * (1 + use_T + use_Z)
    return vis, best, nres


def main():
    rnd = json.load(open(sys.argv[1]))
    names = set(sys.argv[2:])
    for e in rnd:
        if names and e["name"] not in names:
            continue
        vis, (nm, rms, x), N = analyse(e)
        zv, zb = vis ** 2 * N / math.sqrt(2 * N), rms ** 2 * N / math.sqrt(2 * N)
        fam = "in" if e["case"] in gen.IN_FAMILY else "out"
        flag = ""
        if fam == "out" and zb < 8 and zv > 8:
            flag = "  <-- mimicked by in-family"
        if zv < 8 and e["case"] != "none":
            flag += "  (small: z < 8)"
        print(f"{e['name']:10s} {e['case']:20s} {fam:3s} N={N:3d} visible={vis:6.2f} (z={zv:6.1f})  best={nm:22s} rms={rms:6.2f} (z={zb:6.1f}) "
              f"x={np.round(x, 3).tolist() if x is not None else None}{flag}", flush=True)


if __name__ == "__main__":
    main()
