"""The diagnosis on runs of a second, independent generator (``benchmarks/foreign/``).

    python benchmarks/bench_foreign.py [--only a1,v15] [--keep DIR]

``benchmarks/foreign/gen.py`` was written from the hardware contract, the DBC files and the paper
alone, by a session that did not read wheelsoil's code, and imports nothing from wheelsoil (its
module doc says where its choices differ from ``wheelsoil.sim``). Each case below is generated as
a candump log, imported (``wheelsoil import``) and fitted as a user would
(``wheelsoil fit run.mcap --terrain sand``), and scored against the generator's truth:

- no effect -> ``none``; Vasil'ev or Lyasko slip sinkage -> ``slip_sinkage`` (the form is shown);
  a phi mismatch -> ``terrain_mismatch``; a gain error of the transducer's Fx, a cause on no
  list -> ``unexplained``;
- a named effect other than the acceptable one is a WRONG named cause; any other verdict a miss.

The 14 cases (sizes: Dp at s = 0.5 and 13 kN lowered by about 5, 15 and 30 %; GNSS latency drawn
in 0.03-0.2 s; front wheels locked to the instrumented one or rolling freely, half each) were
chosen once, before the pipeline was run on them. Prints one row per case (verdict, latency
found against the truth, its method and reliability) and the totals, and the wall time.
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
import time
import warnings
from pathlib import Path

GEN = Path(__file__).resolve().parent / "foreign" / "gen.py"

#: name, generator case, fronts, seed, latency [s], effect options
CASES = [
    ("a1", "a", "locked", 101, 0.062, []), ("a2", "a", "free", 102, 0.200, []), ("a3", "a", "locked", 103, 0.130, []),
    ("v05", "b", "free", 104, 0.172, ["--H", "0.0104"]), ("v15", "b", "locked", 105, 0.075, ["--H", "0.0290"]),
    ("v30", "b", "free", 106, 0.049, ["--H", "0.0528"]),
    ("l05", "c", "locked", 107, 0.164, ["--m1", "0.031", "--m2", "0.0124"]),
    ("l15", "c", "free", 108, 0.118, ["--m1", "0.085", "--m2", "0.034"]),
    ("l30", "c", "locked", 109, 0.189, ["--m1", "0.153", "--m2", "0.0613"]),
    ("p23", "d", "free", 110, 0.140, ["--phi-field", "23"]), ("p21", "d", "locked", 111, 0.063, ["--phi-field", "21"]),
    ("p27", "d", "free", 112, 0.116, ["--phi-field", "27"]),
    ("g104", "e", "locked", 113, 0.145, ["--fx-gain", "1.04"]), ("g112", "e", "free", 114, 0.163, ["--fx-gain", "1.12"]),
]
NAMED = ("slip_sinkage", "terrain_mismatch", "stress_distribution", "terrain_drift")


def generate(name: str, case: str, fronts: str, seed: int, latency_s: float, extra: list, out: Path) -> dict:
    """Run the generator for one case into ``out``; returns its truth dict (``NAME_truth.json``).
    Raises ``subprocess.CalledProcessError`` if the generator fails."""
    subprocess.run([sys.executable, str(GEN), case, "--fronts", fronts, "--seed", str(seed), "--latency",
                    str(latency_s), *extra, "--out", name, "--outdir", str(out)], check=True, capture_output=True)
    return json.loads((out / f"{name}_truth.json").read_text())


def run_case(name: str, case: str, fronts: str, seed: int, latency_s: float, extra: list, out: Path) -> dict:
    """Generate, import and fit one case; returns a row dict (verdict, score, latency)."""
    from wheelsoil.daq.convert import import_log
    from wheelsoil.pipeline import run_fit

    truth = generate(name, case, fronts, seed, latency_s, extra, out)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        rec = import_log(out / f"{name}.log", out / f"{name}.mcap", overwrite=True).output
        rep = run_fit([rec], "sand", out / f"rep_{name}")
    d = rep["diagnosis"]
    ok = {"none": "none", "slip_sinkage": "slip_sinkage", "terrain_mismatch": "terrain_mismatch"}.get(
        truth["effect"], "unexplained")
    score = "right" if d["effect"] == ok else ("WRONG" if d["effect"] in NAMED else "miss")
    q = rep["data_quality"][0]
    lat = (q.get("processing_quality") or {}).get("latency") or {}
    return {"name": name, "fronts": fronts, "truth": f"{truth['model']} {truth['params'] or ''}".strip(),
            "effect": d["effect"], "model": d.get("model"), "confidence": d.get("confidence"), "score": score,
            "form": d.get("model") == truth["model"] if score == "right" and ok == "slip_sinkage" else None,
            "latency_true_s": truth["gnss_latency_s"], "latency_s": q.get("gnss_latency_s"),
            "latency_method": lat.get("method"), "latency_reliable": lat.get("reliable")}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--only", default="", help="comma list of case names (default: all 14)")
    ap.add_argument("--keep", type=Path, default=None, help="keep logs, recordings and reports here")
    args = ap.parse_args()
    only = set(filter(None, args.only.split(",")))
    base = args.keep or Path(tempfile.mkdtemp(prefix="bench_foreign_"))
    base.mkdir(parents=True, exist_ok=True)
    t0 = time.perf_counter()
    rows = []
    print(f"{'case':<5} {'fronts':<6} {'truth':<34} {'verdict (model, confidence)':<44} {'score':<6} latency ms (true): method, reliable")
    for c in CASES:
        if only and c[0] not in only:
            continue
        r = run_case(*c, base)
        rows.append(r)
        lat = "n/a" if r["latency_s"] is None else f"{1e3 * r['latency_s']:.0f}"
        form = "" if r["form"] is None else (" form right" if r["form"] else " form wrong")
        print(f"{r['name']:<5} {r['fronts']:<6} {r['truth'][:34]:<34} "
              f"{r['effect'] + ' (' + str(r['model']) + ', ' + str(r['confidence']) + ')':<44} {r['score'] + form:<6} "
              f"{lat} ({1e3 * r['latency_true_s']:.0f}): {r['latency_method']}, {r['latency_reliable']}", flush=True)
    fam = [r for r in rows if not r["truth"].startswith("sensor_gain")]
    print(f"\nin family right {sum(r['score'] == 'right' for r in fam)}/{len(fam)}; wrong named causes "
          f"{sum(r['score'] == 'WRONG' for r in rows)}/{len(rows)}; latency within 20 ms "
          f"{sum(r['latency_s'] is not None and abs(r['latency_s'] - r['latency_true_s']) <= 0.02 for r in rows)}/{len(rows)}"
          f"; files in {base}; wall time {time.perf_counter() - t0:.0f} s")


if __name__ == "__main__":
    main()
