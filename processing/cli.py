"""``wheelsoil process``: recording -> signals table (CSV or Parquet)."""

from __future__ import annotations

import argparse

_EPILOG = """\
examples:
  wheelsoil process run.mcap -o signals.csv
  wheelsoil process run.mcap -o signals.parquet --rate 200 --cutoff 8
  wheelsoil process run.mcap -o signals.csv --config my_vehicle.toml
  wheelsoil process candump-2024-05-01.log -o signals.csv     (log imported first)

output columns (one row per grid point, from the first frame on):
  t_s             time since the first frame [s] (host clock)
  slip            slip ratio s = (r*omega - V)/(r*omega), paper Eq. (6); empty where r*omega < 0.1 m/s
  load_n          vertical load W [N]            (WFT, hub frame, Fz)
  drawbar_pull_n  drawbar pull Dp [N]            (WFT, hub frame: Fx + m_w dV/dt, inertia compensated)
  torque_nm       driving torque T [N m]         (WFT: My - I_w domega/dt, inertia compensated)
  speed_mps       vehicle speed V [m/s]          (GNSS/INS forward velocity, latency removed)
  omega_radps     wheel angular speed [rad/s]    (wheel speed module)
  phase           accel | drive | brake | standstill | other
  valid           all values present, no long frame gap, slip in [-1, 1)
  distance_m      travelled distance [m]         (integral of V)
  fx_n, my_nm     WFT Fx [N] and My [N m] as measured (filtered, before inertia compensation)

Inertia: the WFT measures what the rim + tyre transmit, Fx = Dp - m_w dV/dt and
My = T + I_w domega/dt (m_w = wheel_mass_kg, I_w = wheel_inertia_kgm2 in the vehicle
configuration); both are compensated unless --no-inertia. dV/dt and domega/dt are
derivatives of the filtered V and omega (same filter and cutoff as the forces).

Filtering: zero-phase Butterworth low-pass (order 4, run forward and backward),
per contiguous segment (never across lost-frame gaps longer than 3 samples),
cutoff 5 Hz unless --cutoff; capped at 0.4 x --rate (anti-alias).
The GNSS velocity latency is estimated against the free-rolling front wheels'
r*omega (or, when the fronts turn with the measured wheel, from the GNSS
acceleration against the measured drawbar pull) and removed; the host->GPS
time mapping is fitted from RT_SB_GPS_Time. Frames with timestamps far outside
their neighbours are set aside and listed; logs joined out of order are sorted
(refused when their parts overlap in time).
"""


def register(subparsers) -> None:
    """Add the ``process`` subcommand to the ``wheelsoil`` parser."""
    p = subparsers.add_parser(
        "process",
        help="decode, time-sync, filter a recording and compute slip -> CSV/Parquet",
        description="Decode an MCAP recording with the vehicle's DBC files, put all devices on the "
        "host clock, estimate and remove the GNSS latency, filter, resample and compute slip "
        "(paper Eq. 6). Prints the latency found, the GPS time mapping, lost frames and the "
        "share of valid samples.",
        epilog=_EPILOG,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    p.add_argument("recording", help="MCAP recording (from 'wheelsoil log' or 'wheelsoil import'); "
                   ".log/.asc/.blf/.trc logs are imported on the fly")
    p.add_argument("-o", "--output", required=True,
                   help="output table: .csv or .parquet (columns listed below)")
    p.add_argument("--rate", type=float, default=100.0, metavar="HZ",
                   help="output sample rate [Hz] (default 100)")
    p.add_argument("--cutoff", type=float, default=None, metavar="HZ",
                   help="low-pass cutoff [Hz] (default 5; at least 0.1, at most 0.4 x rate)")
    p.add_argument("--config", "--vehicle", dest="config", default=None, metavar="TOML",
                   help="vehicle configuration (default: the one stored in the recording, "
                   "else the shipped dbc/vehicle.toml)")
    p.add_argument("--wheel-radius", type=float, default=None, metavar="R",
                   help="wheel radius r [m] for slip (Eq. 6), overriding the vehicle configuration's "
                   "(a different value is reported as a conflict); 'wheelsoil fit --wheel-radius' uses it too")
    p.add_argument("--no-inertia", action="store_true",
                   help="do not compensate the wheel's inertia (drawbar_pull_n = Fx, torque_nm = My as measured)")
    wheel_mass_args(p)
    p.add_argument("--progress", action="store_true", help="show a progress bar while decoding")
    p.add_argument("--overwrite", action="store_true", help="replace OUTPUT if it exists (default: keep it, refuse)")
    p.set_defaults(func=_cmd_process)


def wheel_mass_args(p) -> None:
    """Add ``--wheel-mass`` and ``--wheel-inertia`` to the parser ``p`` (``process`` and ``fit`` share them)."""
    p.add_argument("--wheel-mass", type=float, default=None, metavar="KG",
                   help="recordings: mass m_w [kg] of the wheel outboard of the transducer (rim + tyre) for the "
                   "inertia compensation Dp = Fx + m_w dV/dt (default: the vehicle configuration's, 80 kg)")
    p.add_argument("--wheel-inertia", type=float, default=None, metavar="KGM2",
                   help="recordings: its polar moment of inertia I_w [kg m^2] for T = My - I_w domega/dt "
                   "(default: the vehicle configuration's, 11.5 kg m^2); give both with another wheel")


def _cmd_process(args) -> int:
    from pathlib import Path

    from .pipeline import process_recording

    out = Path(args.output)
    suffix = out.suffix.lower()
    if suffix not in (".csv", ".parquet"):
        raise ValueError(f"output {out}: use a .csv or .parquet file name")
    if out.exists() and not args.overwrite:  # before the work, not after it
        raise ValueError(f"output {out} exists (--overwrite replaces it)")
    res = process_recording(args.recording, config=args.config, rate_hz=args.rate,
                            cutoff_hz=args.cutoff, progress=args.progress,
                            wheel_radius_m=args.wheel_radius, inertia=not args.no_inertia,
                            wheel_mass_kg=args.wheel_mass, wheel_inertia_kgm2=args.wheel_inertia)
    tmp = out.with_name(f".{out.name}.part")  # a table is complete or absent, never half-written
    try:
        if suffix == ".csv":
            res.signals.to_csv(tmp, index=False, float_format="%.6g")
        else:
            res.signals.to_parquet(tmp, index=False)
        tmp.replace(out)
    finally:
        tmp.unlink(missing_ok=True)
    print(res.summary())
    print(f"wrote {out}: {len(res.signals)} rows")
    return 0
