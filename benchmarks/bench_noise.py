"""How much of an along-run change the cell noise counts as noise: the residual scatter of the cell
means about the noise's smooth (:func:`wheelsoil.model.data.cell_noise`) with and without the slip
spline times the distance, on the diagnosis benchmark's simulated runs.

    .venv/bin/python benchmarks/bench_noise.py --first 6904 --seeds 68
    .venv/bin/python benchmarks/bench_noise.py --terrains library --first 5731 --seeds 68

Prints per run and channel the ratio sigma(with) / sigma(without) (below 1: the additive smooth
counted part of an effect as noise), then its spread over runs without a terrain drift and per
drift.  The runs are the ones ``bench_diagnosis.py`` makes for the same seeds (same options).
"""

from __future__ import annotations

import argparse
import sys
import tempfile
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))


def run_seed(seed: int, terrains) -> dict:
    """Simulate seed ``seed`` as the diagnosis benchmark does, process it, and compare the two smooths."""
    from bench_diagnosis import simulate_seed

    from wheelsoil.model.data import _scatter_about, _smooth_basis, make_cells, prepare_data
    from wheelsoil.pipeline import load_inputs
    from wheelsoil.simulate import write_simulation

    run, row = simulate_seed(seed, 180.0, "reference", terrains)
    out = {"seed": seed, "effect": row["effect"], "mode": None, "ratio": {}}
    if run is None:
        return out
    out["mode"] = run.info["params"].get("mode")
    with tempfile.TemporaryDirectory(prefix="bench-noise-") as tmp:
        df, _ = load_inputs([write_simulation(run, Path(tmp) / "run.mcap")])
    cells = make_cells(prepare_data(df, slip_min=0.1))
    out["cycles"] = int(np.unique(cells.group).size)
    for c, y in cells.channels.items():
        ok = np.isfinite(y)
        args = (cells.slip[ok], cells.load_n[ok], cells.x[ok], int(ok.sum()))
        out["ratio"][c] = (_scatter_about(_smooth_basis(*args), y[ok])
                           / _scatter_about(_smooth_basis(*args, interaction=False), y[ok]))
    return out


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--first", type=int, default=6904, help="first seed (default 6904)")
    ap.add_argument("--seeds", type=int, default=68, help="number of seeds (default 68)")
    ap.add_argument("--terrains", default=None, help="'library' or slugs, as bench_diagnosis.py")
    ap.add_argument("--jobs", type=int, default=2, help="worker processes (default 2)")
    args = ap.parse_args(argv)
    from bench_diagnosis import terrain_list

    try:
        terrains = terrain_list(args.terrains)
    except ValueError as exc:
        ap.error(str(exc))
    seeds = range(args.first, args.first + args.seeds)
    with ProcessPoolExecutor(max_workers=args.jobs) as pool:
        rows = list(pool.map(run_seed, seeds, [terrains] * len(seeds)))
    print("| seed | effect | cycles | Dp ratio | T ratio |\n|---|---|---|---|---|")
    for r in rows:
        ra = r["ratio"]
        print(f"| {r['seed']} | {r['effect']}{' (' + r['mode'] + ')' if r['mode'] else ''} | {r.get('cycles', '-')} | "
              + " | ".join(f"{ra[c]:.2f}" if c in ra else "-" for c in ("drawbar_pull_n", "torque_nm")) + " |")
    still = np.array([v for r in rows if r["effect"] != "terrain_drift" for v in r["ratio"].values()])
    if still.size:
        print(f"\nwithout a terrain drift ({still.size} channel-runs): median {np.median(still):.2f}, "
              f"5-95 % {np.percentile(still, 5):.2f}-{np.percentile(still, 95):.2f}, lowest {still.min():.2f}")
    for r in rows:
        if r["effect"] == "terrain_drift" and r["ratio"]:
            print(f"drift {r['seed']} ({r['mode']}): " + ", ".join(f"{c} {v:.2f}" for c, v in r["ratio"].items()))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
