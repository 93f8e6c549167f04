"""Real measured data: every table of the CMU single-wheel data set through ``wheelsoil fit``.

    python benchmarks/bench_cmu.py [--out DIR]

The tables in ``tests/data/cmu-3d-terramechanics/`` (a smooth and a grousered wheel in dry sand,
slip angle 0 to 90 deg, 27 runs each, measured sinkage, no torque; see ``make_tables.py`` there)
are fitted as the README's CMU command does (``--terrain dry-sand --fit-terrain``, the wheel from
each table's sidecar JSON). No truth is known for real data: what can be checked is that no
cause the data contradict is named. The measured sinkage grows with slip in 13 of the 14 tables
(slip sinkage is there to be found), and at a slip angle the soil is also sheared sideways, a cause on
no list, so ``slip_sinkage``, ``unexplained`` and, as a miss, ``none`` are the verdicts the data
allow; a terrain mismatch, stress distribution or drift named from a table whose terrain was
fitted is counted as a wrong named cause.

Prints one row per table: wheel, slip angle, the measured sinkage's slope with slip (load held
fixed), Wong's drawbar-pull R0 out of sample, the verdict and its confidence, the per-channel
verdicts, and the wall time.
"""

from __future__ import annotations

import argparse
import tempfile
import time
from pathlib import Path

DATA = Path(__file__).resolve().parents[1] / "tests" / "data" / "cmu-3d-terramechanics"
ALLOWED = ("slip_sinkage", "unexplained", "none")


def tables() -> list[Path]:
    """The data set's tables (smooth first, then grousered; by slip angle)."""
    def key(p: Path):
        wheel, beta = p.stem.split("_")[1:3]
        return (wheel != "smooth", int(beta.removeprefix("beta")))
    return sorted(DATA.glob("cmu_*_beta*.csv"), key=key)


def run(table: Path, out: Path) -> dict:
    """Fit one table as the README's CMU command does; returns the report dict."""
    from wheelsoil.pipeline import run_fit

    return run_fit([table], "dry-sand", out, fit_terrain=True)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--out", type=Path, default=None, help="keep the reports here (default: a temporary directory)")
    args = ap.parse_args()
    base = args.out or Path(tempfile.mkdtemp(prefix="bench_cmu_"))
    t0 = time.perf_counter()
    wrong = 0
    print(f"{'table':<22} {'beta':>4} {'dz/ds mm':>12} {'Wong Dp cvR0 N':>14}  verdict (confidence)            Dp / z channels")
    found = tables()
    for t in found:
        rep = run(t, base / t.stem)
        d = rep["diagnosis"]
        ev = d.get("sinkage_evidence") or {}
        cv = d["models"]["wong"]["metrics"]["drawbar_pull_n"]["cv_R0"]
        ch = d["channels"]
        verdict = f"{d['effect']}" + (f" ({d['model']})" if d["effect"] in ("slip_sinkage",) else "")
        ok = d["effect"] in ALLOWED
        wrong += not ok
        slope = f"{1000 * ev.get('slope', float('nan')):.1f}+-{1000 * ev.get('stderr', float('nan')):.1f}"
        print(f"{t.stem:<22} {t.stem.split('beta')[1]:>4} {slope:>12} {cv:>14.3f}  "
              f"{verdict + ' (' + d['confidence'] + ')':<32} {ch['drawbar_pull_n']['effect']} / {ch['sinkage_m']['effect']}"
              f"{'' if ok else '   <- WRONG NAMED CAUSE'}")
    print(f"\nwrong named causes: {wrong}/{len(found)}; reports in {base}; wall time {time.perf_counter() - t0:.1f} s")


if __name__ == "__main__":
    main()
