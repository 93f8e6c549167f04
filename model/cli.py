"""``wheelsoil predict`` and ``wheelsoil terrains``: the model core from the shell."""

from __future__ import annotations

import argparse
import json

_PREDICT_EPILOG = """\
examples:
  wheelsoil predict --terrain clay --model wong --load 11000 --slip 0.1,0.2,0.5
  wheelsoil predict --terrain clay --model lyasko --param m1=0.1 --param m2=0.05 \\
      --load 11000 --slip 0.1,0.2,0.5 --json
  wheelsoil predict --terrain sand --model ding --param n1=0.53 --load 13000 --slip 0.3 --sinkage balance
  wheelsoil predict --terrain my_soil.toml --load 8000,9000 --slip 0.2,0.4 --wheel-radius 0.35

models and parameters (defaults give Wong's model; [bounds] are a fitter's search box):
  wong      no parameters                       z = z0                    (paper Eqs. 1-10)
  vasilev   H [m], [0, 0.2]                     z = z0 + H s              (Eq. 11)
  lyasko    m1 [-], [0, 5]; m2 [-], [0, 0.9]    z = (1+m1 s)/(1-m2 s) z0  (Eq. 12)
  ding      n1 [-], [0, 1]                      N = n + n1 s replaces n   (Eq. 13)

sinkage modes:
  eq10      z0 from Eq. (10), Wong's small-angle closed form (the paper's choice)
  balance   z0 solves Eq. (7) = W at each sample's slip (exact vertical balance);
            the slip-sinkage transform is then applied to that z0

output columns: slip [-], load_n W [N], sinkage_m z [m], theta1_rad [rad],
drawbar_pull_n Dp [N], torque_nm T [N m], load_model_n (model's W from Eq. 7) [N].
--json prints a JSON list of objects with exactly these keys.
Terrains: built-in slugs (see 'wheelsoil terrains') or a TOML file (c_kpa,
phi_deg, K_m, n, kc [kN/m^(n+1)], kphi [kN/m^(n+2)]).
"""

_TERRAINS_EPILOG = """\
units: c [kPa], phi [deg], K [m], n [-], kc [kN/m^(n+1)], kphi [kN/m^(n+2)]
(as written in terrain TOML files; converted to SI inside the code).

A custom terrain file (use it as --terrain my_soil.toml):
  name = "My field soil"
  c_kpa = 5.0
  phi_deg = 20.0
  K_m = 0.02
  n = 0.8
  kc = 20.0
  kphi = 800.0
  source = "plate-sinkage and shear tests, 2026-05-01"
"""

_KEYS = ("slip", "load_n", "sinkage_m", "theta1_rad", "drawbar_pull_n", "torque_nm", "load_model_n")


def _floats(text: str, what: str) -> list[float]:
    try:
        values = [float(v) for v in text.split(",") if v.strip()]
    except ValueError:
        raise ValueError(f"{what}: expected comma-separated numbers, got {text!r}") from None
    if not values:
        raise ValueError(f"{what}: no values given")
    return values


def _params(items: list[str] | None) -> dict[str, float]:
    out: dict[str, float] = {}
    for item in items or []:
        name, sep, value = item.partition("=")
        if not sep or not name.strip():
            raise ValueError(f"--param {item!r}: expected NAME=VALUE, e.g. --param m1=0.1")
        try:
            out[name.strip()] = float(value)
        except ValueError:
            raise ValueError(f"--param {item!r}: value {value!r} is not a number") from None
    return out


def _predict(args: argparse.Namespace) -> int:
    import numpy as np

    from wheelsoil.model import Wheel, get_model, load_terrain
    from wheelsoil.model.terrain import check_k_eq

    terrain = load_terrain(args.terrain)
    wheel = Wheel(args.wheel_radius, args.wheel_width)
    check_k_eq(terrain, wheel.width, f"--terrain {args.terrain}")
    model = get_model(args.model)
    load = np.asarray(_floats(args.load, "--load"))
    slip = np.asarray(_floats(args.slip, "--slip"))
    if len(load) not in (1, len(slip)) and len(slip) != 1:
        raise ValueError(f"--load has {len(load)} values and --slip {len(slip)}: give one load or one per slip")
    load, slip = np.broadcast_arrays(load, slip)
    forces = model.predict(terrain, wheel, load, slip, _params(args.param), sinkage=args.sinkage)
    columns = {
        "slip": slip,
        "load_n": load,
        "sinkage_m": forces.sinkage_m,
        "theta1_rad": forces.theta1_rad,
        "drawbar_pull_n": forces.drawbar_pull_n,
        "torque_nm": forces.torque_nm,
        "load_model_n": forces.load_model_n,
    }
    rows = [{key: float(columns[key][i]) for key in _KEYS} for i in range(len(slip))]
    if args.json:
        print(json.dumps(rows, indent=2))
        return 0
    params = model.resolve(_params(args.param))
    ptext = ", ".join(f"{k}={v:g}" for k, v in params.items()) or "no parameters"
    print(f"terrain {terrain.name} | model {model.name} ({ptext}) | wheel r={wheel.radius:g} m "
          f"b={wheel.width:g} m | sinkage {args.sinkage}")
    header = ("slip", "W [N]", "z [m]", "theta1 [deg]", "Dp [N]", "T [N m]", "W model [N]")
    print("  ".join(f"{h:>12s}" for h in header))
    for row in rows:
        cells = (
            f"{row['slip']:.4f}",
            f"{row['load_n']:.1f}",
            f"{row['sinkage_m']:.5f}",
            f"{np.degrees(row['theta1_rad']):.3f}",
            f"{row['drawbar_pull_n']:.1f}",
            f"{row['torque_nm']:.1f}",
            f"{row['load_model_n']:.1f}",
        )
        print("  ".join(f"{c:>12s}" for c in cells))
    return 0


def _terrains(args: argparse.Namespace) -> int:
    from wheelsoil.model import TERRAINS

    entries = [{"slug": slug, **terrain.field_units()} for slug, terrain in TERRAINS.items()]
    if args.json:
        print(json.dumps(entries, indent=2))
        return 0
    print(f"{'slug':24s} {'c kPa':>7s} {'phi deg':>7s} {'K m':>6s} {'n':>5s} {'kc':>8s} {'kphi':>8s}  source")
    for e in entries:
        print(f"{e['slug']:24s} {e['c_kpa']:7.2f} {e['phi_deg']:7.1f} {e['K_m']:6.3f} {e['n']:5.2f} "
              f"{e['kc']:8.2f} {e['kphi']:8.2f}  {e['source']}")
    print("\nunits: c [kPa], phi [deg], K [m], n [-], kc [kN/m^(n+1)], kphi [kN/m^(n+2)]")
    return 0


def register(subparsers) -> None:
    """Add the ``predict`` and ``terrains`` subcommands to the ``wheelsoil`` parser."""
    from wheelsoil.model.terrain import DEFAULT_WHEEL

    p = subparsers.add_parser(
        "predict",
        help="wheel forces (Dp, T, W, sinkage) of Wong's or a slip-sinkage model",
        description="Predict drawbar pull Dp, torque T, sinkage z and the model's vertical load for "
        "given loads and slips with Wong's rigid-wheel model (paper Eqs. 1-10) or a slip-sinkage "
        "model (Eqs. 11-13).",
        epilog=_PREDICT_EPILOG,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    p.add_argument("--terrain", required=True, help="built-in terrain slug (clay, sand, dry-sand, ...) or a TOML file")
    p.add_argument("--model", default="wong",
                   help="wong | vasilev | lyasko | ding | ding_stress (Eq. 13 with N in the stress only) "
                        "(default wong)")
    p.add_argument("--param", action="append", metavar="NAME=VALUE",
                   help="model parameter, repeatable (e.g. --param m1=0.1 --param m2=0.05); default 0")
    p.add_argument("--load", required=True, help="vertical load W [N], one value or comma-separated per slip")
    p.add_argument("--slip", required=True, help="slip s in [0, 1), comma-separated (e.g. 0.1,0.2,0.5)")
    p.add_argument("--wheel-radius", type=float, default=DEFAULT_WHEEL.radius,
                   help=f"wheel radius r [m] (default {DEFAULT_WHEEL.radius})")
    p.add_argument("--wheel-width", type=float, default=DEFAULT_WHEEL.width,
                   help=f"wheel contact width b [m] (default {DEFAULT_WHEEL.width})")
    p.add_argument("--sinkage", choices=("eq10", "balance"), default="eq10",
                   help="static sinkage from Eq. (10) (default) or from the vertical balance Eq. (7) = W")
    p.add_argument("--json", action="store_true", help="print a JSON list of objects instead of a table")
    p.set_defaults(func=_predict)

    t = subparsers.add_parser(
        "terrains",
        help="list the built-in terrains with values and sources",
        description="List the built-in terrain library (paper Tab. 1; Wong, Theory of Ground "
        "Vehicles, Tab. 2.3) in field units, with sources.",
        epilog=_TERRAINS_EPILOG,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    t.add_argument("--json", action="store_true", help="print a JSON list of objects instead of a table")
    t.set_defaults(func=_terrains)
