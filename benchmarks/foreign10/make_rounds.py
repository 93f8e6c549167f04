#!/usr/bin/env python3
"""Writes round1.json and round2.json (the cases and sizes, fixed before any
run was generated).  Refuses to overwrite existing files.
usage: make_rounds.py [--seed-base1 1301 --seed-base2 1331 --outdir .]"""
import argparse
import json
import os

C, S = "clay_loam", "dry_sand"
HS = {"hill_starts": False}   # brittle soil: no hill starts (the residual strength cannot start the tractor)

ROUND1 = [
    ("none", {"soil": C}),
    ("none", {"soil": S}),
    ("ss_vasilev", {"soil": C, "H": 0.03}),
    ("ss_vasilev", {"soil": S, "H": 0.07}),
    ("ss_lyasko", {"soil": S, "m1": 0.5, "m2": 0.05}),
    ("ss_lyasko", {"soil": C, "m1": 1.0, "m2": 0.2}),
    ("ss_ding", {"soil": C, "n1": 0.45}),
    ("ss_ding", {"soil": S, "n1": 0.9}),
    ("mismatch", {"soil": C, "shift_sd": {"phi_deg": 3.0}}),
    ("mismatch", {"soil": S, "shift_sd": {"K_m": 3.0, "c_kpa": -2.5}}),
    ("mismatch", {"soil": C, "shift_sd": {"k_eq": -4.0, "n": 3.0}}),
    ("mismatch", {"soil": S, "shift_sd": {"phi_deg": -2.5}}),
    ("wong_reece", {"soil": C, "a1": 0.4, "a2": 0.3}),
    ("wong_reece", {"soil": S, "a1": 0.2, "a2": 0.15}),
    ("drift_passes", {"soil": C, "per_pass": {"k_eq_rel": 0.4, "c_rel": 0.2, "K_rel": -0.25, "phi_deg": 2.0}}),
    ("drift_wetpatch", {"soil": S, "x0": 52.0, "x1": 102.0,
                        "change": {"k_eq_rel": -0.4, "c_rel": -0.45, "phi_deg": -4.0, "n": 0.06, "K_rel": 0.3}}),
    ("rut", {"soil": C, "overlap": 1.0}),
    ("rut", {"soil": S, "overlap": 0.5}),
    ("tyre_deflection", {"soil": C, "p_inflation_kpa": 70.0}),
    ("tyre_deflection", {"soil": S, "p_inflation_kpa": 50.0}),
    ("my_crosstalk", {"soil": C, "coeff_m": 0.006}),
    ("my_crosstalk", {"soil": S, "coeff_m": 0.025}),
    ("wss_teeth", {"soil": C, "teeth_true": 48, "teeth_config": 50}),
    ("wss_teeth", {"soil": S, "teeth_true": 52, "teeth_config": 48}),
    ("reece_pressure", {"soil": C, "keq_ratio": 2.0, "kc_share": 0.5}),
    ("reece_pressure", {"soil": S, "keq_ratio": 0.45, "kc_share": 0.3, "gamma_kn_m3": 16.0}),
    ("speed_sinkage", {"soil": C, "kappa_s_per_m": 0.04}),
    ("speed_sinkage", {"soil": S, "kappa_s_per_m": 0.10}),
    ("brittle_shear", dict(HS, soil=C, Kr=0.7)),
    ("brittle_shear", dict(HS, soil=S, Kr=0.5)),
]

ROUND2 = [
    ("none", {"soil": S}),
    ("none", {"soil": C}),
    ("ss_vasilev", {"soil": S, "H": 0.05}),
    ("ss_vasilev", {"soil": C, "H": 0.09}),
    ("ss_lyasko", {"soil": C, "m1": 0.6, "m2": 0.1}),
    ("ss_lyasko", {"soil": S, "m1": 0.9, "m2": 0.15}),
    ("ss_ding", {"soil": S, "n1": 0.6}),
    ("ss_ding", {"soil": C, "n1": 0.8}),
    ("mismatch", {"soil": S, "shift_sd": {"phi_deg": 3.0}}),
    ("mismatch", {"soil": C, "shift_sd": {"K_m": -2.5}}),
    ("mismatch", {"soil": S, "shift_sd": {"k_eq": 3.5, "n": -2.5}}),
    ("mismatch", {"soil": C, "shift_sd": {"c_kpa": 3.5, "phi_deg": 2.0}}),
    ("wong_reece", {"soil": S, "a1": 0.25, "a2": 0.15}),
    ("wong_reece", {"soil": C, "a1": 0.45, "a2": 0.25}),
    ("drift_passes", {"soil": S, "per_pass": {"k_eq_rel": 0.6, "c_rel": 0.3, "K_rel": -0.3, "phi_deg": 2.5}}),
    ("drift_wetpatch", {"soil": C, "x0": 52.0, "x1": 102.0,
                        "change": {"k_eq_rel": -0.3, "c_rel": -0.35, "phi_deg": -3.5, "n": 0.05, "K_rel": 0.25}}),
    ("rut", {"soil": S, "overlap": 1.0}),
    ("rut", {"soil": C, "overlap": 0.6}),
    ("tyre_deflection", {"soil": S, "p_inflation_kpa": 70.0}),
    ("tyre_deflection", {"soil": C, "p_inflation_kpa": 50.0}),
    ("my_crosstalk", {"soil": S, "coeff_m": 0.005}),
    ("my_crosstalk", {"soil": C, "coeff_m": 0.015}),
    ("wss_teeth", {"soil": S, "teeth_true": 46, "teeth_config": 48}),
    ("wss_teeth", {"soil": C, "teeth_true": 49, "teeth_config": 46}),
    ("reece_pressure", {"soil": S, "keq_ratio": 1.9, "kc_share": 0.3, "gamma_kn_m3": 16.0}),
    ("reece_pressure", {"soil": C, "keq_ratio": 0.5, "kc_share": 0.5}),
    ("speed_sinkage", {"soil": S, "kappa_s_per_m": 0.05}),
    ("speed_sinkage", {"soil": C, "kappa_s_per_m": 0.10}),
    ("brittle_shear", dict(HS, soil=S, Kr=0.75)),
    ("brittle_shear", dict(HS, soil=C, Kr=0.55)),
]


def build(entries, base, prefix):
    return [{"name": f"{prefix}_{i + 1:02d}", "case": c, "seed": base + i, "params": p}
            for i, (c, p) in enumerate(entries)]


if __name__ == "__main__":
    ap = argparse.ArgumentParser()
    ap.add_argument("--seed-base1", type=int, default=1301)
    ap.add_argument("--seed-base2", type=int, default=1331)
    ap.add_argument("--outdir", default=os.path.dirname(os.path.abspath(__file__)))
    a = ap.parse_args()
    for fn, ent, base, pre in (("round1.json", ROUND1, a.seed_base1, "f10r1"),
                               ("round2.json", ROUND2, a.seed_base2, "f10r2")):
        path = os.path.join(a.outdir, fn)
        if os.path.exists(path):
            raise SystemExit(f"{path} exists; not overwriting (rounds are fixed before any run)")
        with open(path, "w") as f:
            json.dump(build(ent, base, pre), f, indent=1)
        print("wrote", path)
