#!/usr/bin/env python3
"""foreign10 self-checks.

1. the stress-integral quadrature (tanh-sinh, piecewise) against
   scipy.integrate.quad, rel 1e-6, for every stress/shear form used;
2. determinism: the same seed gives the same bytes (all four log formats);
3. every case generates (exit 0, log + truth written, truth fields present);
4. the refusal works (exit 2 and a 'REFUSED: ...' line);
5. cantools round trip: our vectorised packer equals cantools' encoder for
   random values of every message, and frames read back from generated logs
   (python-can readers) decode with cantools to the packed values.

usage: check.py [--jobs 2] [--keep DIR]
"""
import argparse
import filecmp
import json
import math
import os
import shutil
import subprocess
import sys
import tempfile
from concurrent.futures import ThreadPoolExecutor

import numpy as np
from scipy.integrate import quad

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
import f10_model as fm  # noqa: E402
import f10_can as fc  # noqa: E402
import gen  # noqa: E402

PY = sys.executable
FAIL = []


def ok(cond, msg):
    print(("PASS " if cond else "FAIL ") + msg, flush=True)
    if not cond:
        FAIL.append(msg)


# ----------------------------------------------------------------- 1. quad
def scalar_reference(s, W, soil, r, b, eff, o, zf=None):
    """Independent scalar integrands (paper Eqs. 2-9 corrected, Wong-Reece,
    brittle shear, rut) integrated with scipy.integrate.quad."""
    kind = eff.get("kind", "none")
    th1 = float(o["th1"][0])
    keq = float(o["keq"][0])
    N = float(o["N"][0])
    re = float(o["re"][0])
    Z = float(o["Z"][0])
    c, tphi, K = soil["c"], math.tan(soil["phi"]), soil["K"]
    pts = []
    if kind == "stress_distribution":
        thm = (eff["a1"] + eff["a2"] * min(max(s, 0), 1)) * th1
        pts = [thm]

    def sig(th):
        if kind == "stress_distribution":
            if th >= thm:
                return keq * (re * max(math.cos(th) - math.cos(th1), 0)) ** N
            return keq * (re * max(math.cos(th1 - th / thm * th1) - math.cos(th1), 0)) ** N
        if kind == "rut":
            z = max(Z - re * (1 - math.cos(th)), 0.0)
            ku = eff["A_u"] * max(zf, 1e-4)
            pf = keq * zf ** N
            zs = max(zf - pf / ku, 0)
            rut = 0.0 if z <= zs else (ku * (z - zs) if z <= zf else keq * z ** N)
            return eff["overlap"] * rut + (1 - eff["overlap"]) * keq * z ** N
        return keq * (re * max(math.cos(th) - math.cos(th1), 0)) ** N

    def tau(th):
        j = re * ((th1 - th) - (1 - s) * (math.sin(th1) - math.sin(th)))
        tm = c + sig(th) * tphi
        aj = abs(j)
        if kind == "brittle_shear":
            Kr, Kw = eff["Kr"], eff["Kw_over_K"] * K
            f = Kr * (1 + (1 / (Kr * (1 - math.exp(-1))) - 1) * math.exp(1 - aj / Kw)) * (1 - math.exp(-aj / Kw))
        else:
            f = 1 - math.exp(-aj / K)
        return math.copysign(tm * f, j)

    if kind == "rut":
        for zz in (zf - keq * zf ** N / (eff["A_u"] * max(zf, 1e-4)), zf):
            v = 1 - max(Z - zz, 0) / re
            if -1 < v < 1:
                pts.append(math.acos(v))
    kw = dict(points=pts or None, epsabs=0.0, epsrel=1e-11, limit=400)
    Iw = quad(lambda t: sig(t) * math.cos(t) + tau(t) * math.sin(t), 0, th1, **kw)[0]
    Id = quad(lambda t: tau(t) * math.cos(t) - sig(t) * math.sin(t), 0, th1, **kw)[0]
    It = quad(tau, 0, th1, **kw)[0]
    return re * b * Iw, re * b * Id, It


def check_quadrature():
    r, b = 0.585, 0.40
    effs = [{}, dict(kind="stress_distribution", a1=0.4, a2=0.3),
            dict(kind="stress_distribution", a1=0.2, a2=0.15),
            dict(kind="brittle_shear", Kr=0.5, Kw_over_K=2.0),
            dict(kind="slip_sinkage", form="ding", n1=0.9),
            dict(kind="slip_sinkage", form="lyasko", m1=1.0, m2=0.2),
            dict(kind="slip_sinkage", form="vasilev", H=0.07),
            dict(kind="tyre_deflection", p_inflation_kpa=50.0, p_carcass_kpa=25.0, tyre_kz_kn_m=260.0,
                 hyst_coeff=0.4),
            dict(kind="speed_sinkage", kappa_s_per_m=0.1),
            dict(kind="rut", overlap=0.6, A_u=4e8)]
    worst = 0.0
    for soil_name in gen.SOILS:
        soil = fm.soil_si(gen.load_lab(soil_name))
        for eff in effs:
            for s in (-0.3, 0.05, 0.2, 0.5, 0.9):
                for W in (7000.0, 12500.0):
                    extra = {}
                    zf = None
                    if eff.get("kind") == "rut":
                        zf = 0.8 * float(fm.z0_eq10(W, soil["kc"] / b + soil["kphi"], soil["n"], r, b))
                        extra = dict(zf=np.array([zf]), rut_ratio=np.array([0.9]))
                    o = fm.forces(np.array([s]), np.array([W]), soil, r, b, eff,
                                  omega=np.array([4.0]), return_all=True, **extra)
                    Wq, Dq, Itq = scalar_reference(s, W, soil, r, b, eff, o, zf)
                    # compare the integrals themselves (before tyre post-terms)
                    re = float(o["re"][0])
                    Wm = float(o["W_model"][0])
                    It = float(o["T"][0]) / (re * re * b) if eff.get("kind") != "tyre_deflection" else None
                    errs = [abs(Wm / Wq - 1)]
                    if eff.get("kind") != "tyre_deflection":
                        errs.append(abs(float(o["Dp"][0]) / Dq - 1) if abs(Dq) > 1e-3 * W else
                                    abs(float(o["Dp"][0]) - Dq) / W)
                        errs.append(abs(It / Itq - 1))
                    worst = max(worst, max(errs))
    ok(worst < 1e-6, f"quadrature vs scipy.integrate.quad: worst rel. error {worst:.2e} (< 1e-6)")


# ---------------------------------------------------------------- helpers
def run_gen(case, seed, name, outdir, params=None):
    cmd = [PY, os.path.join(HERE, "gen.py"), case, "--seed", str(seed), "--out", name, "--outdir", outdir]
    for k, v in (params or {}).items():
        cmd += ["--p", f"{k}={json.dumps(v)}"]
    return subprocess.run(cmd, capture_output=True, text=True)


# ----------------------------------------------------------- 5. cantools
def check_packer():
    db = fc.load_db()
    rng = np.random.default_rng(7)
    n = 200
    bad = 0
    for msg in db.messages:
        muxes = [None]
        if msg.is_multiplexed():
            muxes = [0, 1, 2]
        for mv in muxes:
            vals = {}
            for s in msg.signals:
                if mv is not None and s.multiplexer_ids and mv not in s.multiplexer_ids:
                    continue
                if s.is_multiplexer:
                    vals[s.name] = np.full(n, mv)
                    continue
                lo = s.minimum if s.minimum is not None else 0
                hi = s.maximum if s.maximum is not None else 1
                vals[s.name] = rng.uniform(lo, hi, n)
            data, _ = fc.pack(msg, vals, n)
            for i in range(n):
                dec = msg.decode(bytes(data[i]), scaling=True, decode_choices=False)
                for k, v in vals.items():
                    sg = msg.get_signal_by_name(k)
                    if abs(dec[k] - v[i]) > 0.5 * sg.scale + 1e-9:
                        bad += 1
            try:
                fc.verify(db, msg.name, vals, data, idx=range(20))
            except AssertionError as e:
                bad += 1
                print("   ", e)
    ok(bad == 0, f"packer vs cantools encode/decode for every message incl. Motorola and multiplexed ({bad} mismatches)")


def check_logs_roundtrip(dirs):
    import can
    db = cantools_db()
    for path in dirs:
        n = 0
        counters = {}
        chans = {}
        try:
            for m in can.LogReader(path):
                d = db.decode_message(m.arbitration_id, m.data)
                chans.setdefault(m.arbitration_id, set()).add(m.channel)
                if m.arbitration_id in (0x120, 0x121, 0x122):
                    counters.setdefault(m.arbitration_id, []).append(d["Counter"])
                n += 1
            good = n > 1000 and all(len(v) > 1000 for v in counters.values())
            # bus separation: the WFT ids on one channel, wheel speed + GNSS on the other
            c_wft = set().union(*(chans[i] for i in (0x120, 0x121, 0x122, 0x123)))
            c_1 = set().union(*(chans[i] for i in chans if i not in (0x120, 0x121, 0x122, 0x123)))
            good = good and len(c_wft) == 1 and len(c_1) == 1 and c_wft != c_1
            ok(good, f"round trip {os.path.basename(path)}: {n} frames decoded with the shared DBCs "
                     f"(channels {sorted(map(str, c_wft))} / {sorted(map(str, c_1))})")
        except Exception as e:   # noqa: BLE001
            ok(False, f"round trip {os.path.basename(path)}: {e!r}")


def cantools_db():
    import cantools
    db = cantools.database.Database()
    for f in ("wft.dbc", "wheel_speed.dbc", "gps_rt_speedbox.dbc"):
        p = os.path.join("/work/shared/dbc", f)
        db.add_dbc_file(p if os.path.exists(p) else os.path.join(HERE, "dbc", f))
    return db


# ------------------------------------------------------------------- main
def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--keep", default=None)
    a = ap.parse_args()
    tmp = a.keep or tempfile.mkdtemp(prefix="f10check_")
    os.makedirs(tmp, exist_ok=True)
    check_quadrature()
    check_packer()

    # 2. determinism, one run per log format, twice
    jobs = []
    for k, fmt in enumerate(fc.FORMATS):
        for rep in ("a", "b"):
            jobs.append(("det", fmt, rep, ("none", 1401 + k, f"det_{fmt}", os.path.join(tmp, rep),
                                           {"format": fmt, "soil": list(gen.SOILS)[k % 2]})))
    # 3. every case
    for k, case in enumerate(gen.CASES):
        p = {"soil": list(gen.SOILS)[k % 2]}
        if case == "brittle_shear":
            p.update(hill_starts=False, soil="dry_sand")
        if case == "wong_reece":
            p["soil"] = "clay_loam"
        jobs.append(("case", case, None, (case, 1501 + k, f"case_{case}", os.path.join(tmp, "cases"), p)))
    # 4. refusal
    jobs.append(("refuse", None, None, ("none", 1601, "refuse", os.path.join(tmp, "ref"), {"grade_max": 0.6})))

    with ThreadPoolExecutor(max_workers=a.jobs) as ex:
        res = list(ex.map(lambda j: (j, run_gen(*j[3])), jobs))
    for (kind, x, rep, args), p in res:
        if kind == "case":
            tp = os.path.join(args[3], f"{args[2]}_truth.json")
            good = p.returncode == 0 and os.path.exists(tp)
            msg = f"case {x} generates"
            if good:
                t = json.load(open(tp))
                need = {"name", "case", "family", "acceptable_verdicts", "fit_args", "params"}
                good = need <= set(t) and {"seed", "effect", "gnss_latency_s"} <= set(t["params"]) \
                    and os.path.exists(os.path.join(args[3], t["fit_args"][0]))
                cov = t["params"]["slip_coverage"]
                msg += f" ({t['family']}, {t['acceptable_verdicts']}, uphill slip max {cov['uphill_max']:.2f})"
            else:
                msg += f": rc={p.returncode} {p.stdout.strip()[-200:]} {p.stderr.strip()[-300:]}"
            ok(good, msg)
        elif kind == "refuse":
            ok(p.returncode == 2 and p.stdout.startswith("REFUSED: "),
               f"refusal: rc={p.returncode}, {p.stdout.strip()}")
        elif kind == "det" and rep == "b":
            fmt = x
            fa = os.path.join(tmp, "a", f"det_{fmt}.{fmt}")
            fb = os.path.join(tmp, "b", f"det_{fmt}.{fmt}")
            ta = os.path.join(tmp, "a", f"det_{fmt}_truth.json")
            tb = os.path.join(tmp, "b", f"det_{fmt}_truth.json")
            same = all(os.path.exists(f) for f in (fa, fb, ta, tb)) and \
                filecmp.cmp(fa, fb, shallow=False) and filecmp.cmp(ta, tb, shallow=False)
            ok(same, f"determinism .{fmt}: same seed -> same bytes (log and truth)")
    check_logs_roundtrip([os.path.join(tmp, "a", f"det_{f}.{f}") for f in fc.FORMATS])
    if a.keep is None:
        shutil.rmtree(tmp, ignore_errors=True)
    print(f"\n{len(FAIL)} failure(s)")
    sys.exit(1 if FAIL else 0)


if __name__ == "__main__":
    main()
