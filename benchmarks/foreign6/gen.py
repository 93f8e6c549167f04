#!/usr/bin/env python
"""foreign6: synthetic single-wheel soil-bin testbed tables.

usage: gen.py CASE --seed S --out NAME --outdir DIR [--p key=value ...]

Written only from the seed paper, /work/shared/hardware.md and the CMU data set.
See README.md for the soil, wheel, protocol, noise and effect models.
"""
from __future__ import annotations

import argparse
import csv
import json
import math
import os
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import terra  # noqa: E402
from terra import Soil, Wheel, Bekker, Reload  # noqa: E402

HERE = os.path.dirname(os.path.abspath(__file__))
MAIN = "/work/main"

# ----------------------------------------------------------------------------- rig
WHEEL = Wheel(r=0.200, b=0.125)     # rigid aluminium wheel, D = 400 mm, b = 125 mm
CARRIAGE_V = 0.05                   # m/s carriage speed (slip set by the wheel drive)

# ----------------------------------------------------------------------------- soils
SOILS = {
    "A": dict(
        toml="lab_soil.toml",
        name="silty clay loam, 18 % moisture, soil bin (lab, 60/100 mm plate sinkage and 100 mm shear-ring tests)",
        lab=dict(c_kpa=3.5, phi_deg=24.0, K_m=0.022, n=0.80, kc=40.0, kphi=950.0),
        unc=dict(k_eq_rel=0.15, n=0.04, c_kpa=0.6, phi_deg=1.5, K_m=0.004),
        source=("Bevameter in the prepared bin before the test series: two plate sizes (60 x 250 mm and "
                "100 x 250 mm, 3 penetrations each) fitted to Bekker's law; annular shear ring (r = 50/100 mm) at "
                "4 normal pressures for c, phi and K. 1-sigma from the scatter of 3 re-preparations of the bin and "
                "the fit covariance."),
        gamma=15.5e3,
        loads=(300.0, 600.0, 900.0, 1200.0),
    ),
    "B": dict(
        toml="lab_soil_sand.toml",
        name="air-dry medium quartz sand, loosely poured and levelled (lab, plate and shear-box tests)",
        lab=dict(c_kpa=0.6, phi_deg=31.5, K_m=0.014, n=1.05, kc=0.9, kphi=1650.0),
        unc=dict(k_eq_rel=0.20, n=0.06, c_kpa=0.3, phi_deg=1.2, K_m=0.004),
        source=("Two rectangular plates (60 x 200 and 100 x 200 mm, 3 penetrations each, bin re-raked between) "
                "fitted to Bekker's law; 60 mm direct shear box at 5, 10, 20 kPa for c, phi, K (Janosi fit). "
                "1-sigma from the repeat scatter; kc is poorly determined for this dry sand."),
        gamma=15.0e3,
        loads=(150.0, 300.0, 450.0, 600.0),
    ),
}


def lab_soil(key):
    L = SOILS[key]["lab"]
    return Soil.from_lab(L["c_kpa"], L["phi_deg"], L["K_m"], L["n"], L["kc"], L["kphi"])


def write_toml(key):
    S = SOILS[key]
    L, U = S["lab"], S["unc"]
    txt = f'''name = "{S['name']}"
c_kpa = {L['c_kpa']}
phi_deg = {L['phi_deg']}
K_m = {L['K_m']}
n = {L['n']}
kc = {L['kc']}      # kN/m^(n+1)
kphi = {L['kphi']} # kN/m^(n+2)

[uncertainty]
# one standard deviation of the lab values
k_eq_rel = {U['k_eq_rel']}   # fraction of (kc/b + kphi)
n = {U['n']}
c_kpa = {U['c_kpa']}
phi_deg = {U['phi_deg']}
K_m = {U['K_m']}
source = "{S['source']}"
'''
    with open(os.path.join(HERE, S["toml"]), "w") as f:
        f.write(txt)


# ----------------------------------------------------------------------------- cases
IN_FAMILY = {"none", "vasilev", "lyasko", "ding", "terrain_mismatch", "stress_distribution"}
OUT_FAMILY = {"crosstalk", "bearing_torque", "shear_peak", "bulldozing", "sinkage_datum",
              "flexible_tyre", "multipass", "load_transfer", "rate_effect"}
ALL_CASES = IN_FAMILY | OUT_FAMILY

DEFAULTS = dict(
    soil="A", loads=None, slips=[0.05, 0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 0.9],
    repeats=1, torque=True, sinkage=True, order="random", noise=1.0,
)


def mismatch_soil(soil, p, b):
    """Apply a terrain mismatch: keys k_rel (kc and kphi together), kc_rel, kphi_rel,
    dn, dc_kpa, dphi_deg, K_rel."""
    kc, kphi = soil.kc, soil.kphi
    if "k_rel" in p:
        kc *= 1 + p["k_rel"]
        kphi *= 1 + p["k_rel"]
    if "kc_rel" in p:
        kc *= 1 + p["kc_rel"]
    if "kphi_rel" in p:
        kphi *= 1 + p["kphi_rel"]
    n = soil.n + p.get("dn", 0.0)
    if "dn" in p:
        # keep the plate-test pressure at the lab's mean plate sinkage (about 25 mm) when n
        # changes: a soil whose curve has another shape, not another level
        zr = 0.025
        f = zr ** soil.n / zr ** n
        kc *= f
        kphi *= f
    c = soil.c + p.get("dc_kpa", 0.0) * 1e3
    phi = soil.phi + math.radians(p.get("dphi_deg", 0.0))
    K = soil.K * (1 + p.get("K_rel", 0.0))
    return Soil(c, phi, K, n, kc, kphi)


def physics(case, p, soil, W, s, key):
    """True (noise-free) soil response: returns (sinkage, Dp, T) for true load W and slip s,
    on the given (bin) soil, BEFORE any measurement-chain effect."""
    wh = WHEEL
    if case in ("none", "crosstalk", "bearing_torque", "sinkage_datum", "load_transfer"):
        Z = terra.solve_sinkage(W, s, wh, soil)
        _, Dp, T = terra.forces(Z, s, wh, soil)
        return Z, Dp, T
    if case == "terrain_mismatch":
        so = mismatch_soil(soil, p["change"], wh.b)
        Z = terra.solve_sinkage(W, s, wh, so)
        _, Dp, T = terra.forces(Z, s, wh, so)
        return Z, Dp, T
    if case in ("vasilev", "lyasko"):
        Z0 = terra.solve_sinkage(W, s, wh, soil)
        if case == "vasilev":
            Z = Z0 + p["H"] * s
        else:
            Z = (1 + p["m1"] * s) / (1 - p["m2"] * s) * Z0
        _, Dp, T = terra.forces(Z, s, wh, soil)
        return Z, Dp, T
    if case == "ding":
        so = soil.with_(n=soil.n + p["n1"] * s)
        Z = terra.solve_sinkage(W, s, wh, so)
        _, Dp, T = terra.forces(Z, s, wh, so)
        return Z, Dp, T
    if case == "stress_distribution":
        dist = ("wr", p["a1"], p["a2"])
        Z = terra.solve_sinkage(W, s, wh, soil, dist=dist)
        _, Dp, T = terra.forces(Z, s, wh, soil, dist=dist)
        return Z, Dp, T
    if case == "shear_peak":
        sh = ("peak", p["Kr"], p["Kw_rel"] * soil.K)
        Z = terra.solve_sinkage(W, s, wh, soil, shear=sh)
        _, Dp, T = terra.forces(Z, s, wh, soil, shear=sh)
        return Z, Dp, T
    if case == "rate_effect":
        vs = s * CARRIAGE_V / max(1 - s, 1e-3)
        vref = 0.1 * CARRIAGE_V / 0.9
        m = max(1.0 + p["beta"] * math.log10(max(vs, 1e-6) / vref), 0.85)
        Z = terra.solve_sinkage(W, s, wh, soil, tau_mult=m)
        _, Dp, T = terra.forces(Z, s, wh, soil, tau_mult=m)
        return Z, Dp, T
    if case == "bulldozing":
        Z = terra.solve_sinkage(W, s, wh, soil)
        _, Dp, T = terra.forces(Z, s, wh, soil)
        Kp = math.tan(math.pi / 4 + soil.phi / 2) ** 2
        gamma = SOILS[key]["gamma"]
        Rb = p["zeta"] * wh.b * (0.5 * gamma * Z * Z * Kp + 2.0 * soil.c * Z * math.sqrt(Kp))
        return Z, Dp - Rb, T
    if case == "flexible_tyre":
        Z, _, Dp, T, _ = terra.flexible_solve(W, s, wh, soil, p["pg_kpa"] * 1e3)
        return Z, Dp, T
    if case == "multipass":
        Z1 = terra.solve_sinkage(W, p["s_prev"], wh, soil)
        law = Reload(soil.keq(wh.b), soil.n, Z1, p["Au"] * Z1)
        Z = terra.solve_sinkage(W, s, wh, soil, law=law)
        _, Dp, T = terra.forces(Z, s, wh, soil, law=law)
        return Z, Dp, T
    raise ValueError(case)


def measure_chain(case, p, W, s, Z, Dp, T):
    """Measurement-chain effects (applied to the true response)."""
    if case == "crosstalk":
        Dp = Dp + p["kappa"] * W
    elif case == "bearing_torque":
        T = T + p["T0"] + p["Tv"] / (1.0 - s)
    elif case == "sinkage_datum":
        Z = Z + p["dz"]
    return Z, Dp, T


def true_soil_for_case(case, p, key, rng):
    soil = lab_soil(key)
    if case == "none":
        # the bin soil differs from the lab values by a fraction of their 1-sigma
        U = SOILS[key]["unc"]
        f = float(p.get("lab_offset", 0.4))
        d = np.clip(rng.normal(0.0, f, 5), -1.0, 1.0)
        kk = 1 + d[0] * U["k_eq_rel"]
        soil = Soil(soil.c + d[3] * U["c_kpa"] * 1e3 if soil.c + d[3] * U["c_kpa"] * 1e3 > 0 else soil.c,
                    soil.phi + math.radians(d[4] * U["phi_deg"]),
                    soil.K + d[2] * U["K_m"] * 0.5,
                    soil.n + d[1] * U["n"], soil.kc * kk, soil.kphi * kk)
    return soil


def prep_bias(soil, rng, scale):
    """Soil of one bin preparation: small random variation around the bin's soil."""
    kk = math.exp(rng.normal(0, 0.05 * scale))
    return Soil(max(soil.c * (1 + rng.normal(0, 0.05 * scale)), 0.0),
                soil.phi + math.radians(rng.normal(0, 0.35 * scale)),
                soil.K * (1 + rng.normal(0, 0.05 * scale)),
                soil.n + rng.normal(0, 0.01 * scale),
                soil.kc * kk, soil.kphi * kk)


def noise_free(case, p, key, W, s, soil=None):
    soil = lab_soil(key) if soil is None else soil
    if case == "load_transfer":
        # the load is measured, so the model at the measured load is exact
        pass
    Z, Dp, T = physics(case, p, soil, W, s, key)
    return measure_chain(case, p, W, s, Z, Dp, T)


# ----------------------------------------------------------------------------- truth text
VERDICTS = {
    "none": ["none"], "vasilev": ["slip_sinkage"], "lyasko": ["slip_sinkage"], "ding": ["slip_sinkage"],
    "terrain_mismatch": ["terrain_mismatch"], "stress_distribution": ["stress_distribution"],
}

NOTES = {
    "none": "Wong's rigid-wheel model on the bin soil; the bin soil differs from the lab values by a fraction "
            "(<= 1 sigma) of their stated uncertainty, plus the per-preparation variation.",
    "vasilev": "Slip sinkage, Vasil'ev Eq. 11: Z = Z0 + H s, Z0 = the force-balance sinkage of Wong's model at the "
               "same load and slip; Dp and T from Eqs. 8-9 at Z.",
    "lyasko": "Slip sinkage, Lyasko Eq. 12: Z = (1 + m1 s)/(1 - m2 s) Z0; Dp and T from Eqs. 8-9 at Z.",
    "ding": "Slip sinkage, Ding Eq. 13: exponent N = n + n1 s in the pressure law; sinkage from the vertical "
            "force balance (dead-weight rig) with N; Dp and T with N.",
    "terrain_mismatch": "The prepared bin's soil differs from the lab values beyond their uncertainty in the listed "
                        "parameter(s); Wong's model otherwise exact.",
    "stress_distribution": "Wong-Reece normal stress: maximum at theta_m = (a1 + a2 s) theta1, front region Bekker "
                           "of Eq. 2-3, rear region mapped onto the front (sigma -> 0 at theta2 = 0); sinkage "
                           "from the vertical force balance.",
    "crosstalk": "Load-cell cross-talk / misalignment: the drawbar-pull channel reads Dp + kappa * W (vertical "
                 "load leaks into the horizontal channel, e.g. a 1-3 deg tilted 6-axis cell or a bin rail not "
                 "level). Torque and sinkage are unaffected. No soil hypothesis moves Dp by a slip-independent "
                 "amount proportional to W while leaving T and sinkage unchanged.",
    "bearing_torque": "The torque transducer sits between the drive motor and the axle bearings/seals: it reads "
                      "T + T0 + Tv/(1-s) (Coulomb seal friction plus a viscous part growing with wheel speed; the "
                      "carriage speed is fixed so omega ~ 1/(1-s)). Dp and sinkage are unaffected; torque exceeds "
                      "the soil torque everywhere, even at slip 0.",
    "shear_peak": "The soil has a peaked (hump) shear curve (Wong's dense-soil curve): tau reaches the "
                  "Mohr-Coulomb strength at j = Kw and falls to Kr times it at large j. Dp rises, peaks and falls "
                  "with slip while the sinkage does NOT grow with slip; Janosi's exponential curve cannot do this.",
    "bulldozing": "A soil wedge is pushed ahead of the wheel (bulldozing, Bekker): extra resistance "
                  "Rb = zeta b (0.5 gamma z^2 Kp + 2 c z sqrt(Kp)), Kp = tan^2(45 + phi/2), acting through the "
                  "axle: it lowers Dp at every slip by an amount set by the sinkage only, leaves T and sinkage "
                  "unchanged.",
    "sinkage_datum": "The sinkage sensor's zero was set on an uneven/loosened surface: every sinkage reading is "
                     "offset by dz. Dp and T are exact. (The CMU set itself has a hard-coded sinkage datum.)",
    "flexible_tyre": "The wheel is a low-pressure pneumatic tyre, not rigid: where the rigid-wheel peak pressure "
                     "would exceed pg (inflation + carcass), the tyre flattens (Wong's elastic mode): sinkage "
                     "(pg/k)^(1/n), independent of load, a flat contact of uniform pressure pg, less compaction "
                     "resistance. The sidecar radius is the undeflected radius.",
    "multipass": "The bin was not re-prepared: each test pass runs in the rut left by a previous pass at the same "
                 "load and slip s_prev. The soil reloads along an unload-reload line (slope ku = Au z1, Wong) up to "
                 "the previous depth, then the virgin Bekker curve. Sinkage is measured from the original "
                 "(prepared) surface, so it is as large as a single pass's while the compaction resistance is much "
                 "smaller: Dp higher with no loss of sinkage.",
    "load_transfer": "The loading arm is pivoted: the vertical load on the wheel drops with drawbar pull "
                     "(W = W_dead - lam Dp). The load cell measures the actual W, so the measured inputs already "
                     "absorb it: the model at the measured load is exact ('none' acceptable).",
    "rate_effect": "Rate-dependent shear strength of the moist cohesive soil: tau_max grows by beta per decade of "
                   "slip velocity s V/(1-s) above that at s = 0.1 (the lab shear rate). Dp and T rise "
                   "progressively with slip, sinkage nearly unchanged.",
}


def parse_value(v):
    try:
        return json.loads(v)
    except Exception:
        return v


def relpath_main(path):
    ap = os.path.abspath(path)
    if ap.startswith(MAIN + "/"):
        return os.path.relpath(ap, MAIN)
    return ap


def dp_change(case, params, key):
    loads = params.get("loads") or list(SOILS[key]["loads"])
    Wm = float(np.median(loads)) if len(loads) % 2 == 1 else 0.5 * (sorted(loads)[len(loads) // 2 - 1] + sorted(loads)[len(loads) // 2])
    soil = lab_soil(key)
    Z0 = terra.solve_sinkage(Wm, 0.5, WHEEL, soil)
    _, Dp0, _ = terra.forces(Z0, 0.5, WHEEL, soil)
    if case == "load_transfer":
        return 0.0, Wm, Dp0
    if case == "none":
        return None, Wm, Dp0   # filled by caller with the true soil
    _, Dp, _ = noise_free(case, params, key, Wm, 0.5)
    return 100.0 * (Dp - Dp0) / abs(Dp0), Wm, Dp0


def acceptable(case, params):
    if case in VERDICTS:
        return list(VERDICTS[case])
    v = ["unexplained"]
    if params.get("also_none"):
        v.append("none")
    if case == "load_transfer":
        v = ["none", "unexplained"]
    return v


def generate(case, seed, name, outdir, params):
    if case not in ALL_CASES:
        raise SystemExit(f"unknown case {case}; known: {sorted(ALL_CASES)}")
    P = dict(DEFAULTS)
    P.update(params)
    key = P["soil"]
    loads = P["loads"] or list(SOILS[key]["loads"])
    slips = P["slips"]
    rng = np.random.default_rng(seed)
    bin_soil = true_soil_for_case(case, P, key, rng)
    ns = float(P["noise"])
    wh = WHEEL
    rows = []
    blocks = [(W, rep) for rep in range(int(P["repeats"])) for W in loads]
    if P["order"] == "random":
        rng.shuffle(blocks)
    for (Wnom, rep) in blocks:
        soil = prep_bias(bin_soil, rng, ns)           # bin re-prepared for every block
        order = list(slips)
        if P["order"] == "random":
            rng.shuffle(order)
        for sn in order:
            s_rec = float(np.clip(sn + rng.normal(0, 0.006), 0.0, 0.95))
            s_true = float(np.clip(s_rec + rng.normal(0, 0.003 * ns), 0.0, 0.96))
            W = Wnom * (1 + rng.normal(0, 0.025))
            if case == "load_transfer":
                Wd = W
                for _ in range(30):
                    Z, Dp, T = physics(case, P, soil, W, s_true, key)
                    W = Wd - P["lam"] * Dp
            Z, Dp, T = physics(case, P, soil, W, s_true, key)
            Z, Dp, T = measure_chain(case, P, W, s_true, Z, Dp, T)
            W_m = W + rng.normal(0, (0.004 * Wnom + 0.5) * ns)
            Dp_m = Dp + rng.normal(0, (0.008 * Wnom + 0.03 * abs(Dp)) * ns)
            T_m = T + rng.normal(0, (0.008 * Wnom * wh.r + 0.02 * abs(T)) * ns)
            Z_m = Z + rng.normal(0, (0.0004 + 0.03 * abs(Z)) * ns)
            rows.append((s_rec, W_m, Dp_m, T_m, Z_m))
    os.makedirs(outdir, exist_ok=True)
    cols = ["slip", "load_n", "drawbar_pull_n"]
    if P["torque"]:
        cols.append("torque_nm")
    if P["sinkage"]:
        cols.append("sinkage_m")
    csv_path = os.path.join(outdir, name + ".csv")
    with open(csv_path, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(cols)
        for s_rec, W_m, Dp_m, T_m, Z_m in rows:
            r = [f"{s_rec:.4f}", f"{W_m:.1f}", f"{Dp_m:.2f}"]
            if P["torque"]:
                r.append(f"{T_m:.3f}")
            if P["sinkage"]:
                r.append(f"{Z_m:.5f}")
            w.writerow(r)
    with open(os.path.join(outdir, name + ".json"), "w") as f:
        json.dump({"wheel": {"radius_m": wh.r, "width_m": wh.b}}, f, indent=2)
    # truth
    chg, Wm, Dp0 = dp_change(case, P, key)
    if chg is None:
        Zt = terra.solve_sinkage(Wm, 0.5, wh, bin_soil)
        _, Dpt, _ = terra.forces(Zt, 0.5, wh, bin_soil)
        chg = 100.0 * (Dpt - Dp0) / abs(Dp0)
    form = case if case in ("vasilev", "lyasko", "ding") else None
    tcase = "slip_sinkage" if form else case
    eff = {k: v for k, v in P.items() if k not in DEFAULTS and k != "also_none"}
    if case == "none":
        eff["bin_soil"] = {k: round(v, 5) for k, v in bin_soil.lab_dict().items()}
    truth = {
        "name": name,
        "case": tcase,
        "family": "in" if case in IN_FAMILY else "out",
        "acceptable_verdicts": acceptable(case, P),
        "form": form,
        "params": eff,
        "dp_change_s05_pct": round(float(chg), 2),
        "fit_args": [relpath_main(csv_path), "--terrain", "benchmarks/foreign6/" + SOILS[key]["toml"]],
        "notes": NOTES[case] + (" " + P["why_none"] if P.get("why_none") else ""),
        "generator": "foreign6",
        "subcase": case,
        "protocol": {"soil": key, "loads_n": loads, "slips_nominal": slips, "repeats": P["repeats"],
                     "torque": bool(P["torque"]), "sinkage": bool(P["sinkage"]), "order": P["order"],
                     "rows": len(rows)},
        "dp_lab_s05_mid_n": round(Dp0, 2),
        "mid_load_n": Wm,
    }
    # the same change at every nominal load (some effects depend strongly on the load)
    by_load = {}
    for Wl in loads:
        Zl = terra.solve_sinkage(Wl, 0.5, wh, lab_soil(key))
        _, Dl, _ = terra.forces(Zl, 0.5, wh, lab_soil(key))
        if case == "load_transfer":
            De = Dl
        elif case == "none":
            Ze = terra.solve_sinkage(Wl, 0.5, wh, bin_soil)
            De = terra.forces(Ze, 0.5, wh, bin_soil)[1]
        else:
            De = noise_free(case, P, key, Wl, 0.5)[1]
        by_load[str(int(Wl))] = round(100.0 * (De - Dl) / abs(Dl), 2)
    truth["dp_change_s05_pct_by_load"] = by_load
    with open(os.path.join(outdir, name + "_truth.json"), "w") as f:
        json.dump(truth, f, indent=2)
    return truth


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("case")
    ap.add_argument("--seed", type=int, required=True)
    ap.add_argument("--out", required=True)
    ap.add_argument("--outdir", required=True)
    ap.add_argument("--p", action="append", default=[], metavar="key=value")
    a = ap.parse_args(argv)
    params = {}
    for kv in a.p:
        k, v = kv.split("=", 1)
        params[k] = parse_value(v)
    generate(a.case, a.seed, a.out, a.outdir, params)


if __name__ == "__main__":
    main()
