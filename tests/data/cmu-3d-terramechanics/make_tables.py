"""Write the CMU single-wheel tables beside this file from the data set's processed results.

Source: ``raw-data-processing/all_smooth_data.mat`` and ``all_grouser_data.mat`` (struct
``all_results``: one element per test run, mean forces over the run) of the public repository
robomechanics/3d-terramechanics, commit 55a6e92 (MIT licence, LICENSE beside this file).
The conversion is the one of ``shared/data/cmu-grouser-wheel`` (its JSON), which it reproduces
for the grousered wheel at slip angle 0, following the owners' ``average_data_to_model.m``:

- ``slip`` = (Vry - 10) / max(10, Vry), Vry the run's mean rim speed [mm/s], 10 mm/s the
  carriage speed (Wong's s = 1 - V/(r w) driving, s = r w/V - 1 skidding);
- ``load_n`` = -avg_Fz, ``drawbar_pull_n`` = -avg_Fy [N] (along the wheel's heading),
  ``sinkage_m`` = -avg_Z / 1000.

One table per wheel (smooth, grousered) and slip angle beta (0, 15, ..., 90 deg), rows sorted by
slip; each with a sidecar JSON stating the wheel (r 0.0625 m: the smooth wheel's radius and the
grouser tips', b 0.06 m; CAD of the same lab) and the slip angle.

    python make_tables.py /path/to/3d-terramechanics/raw-data-processing
"""

import csv
import json
import sys
from pathlib import Path

from scipy.io import loadmat

HERE = Path(__file__).resolve().parent
WHEEL = {"radius_m": 0.0625, "width_m": 0.06}


def main(src: Path) -> None:
    for wheel in ("smooth", "grouser"):
        runs = loadmat(src / f"all_{wheel}_data.mat", squeeze_me=True, struct_as_record=False)["all_results"]
        for beta in sorted({int(round(float(r.beta))) for r in runs}):
            rows = []
            for r in runs:
                if int(round(float(r.beta))) != beta:
                    continue
                vry = float(r.avg_Vry)
                rows.append(((vry - 10.0) / max(10.0, vry), -float(r.avg_Fz), -float(r.avg_Fy), -float(r.avg_Z) / 1000))
            rows.sort()
            name = f"cmu_{wheel}_beta{beta}"
            with open(HERE / f"{name}.csv", "w", newline="") as fh:
                w = csv.writer(fh, lineterminator="\n")
                w.writerow(["slip", "load_n", "drawbar_pull_n", "sinkage_m"])
                w.writerows([f"{v:.6g}" for v in row] for row in rows)
            side = {"wheel": dict(WHEEL, kind=wheel), "slip_angle_deg": beta, "rows": len(rows),
                    "source": "robomechanics/3d-terramechanics 55a6e92, raw-data-processing/"
                              f"all_{wheel}_data.mat, runs with beta == {beta}; see make_tables.py"}
            (HERE / f"{name}.json").write_text(json.dumps(side, indent=1) + "\n")


if __name__ == "__main__":
    main(Path(sys.argv[1]))
