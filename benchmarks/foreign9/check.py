#!/usr/bin/env python3
"""foreign9 self-checks: quadrature vs scipy quad, determinism, every case, refusal,
CAN round trip (cantools decode of written frames == encoded signals)."""
import hashlib
import json
import os
import subprocess
import sys
import tempfile

import numpy as np
from scipy.integrate import quad

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
from physics import wheel_forces, static_sinkage  # noqa: E402
import gen  # noqa: E402

PY = sys.executable
ok = True


def fail(msg):
    global ok
    ok = False
    print("FAIL:", msg)


def ref_forces(W, s, soil, r, b, eff):
    """Straightforward scalar reference with scipy.integrate.quad."""
    k, n, c, tphi, K = soil["k"], soil["n"], soil["c"], soil["tphi"], soil["K"]
    Z = static_sinkage(W, r, b, k, n)
    case = eff.get("case", "none")
    if case == "vasilev":
        Z = Z + eff["H"] * s
    if case == "lyasko":
        Z = (1 + eff["m1"] * s) / (1 - eff["m2"] * s) * Z
    N = n + eff["n1"] * s if case == "ding" else n
    t1 = np.arccos(1 - Z / r)
    tm = (eff["a1"] + eff["a2"] * s) * t1 if case == "stress_distribution" else None
    ta = np.tan(np.radians(eff["alpha_deg"])) if case == "steer" else 0.0

    def sig(th):
        ts = t1 - th / tm * (t1 - tm) if (tm is not None and th < tm) else th
        return k * max(r * (np.cos(ts) - np.cos(t1)), 0.0) ** N

    def taux(th):
        jx = r * (t1 - th - (1 - s) * (np.sin(t1) - np.sin(th)))
        jy = r * (1 - s) * (t1 - th) * ta
        j = np.hypot(jx, jy)
        if j == 0:
            return 0.0
        return (c + sig(th) * tphi) * (1 - np.exp(-j / K)) * jx / j

    pts = [tm] if tm is not None else None
    q = lambda f: quad(f, 0, t1, points=pts, limit=200, epsabs=0, epsrel=1e-10)[0]
    Dp = r * b * (q(lambda th: taux(th) * np.cos(th)) - q(lambda th: sig(th) * np.sin(th)))
    T = r * r * b * q(taux)
    W7 = r * b * (q(lambda th: sig(th) * np.cos(th)) + q(lambda th: taux(th) * np.sin(th)))
    return Dp, T, W7


def check_quadrature():
    r, b = gen.WHEEL["r"], gen.WHEEL["b"]
    worst = 0.0
    effs = [{}, {"case": "vasilev", "H": 0.04}, {"case": "lyasko", "m1": 0.3, "m2": 0.2},
            {"case": "ding", "n1": 0.25}, {"case": "stress_distribution", "a1": 0.3, "a2": 0.15},
            {"case": "steer", "alpha_deg": 6.0}]
    for nm, L in gen.LAB.items():
        soil = {"k": gen.lab_k_eq(L, b), "n": L["n"], "c": L["c_kpa"] * 1e3,
                "tphi": np.tan(np.radians(L["phi_deg"])), "K": L["K_m"]}
        for eff in effs:
            for W, s in ((8000.0, 0.05), (11000.0, 0.3), (13500.0, 0.8)):
                R = wheel_forces(np.array([W]), np.array([s]), soil, r, b, eff)
                ref = ref_forces(W, s, soil, r, b, eff)
                for key, rv in zip(("Dp", "T", "W7"), ref):
                    e = abs(R[key][0] - rv) / max(abs(rv), 1e-9 * W + 1.0)
                    worst = max(worst, e)
    print(f"quadrature: worst relative error vs scipy quad = {worst:.2e} (36 states x Dp,T,W7)")
    if worst > 1e-3:
        fail("quadrature error too large")


def run(case, seed, out, outdir, params=(), env=None):
    a = [PY, os.path.join(HERE, "gen.py"), case, "--seed", str(seed), "--out", out, "--outdir", outdir]
    for p in params:
        a += ["--p", p]
    return subprocess.run(a, capture_output=True, text=True, env=env)


def sha(path):
    return hashlib.sha256(open(path, "rb").read()).hexdigest()


def main():
    check_quadrature()
    tmp = tempfile.mkdtemp(prefix="f9check_")
    # determinism, one per format
    for fmt in ("log", "asc", "blf"):
        hs = []
        for rep in range(2):
            d = os.path.join(tmp, f"det{rep}")
            p = run("vasilev", 77, "det", d, [f"fmt={fmt}", "duration=30"])
            if p.returncode != 0:
                fail(f"determinism run failed: {p.stderr[-500:]}")
                break
            hs.append((sha(os.path.join(d, f"det.{fmt}")), sha(os.path.join(d, "det_truth.json"))))
        same = len(hs) == 2 and hs[0] == hs[1]
        print(f"determinism {fmt}: {'same bytes' if same else 'DIFFERENT'}")
        if not same:
            fail(f"determinism {fmt}")
    # every case
    for i, case in enumerate(gen.CASES):
        p = run(case, 500 + i, f"c_{case}", os.path.join(tmp, "cases"), ["duration=30"])
        if p.returncode != 0:
            fail(f"case {case}: rc={p.returncode} {p.stderr[-800:]}")
            continue
        t = json.load(open(os.path.join(tmp, "cases", f"c_{case}_truth.json")))
        need = {"name", "case", "family", "acceptable_verdicts", "params", "fit_args"}
        miss = need - set(t)
        if miss or "gnss_latency_s" not in t["params"]:
            fail(f"case {case}: truth keys missing {miss}")
        if t["case"] in ("vasilev", "lyasko", "ding") and t.get("form") != case:
            fail(f"case {case}: form")
        print(f"case {case:10s} ok  {p.stdout.strip()}")
    # refusal
    for prm in (["tow_min_kn=40"], ["load_kn=90"]):
        p = run("none", 5, "ref", os.path.join(tmp, "ref"), prm)
        good = p.returncode == 2 and (p.stdout.startswith("REFUSED:") or p.stderr.startswith("REFUSED:"))
        print(f"refusal {prm}: rc={p.returncode} {p.stdout.strip()[:120]}")
        if not good:
            fail(f"refusal {prm}")
    # CAN round trip: the first frames of a generated file decode to the encoded signals
    import can
    import cantools
    dbs = [cantools.database.load_file(os.path.join(gen.DBC_DIR, f)) for f in
           ("wft.dbc", "wheel_speed.dbc", "gps_rt_speedbox.dbc")]
    for fmt in ("log", "asc", "blf"):
        d = os.path.join(tmp, "rt")
        dump = os.path.join(tmp, f"dump_{fmt}.json")
        env = dict(os.environ, F9_DUMP=dump)
        p = run("steer", 31, f"rt_{fmt}", d, [f"fmt={fmt}", "duration=30"], env=env)
        if p.returncode != 0:
            fail(f"round trip gen {fmt}: {p.stderr[-500:]}")
            continue
        ref = json.load(open(dump))
        got = []
        for msg in can.LogReader(os.path.join(d, f"rt_{fmt}.{fmt}")):
            if msg.is_error_frame:
                continue
            got.append(msg)
            if len(got) == len(ref):
                break
        worst, nbad = 0.0, 0
        t_r0, t_g0 = ref[0]["t"], got[0].timestamp  # ASC stores times relative to its start
        for rf, msg in zip(ref, got):
            if msg.arbitration_id != rf["id"] or abs((msg.timestamp - t_g0) - (rf["t"] - t_r0)) > 2e-6:
                nbad += 1
                continue
            for db in dbs:
                try:
                    m = db.get_message_by_frame_id(msg.arbitration_id)
                    break
                except KeyError:
                    m = None
            dec = m.decode(msg.data, decode_choices=False)
            for key, val in rf["sig"].items():
                worst = max(worst, abs(float(dec[key]) - float(val)))
        chans = sorted({str(mm.channel) for mm in got})
        print(f"round trip {fmt}: {len(got)} frames, id/time mismatches {nbad}, worst signal diff {worst:.2e}, channels {chans}")
        if nbad or worst > 1e-6:
            fail(f"round trip {fmt}")
    print("ALL CHECKS PASSED" if ok else "SOME CHECKS FAILED")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
