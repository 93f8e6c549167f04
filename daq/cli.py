"""``wheelsoil log | import | export | info | replay | decode | recover``: thin wrappers over wheelsoil.daq."""

from __future__ import annotations

import argparse
import json
import sys

_RAW = argparse.RawDescriptionHelpFormatter

_BUS_HELP = ("bus to use, [NAME=]INTERFACE:CHANNEL[,key=value...] (python-can interface and "
             "channel); repeat for several buses. NAME is the bus name in the recording and the "
             "vehicle config (default: the channel when it is a plain name like can0)")


def register(subparsers) -> None:
    """Add the daq subcommands to the ``wheelsoil`` parser."""
    p = subparsers.add_parser(
        "log", formatter_class=_RAW, help="record CAN buses into an MCAP file (field logger)",
        description="Record raw CAN frames of one or more python-can buses into an MCAP recording.\n"
        "Shows a status line every second: frames/s per bus, lost WFT frames (Counter gaps),\n"
        "error frames/bus errors, kernel receive drops (SocketCAN), file size.\n"
        "SIGINT/SIGTERM close the file cleanly; after a SIGKILL or power cut everything but the\n"
        "last ~0.6 s is in the file (chunks are closed and fsynced every 0.5 s).",
        epilog="examples:\n"
        "  wheelsoil log --bus socketcan:can0 --bus socketcan:can1 -o run.mcap\n"
        "  wheelsoil log --bus socketcan:can0 --bus socketcan:can1 -o field.mcap --split-minutes 10\n"
        "  wheelsoil log --bus can0=udp_multicast:239.0.0.1 --duration 60 -o test.mcap\n"
        "  wheelsoil log --bus can0=virtual:ch0 -o sim.mcap --vehicle my_vehicle.toml\n"
        "systemd unit example: daq/wheelsoil-logger.service")
    p.add_argument("--bus", action="append", required=True, metavar="SPEC", help=_BUS_HELP)
    p.add_argument("-o", "--output", required=True,
                   help="output .mcap file; if it exists the recording goes to OUTPUT-001.mcap, -002, ... "
                   "(never over an existing file) unless --overwrite")
    p.add_argument("--overwrite", action="store_true", help="replace OUTPUT if it exists")
    p.add_argument("--duration", type=float, default=None, metavar="S", help="stop after S seconds (default: until SIGINT/SIGTERM)")
    p.add_argument("--split-minutes", type=float, default=None, metavar="M",
                   help="start a new file every M minutes: OUTPUT_0001.mcap, OUTPUT_0002.mcap, ...")
    p.add_argument("--vehicle", default=None, metavar="TOML", help="vehicle configuration (default: the shipped dbc/vehicle.toml)")
    p.add_argument("--rcvbuf-bytes", type=int, default=None, metavar="B",
                   help="socket receive buffer asked for on socketcan buses, bytes (default 64 MiB, about 10 s of both buses saturated; needs CAP_NET_ADMIN or a large net.core.rmem_max)")
    p.add_argument("--max-frames", type=int, default=None, metavar="N", help="stop after N frames (tests)")
    p.add_argument("-q", "--quiet", action="store_true", help="no status line")
    p.set_defaults(func=_cmd_log)

    p = subparsers.add_parser(
        "import", formatter_class=_RAW, help="convert candump .log / .asc / .blf / .trc into MCAP",
        description="Convert logs of other tools into a wheelsoil MCAP recording (python-can readers).\n"
        "Channel -> bus: python-can channel c (ASC/BLF/TRC file channel c+1) becomes bus canC;\n"
        "named channels (candump's can0, vcan1) keep their name. Unparsable lines are skipped\n"
        "and reported with file:line.",
        epilog="examples:\n  wheelsoil import candump-2024-05-03.log -o run.mcap\n"
        "  wheelsoil import drive.asc -o run.mcap --map can0=can1   (ASC channel 1 is the GNSS bus)\n"
        "  wheelsoil import a.log b.log -o run.mcap --map vcan0=can0 --map vcan1=can1\n"
        "  wheelsoil import wft.trc wss.trc -o run.mcap --map wss.trc:can0=can1   (one bus per file: TRC 1.x)")
    p.add_argument("inputs", nargs="+", help="input log file(s), format from the suffix")
    p.add_argument("-o", "--output", required=True, help="output .mcap file")
    p.add_argument("--map", action="append", default=[], metavar="SRC=BUS",
                   help="name bus BUS what the file calls SRC (python-can channel or default bus name); "
                   "FILE:SRC=BUS for the input FILE only; repeatable")
    p.add_argument("--vehicle", default=None, metavar="TOML", help="vehicle configuration to attach (default: shipped)")
    p.add_argument("--overwrite", action="store_true", help="replace OUTPUT if it exists (default: keep it, refuse)")
    p.set_defaults(func=_cmd_import)

    p = subparsers.add_parser(
        "export", formatter_class=_RAW, help="write an MCAP recording as candump .log / .asc / .blf / .trc",
        description="Write the raw frames of a recording with python-can's writers, all buses merged\n"
        "by time. Ids, flags, DLC and data are bit-exact; candump .log keeps absolute timestamps\n"
        "to the microsecond and the bus name as the channel.",
        epilog="examples:\n  wheelsoil export run.mcap -o run.log\n  wheelsoil export run.mcap -o run.blf --bus can0\n"
        "  wheelsoil export run.mcap -o run.log --map can0=vcan0")
    p.add_argument("recording")
    p.add_argument("-o", "--output", required=True, help="output file; format from the suffix")
    p.add_argument("--bus", action="append", default=None, metavar="NAME", help="only these buses (repeatable)")
    p.add_argument("--map", action="append", default=[], metavar="BUS=CHANNEL",
                   help="channel name written for BUS (default: the bus name); repeatable")
    p.add_argument("--overwrite", action="store_true", help="replace OUTPUT if it exists (default: keep it, refuse)")
    p.set_defaults(func=_cmd_export)

    p = subparsers.add_parser(
        "info", formatter_class=_RAW, help="summarise a recording: buses, ids, duration, losses",
        description="Summarise a recording: channels, frames per bus and per id with DBC message\n"
        "names, duration, lost WFT frames (Counter gaps), error frames, unknown ids, DLC\n"
        "mismatches, kernel drops, damage. DBCs: those attached to the recording.",
        epilog="examples:\n  wheelsoil info run.mcap\n  wheelsoil info run.mcap --json | jq .lost_frames")
    p.add_argument("recording")
    p.add_argument("--json", action="store_true", help="print JSON instead of text")
    p.add_argument("--vehicle", default=None, metavar="TOML", help="use this vehicle configuration instead of the attached one")
    p.set_defaults(func=_cmd_info)

    p = subparsers.add_parser(
        "replay", formatter_class=_RAW, help="send a recording onto CAN buses with the recorded timing",
        description="Send the frames of a recording onto python-can buses with the recorded timing\n"
        "(like canplayer). --bus NAME=SPEC sends recorded bus NAME there; unnamed --bus options\n"
        "take the recorded buses in sorted order, a single unnamed one takes all of them.",
        epilog="examples:\n  wheelsoil replay run.mcap --bus socketcan:vcan0\n"
        "  wheelsoil replay run.mcap --bus can0=socketcan:vcan0 --bus can1=socketcan:vcan1 --speed 2\n"
        "  wheelsoil replay run.mcap --bus can0=udp_multicast:239.0.0.1 --speed 0   (as fast as possible)")
    p.add_argument("recording")
    p.add_argument("--bus", action="append", required=True, metavar="SPEC", help=_BUS_HELP)
    p.add_argument("--speed", type=float, default=1.0, help="time factor (2 = twice as fast; 0 = no waiting). Default 1")
    p.set_defaults(func=_cmd_replay)

    p = subparsers.add_parser(
        "decode", formatter_class=_RAW, help="add decoded signals as JSON channels (Foxglove) to a recording copy",
        description="Copy a recording and add one JSON channel per DBC message, /decoded/<bus>/<Message>,\n"
        "one message per frame with the physical signal values (DBC factor/offset applied),\n"
        "log_time = the frame's receive time: open the output in Foxglove and plot signals.\n"
        "DBCs: those attached to the recording (or --vehicle). Raw frames are copied unchanged.",
        epilog="example:\n  wheelsoil decode run.mcap -o run.decoded.mcap")
    p.add_argument("recording")
    p.add_argument("-o", "--output", required=True)
    p.add_argument("--bus", action="append", default=None, metavar="NAME", help="only decode these buses (repeatable)")
    p.add_argument("--vehicle", default=None, metavar="TOML", help="use this vehicle configuration's DBCs")
    p.add_argument("--overwrite", action="store_true", help="replace OUTPUT if it exists (default: keep it, refuse)")
    p.set_defaults(func=_cmd_decode)

    p = subparsers.add_parser(
        "recover", formatter_class=_RAW, help="rewrite a truncated/damaged recording into a clean one",
        description="Rewrite a recording cut short (power loss, SIGKILL) into a complete, indexed MCAP\n"
        "file with every verified chunk (CRC checked), its metadata and attachments; what was\n"
        "dropped is recorded in the metadata record wheelsoil.recovered.",
        epilog="example:\n  wheelsoil recover field_0003.mcap -o field_0003.fixed.mcap")
    p.add_argument("recording")
    p.add_argument("-o", "--output", required=True)
    p.add_argument("--overwrite", action="store_true", help="replace OUTPUT if it exists (default: keep it, refuse)")
    p.set_defaults(func=_cmd_recover)


def _config(path):
    from .config import load_vehicle_config

    return load_vehicle_config(path)


def _cmd_log(args) -> int:
    from .logger import format_status, log_buses

    tty = sys.stderr.isatty()
    count = [0]

    def show(st):
        count[0] += 1
        if args.quiet:
            return
        if tty:
            print("\r" + format_status(st), end="", file=sys.stderr, flush=True)
        elif count[0] % 10 == 1:
            print(format_status(st), file=sys.stderr, flush=True)

    from .buses import parse_bus_specs

    config = _config(args.vehicle)
    specs = parse_bus_specs(args.bus)
    for s in specs:
        if s.name not in config.buses:
            print(f"warning: bus {s.name} is not in the vehicle configuration ({', '.join(config.buses)}); "
                  f"its frames are recorded but not matched to a DBC. Name it, e.g. "
                  f"--bus {next(iter(config.buses))}={s.interface}:{s.channel}", file=sys.stderr)
    res = log_buses(specs, args.output, config=config, duration_s=args.duration,
                    split_minutes=args.split_minutes, max_frames=args.max_frames,
                    rcvbuf_bytes=args.rcvbuf_bytes, on_status=show, handle_signals=True,
                    metadata={"command": " ".join(sys.argv)}, overwrite=args.overwrite,
                    command=["wheelsoil", *sys.argv[1:]] if sys.argv else None)
    if tty and not args.quiet:
        print(file=sys.stderr)
    st = res.status
    from pathlib import Path

    if res.files and not args.split_minutes and Path(res.files[0]) != Path(args.output):
        print(f"note: {args.output} exists and is kept; recorded into {res.files[0]} "
              "(--overwrite replaces it)", file=sys.stderr)
    print(f"recorded {sum(res.frames.values())} frames ({_counts(res.frames)}) "
          f"into {', '.join(map(str, res.files))}; stop: {res.stop_reason}")
    lost = sum(b["lost_wft_frames"] for b in st["buses"].values())
    est = sum(b.get("lost_frames_estimated") or 0 for b in st["buses"].values())
    drops = [b["rx_dropped"] for b in st["buses"].values()]
    unknown = [name for name, b in st["buses"].items() if b["rx_dropped"] is None]
    known = sum(d for d in drops if d is not None)
    if lost or est or known or unknown or st.get("bad_frames"):
        parts = [f"{b['rx_dropped']} on {name}" for name, b in st["buses"].items() if b["rx_dropped"] is not None]
        if unknown:
            parts.append(f"unknown on {', '.join(unknown)} (the interface cannot report drops)")
        drop_txt = ", ".join(parts)
        print(_safe(f"warning: lost WFT frames {lost} (counter gaps), frames missing by cycle time {est}, "
                    f"kernel rx drops {drop_txt}, unrecordable frames {st.get('bad_frames', 0)}"),
              file=sys.stderr)
    return 0


def _overwrite_kw(fn, args) -> dict:
    """``{"overwrite": ...}`` for library writers that take it (import/export do their own
    atomic write and output check), else {} (the CLI checked the output itself)."""
    import inspect

    try:
        return {"overwrite": args.overwrite} if "overwrite" in inspect.signature(fn).parameters else {}
    except (TypeError, ValueError):
        return {}


def _counts(d: dict) -> str:
    return ", ".join(f"{b} {n}" for b, n in d.items()) or "no bus"


def _safe(text: str) -> str:
    """``text`` with control characters (terminal escape sequences) shown as escapes."""
    from .recording import _printable

    return "\n".join(_printable(line) for line in str(text).split("\n"))


def _print_warnings(ws, limit=20):
    for w in ws[:limit]:
        print(_safe(f"warning: {w}"), file=sys.stderr)
    if len(ws) > limit:
        print(f"warning: ... and {len(ws) - limit} more", file=sys.stderr)


def _cmd_import(args) -> int:
    import warnings

    from .convert import import_log, parse_channel_map
    from .recording import check_output

    check_output(args.output, args.inputs, overwrite=args.overwrite)
    config = _config(args.vehicle)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        res = import_log(args.inputs, args.output, channel_map=parse_channel_map(args.map),
                         config=config, **_overwrite_kw(import_log, args))
    _print_warnings(res.warnings)
    print(_safe(f"imported {res.total} frames ({_counts(res.frames)}) into "
                f"{res.output}" + (f"; skipped {res.skipped} unparsable line(s)" if res.skipped else "")))
    if args.vehicle is None:  # a log file carries no vehicle: slip (Eq. 6) is computed with this wheel
        print(_safe(f"note: attached the shipped vehicle configuration ({config.source}: wheel radius "
                    f"{config.wheel_radius_m:g} m, width {config.wheel_width_m:g} m); give --vehicle TOML "
                    "if the run used another wheel"))
    return 0


def _cmd_export(args) -> int:
    import os
    import secrets
    from pathlib import Path

    from .convert import export_recording, parse_channel_map
    from .recording import check_output

    out = check_output(args.output, [args.recording], overwrite=args.overwrite)
    kw = _overwrite_kw(export_recording, args)
    if kw:  # export_recording writes atomically itself
        tmp = out
        res = export_recording(args.recording, out, channel_map=parse_channel_map(args.map), buses=args.bus, **kw)
    else:  # write a temporary file next to the output, rename it into place only on success
        tmp = out.with_name(f".{out.stem}.tmp-{secrets.token_hex(4)}{out.suffix}")
        try:
            res = export_recording(args.recording, tmp, channel_map=parse_channel_map(args.map), buses=args.bus)
            os.replace(tmp, out)
        finally:
            if tmp.exists():
                tmp.unlink()
    res.output = Path(out)
    _print_warnings([w.replace(str(tmp), str(out)) for w in res.warnings])
    print(_safe(f"exported {res.total} frames ({_counts(res.frames)}) to {out}"))
    return 0


def _cmd_decode(args) -> int:
    from .decode_json import decode_recording
    from .recording import check_output

    check_output(args.output, [args.recording], overwrite=args.overwrite)
    res = decode_recording(args.recording, args.output, buses=args.bus,
                           config=_config(args.vehicle) if args.vehicle else None)
    _print_warnings(res.warnings)
    print(_safe(f"decoded {res.decoded} of {res.total} frames into JSON channels of {res.output}"))
    return 0


def _cmd_recover(args) -> int:
    from .convert import recover_recording
    from .recording import check_output

    check_output(args.output, [args.recording], overwrite=args.overwrite)
    res = recover_recording(args.recording, args.output)
    _print_warnings(res.warnings)
    print(_safe(f"recovered {res.total} frames ({_counts(res.frames)}) into {res.output}"))
    return 0


def _cmd_replay(args) -> int:
    import signal
    import threading

    from .replay import MAX_REPLAY_GAP_S, replay_recording

    stop = threading.Event()
    old = signal.signal(signal.SIGTERM, lambda *_: stop.set())
    try:
        res = replay_recording(args.recording, args.bus, speed=args.speed, stop_event=stop)
    finally:
        signal.signal(signal.SIGTERM, old)
    if res.gaps_skipped:
        print(f"warning: {res.gaps_skipped} recorded gap(s) longer than {MAX_REPLAY_GAP_S:g} s "
              f"({res.gap_skipped_s:.0f} s in all; a host clock step?) not waited for", file=sys.stderr)
    print(f"sent {sum(res.sent.values())} frames ({_counts(res.sent)}) "
          f"in {res.wall_s:.1f} s" + (f"; {res.send_failures} frames could not be sent" if res.send_failures else ""))
    return 1 if res.send_failures else 0


def _cmd_info(args) -> int:
    from .info import read_recording_info

    info = read_recording_info(args.recording, config=_config(args.vehicle) if args.vehicle else None)
    if args.json:
        print(json.dumps(info.to_dict(), indent=1, default=str))
        return 0
    print(format_info(info))
    return 0


def format_info(info) -> str:
    """Human-readable text of a :class:`~wheelsoil.daq.info.RecordingInfo` (control
    characters and terminal escape sequences from the file are shown escaped, never raw)."""
    from .stats import LONG_GAP_NS

    d = info.to_dict()
    if info.complete:
        state = "complete"
    elif info.damage and info.footer:
        state = "DAMAGED (damaged parts skipped, see below; wheelsoil recover writes a clean copy)"
    else:
        state = "INCOMPLETE (no footer: truncated; run wheelsoil recover)"
    out = [f"{info.path}: {info.size_bytes / 1e6:.2f} MB, {state}"]
    rec = info.metadata.get("wheelsoil.recording", {})
    if info.start_ns is not None:
        out.append(f"  frames from {_utc(info.start_ns)} to {_utc(info.end_ns)} UTC, "
                   f"duration {info.duration_s:.3f} s")
    if info.outlier_frames:
        tb = info.time.get("outliers", {})
        ex = "; ".join(f"{e['bus']} frame {e['frame']} at {_utc(e['t_ns'])}" for e in tb.get("examples", [])[:3])
        out.append(f"  OUTLIER TIMESTAMPS: {info.outlier_frames} frame(s) far outside the run ({ex}); "
                   "not counted in the first/last time and duration")
    if info.time.get("gaps_s"):
        out.append("  gaps of more than an hour inside the run: "
                   + ", ".join(f"{g / 3600:.2f} h" for g in info.time["gaps_s"])
                   + " (a pause of the logger, or a step of the host clock that 'wheelsoil process' finds with "
                   "GPS time and undoes; the lost frames below do not count the frames across them)")
    for bus, n in sorted(info.non_monotonic.items()):
        back = info.time.get("max_backward_s", {}).get(bus, 0.0)
        out.append(f"  NON-MONOTONIC TIME on {bus}: {n} backward step(s), largest {back:.6g} s "
                   "(logs joined out of order?)")
    prov = info.provenance
    if prov:
        kind = prov.get("kind", "?")
        line = f"  provenance: {kind}, written by wheelsoil {prov.get('wheelsoil_version', '?')} on " \
               f"{prov.get('host', '?')} at {prov.get('created_utc', '?')}"
        if kind == "recorded":
            line += f"; adapters: {', '.join(map(str, prov.get('adapters') or [])) or '?'}"
        elif kind == "imported":
            srcs = prov.get("sources") or []
            line += "; from " + ", ".join(
                f"{s.get('path', '?')} (sha256 {str(s.get('sha256', '?'))[:16]}..., {s.get('size_bytes', '?')} B)"
                if isinstance(s, dict) else str(s) for s in srcs)
        elif kind == "simulated":
            line += f"; simulator {prov.get('simulator', '?')}, seed {prov.get('seed', '?')}"
        if prov.get("command"):
            cmd = prov["command"]
            line += f"; command: {' '.join(map(str, cmd)) if isinstance(cmd, list) else cmd}"
        out.append(line)
    elif rec:
        out.append(f"  recorded on {rec.get('host', '?')} with wheelsoil {rec.get('version.wheelsoil', '?')}, "
                   f"started {rec.get('start_time_utc', '?')} (no provenance record)")
    out.append(f"  DBC source: {info.config_source}; attachments: {', '.join(info.attachments) or 'none'}")
    out.append("  channels:")
    for c in info.channels:
        out.append(f"    {c['topic']:<28} {c['schema'] or '-'} ({c['encoding']})")
    for bus, b in d["buses"].items():
        drop = "" if b["rx_dropped"] is None else f", kernel rx drops {b['rx_dropped']}"
        rate = b["frames"] / info.duration_s if info.duration_s > 0 else 0.0
        no_dbc = bus not in info.stats.names  # a bus the configuration gives no DBC: its ids are not "unknown"
        out.append(f"  bus {bus}: {b['frames']} frames ({rate:.0f}/s), error frames {b['error_frames']}, "
                   f"remote {b['remote_frames']}{drop}" + ("; no DBC configured for it" if no_dbc else ""))
        for fid, v in b["ids"].items():
            bad = b["dlc_mismatch"].get(fid, {}).get("frames", 0)
            out.append(f"    {fid:>12} {v['frames']:>10}  {v.get('message', '(no DBC)' if no_dbc else '(unknown id)')}"
                       + (f"  DLC mismatch: {bad}" if bad else ""))
    s = info.stats
    out.append(f"  lost frames (counter gaps): {s.total('lost_frames')}"
               + (f" ({', '.join(f'{k} {v}' for k, v in sorted(s.lost_frames.items()))})" if s.lost_frames else ""))
    if s.counter_stride:
        out.append("  counter steps per frame: " + ", ".join(f"{k} {v}" for k, v in sorted(s.counter_stride.items()))
                   + " (the transducer sends one sample in that many: a decimated output rate; lost frames are "
                   "counted in frames of that rate)")
    if s.lost_frames_estimated:
        out.append(f"  frames missing by nominal cycle time (estimate): {s.total('lost_frames_estimated')} ("
                   + ", ".join(f"{k} {v}" for k, v in sorted(s.lost_frames_estimated.items())) + ")")
    if s.long_gaps:
        out.append(f"  not counted as lost: {s.total('long_gaps')} interval(s) longer than {LONG_GAP_NS / 3.6e12:g} h "
                   "between frames of one message (" + ", ".join(f"{k} {v}" for k, v in sorted(s.long_gaps.items()))
                   + "): a pause of the logger or a step of the host clock")
    out.append(f"  unknown-id frames: {s.total('unknown_ids')}, DLC mismatches: {s.total('dlc_mismatch')}, "
               f"error frames: {s.total('error_frames')}")
    if info.damage:
        lost = info.frames_lost_to_damage
        out.append(f"  DAMAGE: {len(info.damage)} damaged place(s) skipped, frames lost "
                   f"{'unknown' if lost is None else lost}")
    for w in info.warnings:
        out.append(f"  warning: {w}")
    return _safe("\n".join(out))


def _utc(t_ns) -> str:
    from .info import _fmt_ns

    return _fmt_ns(int(t_ns))
