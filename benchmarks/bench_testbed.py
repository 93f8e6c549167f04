"""Testbed benchmark of the diagnosis: single-wheel soil-bin tables with a hidden effect.

The other shape of measured data the pipeline meets (the paper's and the CMU data set's): a
single-wheel testbed runs the wheel at set slips and dead-weight loads and records one row per
steady test point, drawbar pull, torque, load and *measured sinkage*, in a table that
``wheelsoil fit table.csv`` reads.  ``bench_diagnosis.py`` scores the rule on vehicle
recordings without a sinkage channel; this scores it on tables with one, at three loads.

Each seed N draws its case as ``bench_diagnosis.py`` does (``wheelsoil.simulate.draw_case``:
effect ``EFFECTS[N % 17]``, the scenario's soil, wheel and load, size uniform in [0, 1]); the
independent simulator's truth (``wheelsoil.sim.effects.TruthModel``, reference quadrature,
sharing no code with the fitter's kernel) gives the forces and sinkage at each test point:
slips 0.12 .. 0.88 (9 levels; the fit uses s > 0.1) x loads 0.75, 1, 1.25 x the scenario's static load, each point
twice, in a random order, at a carriage speed drawn in 0.1 .. 1 m/s.  Measurement noise per
point (``--noise`` scales it): drawbar pull and torque 2 % of the table's RMS, load 0.5 % of
the static load, sinkage 1 mm.  Effects that change along the run have no meaning in a
table without an order (a soil bin is prepared before each test), and sensor effects other
than a gain of the force, torque or load channel need the vehicle's signals: those seeds are
skipped, with the reason.  A soil that cannot carry the wheel at the testbed's loads moves the
case to the next plausible run (as ``bench_diagnosis.py`` does); an effect that buries the wheel
is re-drawn at half the size, at most 3 times, then moves it.  Scored by ``judge`` against the truth's acceptable verdicts;
the diagnosis' thresholds are whatever the code holds (printed, never changed here).

    python benchmarks/bench_testbed.py                      # seeds 0..67, 2 processes
    python benchmarks/bench_testbed.py --first 8400 --seeds 68 --terrains library
    python benchmarks/bench_testbed.py --no-torque          # tables like the CMU data: no torque
    python benchmarks/bench_testbed.py --seed 17 --keep DIR  # one row again, keeping the table and report

Prints the tables of ``bench_diagnosis.py`` (confusion, calibration, in-family misses by why,
summary, per-seed list).  The "floor" split uses each effect's imprint on the table: the RMS of
the noise-free Dp (T) change over the RMS of Wong's on the lab soil at the same points.
"""

from __future__ import annotations

import argparse
import json
import sys
import tempfile
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import bench_diagnosis  # noqa: E402  (the tables and terrain list, shared)

SLIPS = np.linspace(0.12, 0.88, 9)
LOAD_FACTORS = (0.75, 1.0, 1.25)
REPEATS = 2
#: Per-point measurement noise (x ``--noise``): Dp and T this share of the table's RMS, the load this share of
#: the static load, the sinkage this many metres (a steady test point averages its segment's samples).
NOISE_REL, NOISE_LOAD_REL, NOISE_SINKAGE_M = 0.02, 0.005, 1e-3
#: Sensor effects a testbed table can carry: a gain of the channel (the others need the vehicle's signals).
TABLE_SENSOR_GAINS = {"fx_gain": "drawbar_pull_n", "my_gain": "torque_nm", "load_gain": "load_n"}


def testbed_table(seed: int, terrains=None, effects: str = "listed", noise: float = 1.0, speeds: int = 1):
    """The testbed table of seed ``seed``: ``(df, info, row)``; ``df`` None when the seed is skipped or
    the testbed cannot run it (``row["notes"]`` says why).  ``df`` columns: slip, load_n,
    drawbar_pull_n [N], torque_nm [N m], sinkage_m [m], wheel_radius_m, wheel_width_m (one row per test
    point, 54 rows), and speed_mps [m/s] with ``speeds=2`` (module doc); ``info``: the truth (``effect``,
    ``family``, ``acceptable``, ``params``).  Source of the forces: ``TruthModel.drive_forces`` (paper
    Eqs. 1-10 by adaptive quadrature, the effect applied).  Never raises."""
    from wheelsoil.sim.effects import ACCEPTABLE, SENSOR_EFFECTS, TruthModel, draw_effect, family_of
    from wheelsoil.simulate import EFFECTS, HELD_OUT_BATCHES, STATIC_LOAD_N, _terrain_values, draw_case

    pool = EFFECTS if effects == "listed" else HELD_OUT_BATCHES[effects]
    case = draw_case(seed, terrains=terrains, effects=pool)
    e = case["effect"]
    row = {"seed": seed, "effect": e, "terrain": case["terrain"], "wheel": list(case["wheel"]),
           "added_load_n": case["added_load_n"], "size": case["size"], "notes": []}
    if e in SENSOR_EFFECTS and e not in TABLE_SENSOR_GAINS:
        row["notes"].append("skipped: a sensor effect of the vehicle's signals")
        return None, None, row
    rng = np.random.default_rng([seed, 20261126])
    order = rng.permutation(len(SLIPS) * len(LOAD_FACTORS) * REPEATS)
    v1 = rng.uniform(0.1, 1.0)
    if speeds == 2:  # each point's repeat at a second carriage speed, 3x the first (the first in 0.1 .. 0.33 m/s)
        v1 = 0.1 + (v1 - 0.1) * 0.23 / 0.9
        speed = np.tile([v1, 3.0 * v1], len(SLIPS) * len(LOAD_FACTORS))[order]
    else:
        speed = np.full(order.size, v1)
    slip = np.repeat(np.tile(SLIPS, len(LOAD_FACTORS)), REPEATS)[order]
    found = None
    # a soil that cannot carry the wheel at the testbed's loads: the next plausible run (as bench_diagnosis.py),
    # an effect that buries it: half the size (3 tries), then the next run at the full size
    for k, (terrain, wheel, added) in enumerate(bench_diagnosis._runs_to_try(case["terrain"], case, terrains)):
        if k:
            row["notes"].append(f"moved to {terrain} {wheel[0]}x{wheel[1]} +{added:.0f} N")
        _, soil = _terrain_values(terrain)
        r, b = wheel
        static = STATIC_LOAD_N + added
        load = np.repeat(np.outer(LOAD_FACTORS, np.ones(SLIPS.size)).ravel() * static, REPEATS)[order]
        lab = TruthModel(soil, r, b, "none", {}, static)
        try:
            wong = lab.drive_forces(load, slip, frac=0.5, speed_mps=speed)
        except ValueError as exc:
            row["notes"].append(f"the lab soil buries the wheel: {str(exc)[:50]}")
            continue
        size = case["size"]
        for _ in range(3):
            params = draw_effect(e, np.random.default_rng(seed), size=size)
            tm = TruthModel(soil, r, b, e if e not in SENSOR_EFFECTS else "none", params, static)
            try:
                true = tm.drive_forces(load, slip, frac=0.5, speed_mps=speed)
                early, late = (tm.drive_forces(load, slip, frac=f, speed_mps=speed) for f in (0.1, 0.9))
                if not all(np.allclose(early[c], late[c]) for c in ("drawbar_pull_n", "torque_nm", "sinkage_m")):
                    row["notes"].append("skipped: the effect changes along the run (a table has no order)")
                    return None, None, row
                found = (terrain, wheel, added)
                break
            except ValueError as exc:
                row["notes"].append(f"refused at size {size:.3f}: {str(exc)[:60]}")
                size *= 0.5
        if found:
            break
    if not found:
        return None, None, row
    row.update(terrain=found[0], wheel=list(found[1]), added_load_n=found[2])
    row["size"] = size
    meas = {c: np.asarray(true[c], float).copy() for c in ("drawbar_pull_n", "torque_nm", "sinkage_m")}
    meas["load_n"] = load.copy()
    if e in TABLE_SENSOR_GAINS:
        meas[TABLE_SENSOR_GAINS[e]] *= params["gain"]
        if e == "load_gain":  # what the fit sees: the forces against Wong at the load the channel reports
            try:
                wong = lab.drive_forces(meas["load_n"], slip, frac=0.5, speed_mps=speed)
            except ValueError:
                pass
    row["imprint"] = {c: float(np.sqrt(np.mean((meas[c] - wong[c]) ** 2)) / max(np.sqrt(np.mean(wong[c] ** 2)), 1e-9))
                      for c in ("drawbar_pull_n", "torque_nm")}
    sd = {c: NOISE_REL * float(np.sqrt(np.mean(meas[c] ** 2))) for c in ("drawbar_pull_n", "torque_nm")}
    sd.update(sinkage_m=NOISE_SINKAGE_M, load_n=NOISE_LOAD_REL * static)
    import pandas as pd

    df = pd.DataFrame({"slip": slip, **{c: meas[c] + noise * sd[c] * rng.standard_normal(load.size) for c in sd},
                       "wheel_radius_m": r, "wheel_width_m": b})
    if speeds == 2:
        df["speed_mps"] = speed
    info = {"effect": e, "family": family_of(e), "acceptable": list(ACCEPTABLE[e]), "params": params}
    row["params"] = params
    return df, info, row


def run_seed(seed: int, terrains=None, effects: str = "listed", noise: float = 1.0, keep_dir: str | None = None,
             no_torque: bool = False, no_sinkage: bool = False, speeds: int = 1) -> dict:
    """Make seed ``seed``'s table (:func:`testbed_table`), fit it as a user would (``run_fit([table],
    terrain)``) and score it with ``judge``: returns the benchmark row (dict: ``verdict``, ``model``,
    ``confidence``, ``right``, ``wrong_cause``, ``why``, ``imprint`` (channel -> relative RMS), CPU
    seconds, notes).  Never raises: a pipeline exception is a row with verdict ``(error)``."""
    from wheelsoil.pipeline import run_fit
    from wheelsoil.simulate import judge

    c0 = time.process_time()
    df, info, row = testbed_table(seed, terrains, effects, noise, speeds)
    row["sim_cpu_s"] = time.process_time() - c0
    if df is None:
        row.update(verdict="(skipped)", right=False, wrong_cause=False, confidence=None, model=None, family=None)
        return row
    df = df.drop(columns=[c for c, off in (("torque_nm", no_torque), ("sinkage_m", no_sinkage)) if off])
    with tempfile.TemporaryDirectory(prefix="bench-testbed-") as tmp:
        base = Path(keep_dir) if keep_dir else Path(tmp)
        base.mkdir(parents=True, exist_ok=True)
        table = base / f"testbed{seed}.csv"
        df.to_csv(table, index=False)
        if keep_dir:
            (base / f"testbed{seed}.truth.json").write_text(json.dumps(info, indent=1, default=float))
        c1 = time.process_time()
        try:
            report = run_fit([table], row["terrain"], base / f"report-testbed{seed}")
        except Exception as exc:  # noqa: BLE001 - a crash of the pipeline is a result too
            row.update(verdict="(error)", right=False, wrong_cause=False, confidence=None, model=None,
                       family=info["family"], fit_cpu_s=time.process_time() - c1)
            row["notes"].append(f"{type(exc).__name__}: {str(exc)[:200]}")
            return row
        row["fit_cpu_s"] = time.process_time() - c1
    j = judge(info, report)
    row.update({k: j[k] for k in ("family", "acceptable", "verdict", "model", "confidence", "right",
                                  "wrong_cause", "missed", "false_alarm", "form_ok")})
    dg = report["diagnosis"]
    row["why"] = dg.get("why")
    row["alternatives"] = list(dg.get("alternatives") or [])
    return row


def main(argv=None) -> int:
    from wheelsoil.simulate import HELD_OUT_BATCHES

    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                 formatter_class=argparse.RawDescriptionHelpFormatter, epilog=__doc__)
    ap.add_argument("--seeds", type=int, default=68, help="N seeds from --first on (default 68)")
    ap.add_argument("--first", type=int, default=0, help="first seed (default 0)")
    ap.add_argument("--seed", type=int, action="append", default=None, help="run only this seed (repeatable)")
    ap.add_argument("--jobs", type=int, default=2, help="worker processes, at most 2 (default 2)")
    ap.add_argument("--terrains", default=None, metavar="SLUGS",
                    help="draw each seed's soil from these built-in terrains (as bench_diagnosis.py; 'library': "
                    "every built-in terrain but the paper's clay and sand)")
    ap.add_argument("--effects", choices=("listed", *HELD_OUT_BATCHES), default="listed",
                    help="the effects drawn from, as bench_diagnosis.py (default 'listed')")
    ap.add_argument("--noise", type=float, default=1.0, metavar="F",
                    help="scale of the per-point measurement noise (default 1: Dp and T 2 %% of the table's RMS, "
                    "the load 0.5 %% of the static load, sinkage 1 mm)")
    ap.add_argument("--no-torque", action="store_true", help="tables without torque (as the CMU data set's)")
    ap.add_argument("--no-sinkage", action="store_true", help="tables without measured sinkage")
    ap.add_argument("--speeds", type=int, choices=(1, 2), default=1,
                    help="carriage speeds: 1 (default, one speed drawn in 0.1 .. 1 m/s) or 2 (each point's repeat "
                    "at 3x the first speed, drawn in 0.1 .. 0.33 m/s; the table gets a speed_mps column): the "
                    "measurement that separates rate and speed effects from slip and soil values")
    ap.add_argument("--json", default=None, metavar="FILE", help="also write the rows as JSON")
    ap.add_argument("--keep", default=None, metavar="DIR", help="keep tables, truths and reports here")
    args, terrains = bench_diagnosis.parse_args(ap, argv)
    seeds = args.seed if args.seed else list(range(args.first, args.first + args.seeds))
    print(f"bench_testbed: {len(seeds)} seeds, {len(SLIPS) * len(LOAD_FACTORS) * REPEATS} test points each, "
          f"noise x{args.noise:g}, {args.jobs} process(es)"
          + ("" if terrains is None else f", terrains {', '.join(terrains)}")
          + ("" if args.effects == "listed" else f", effects {args.effects}")
          + (", no torque" if args.no_torque else "") + (", no sinkage" if args.no_sinkage else "")
          + (", two carriage speeds" if args.speeds == 2 else ""))
    print("diagnosis thresholds as the code holds them (wheelsoil.model.diagnosis):",
          json.dumps(bench_diagnosis.thresholds(), sort_keys=True))
    sys.stdout.flush()
    t0 = time.perf_counter()
    task = (terrains, args.effects, args.noise, args.keep, args.no_torque, args.no_sinkage, args.speeds)
    rows = []
    with ProcessPoolExecutor(max_workers=args.jobs) as pool:
        futs = {s: pool.submit(run_seed, s, *task) for s in seeds}
        for s in seeds:
            rows.append(futs[s].result())
            print(f"  seed {s}: {rows[-1]['effect']} -> {rows[-1]['verdict']} ({rows[-1].get('confidence')})",
                  flush=True)
    wall = time.perf_counter() - t0
    scored = [r for r in rows if r["verdict"] != "(skipped)"]
    print(f"\n{len(rows) - len(scored)} seeds skipped (sensor effects of the vehicle's signals, effects along the run)\n")
    print(bench_diagnosis.report(scored, wall, args, runs="testbed tables"))
    if args.json:
        Path(args.json).write_text(json.dumps({"rows": rows, "wall_s": wall, "thresholds": bench_diagnosis.thresholds(),
                                               "args": vars(args)}, indent=1, default=str))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
