"""Benchmark of wheelsoil.daq: logger CPU per frame vs python-can's own logging path,
import and read rates, bytes per frame (MCAP vs candump .log vs BLF).

Run: python benchmarks/bench_daq.py [--frames N] [--repeat R]

Feed: the vehicle's traffic (WFT 3x500 Hz + diag on can0; wheel speed, status,
GNSS on can1; signals packed with cantools from the shipped DBCs, smooth values
plus noise, timestamps with jitter), put into python-can ``virtual`` buses
before the clock starts, so both paths read the same frames at full speed.

- wheelsoil: bus -> reader thread -> 100 ms batches -> MCAP (zstd, chunk close + fsync every 0.5 s)
- python-can: bus -> can.Notifier -> can.CanutilsLogWriter (.log)

CPU time is process CPU time (all threads) per frame. Targets: <= 20 us/frame
and <= 1.25x python-can's path.
"""

from __future__ import annotations

import argparse
import os
import statistics
import sys
import tempfile
import threading
import time
from pathlib import Path

import can
import numpy as np

from wheelsoil.daq import FrameBatch, iter_frame_batches, load_vehicle_config
from wheelsoil.daq.convert import import_log
from wheelsoil.daq.logger import CanLogger
from wheelsoil.daq.recording import RecordingWriter


def vehicle_traffic(seconds: float, seed: int = 0) -> dict[str, list[can.Message]]:
    """Realistic frames of both buses for ``seconds`` (see module docstring)."""
    cfg = load_vehicle_config()
    rng = np.random.default_rng(seed)
    t0 = 1_700_000_000.0
    out = {"can0": [], "can1": []}

    def add(bus, name, rate, values_fn):
        db = cfg.database(bus)
        msg = db.get_message_by_name(name)
        n = int(seconds * rate)
        for i in range(n):
            t = i / rate
            data = msg.encode(values_fn(i, t), strict=False)
            ts = round(t0 + t + float(rng.normal(0, 30e-6)) + 50e-6, 6)
            out[bus].append(can.Message(timestamp=ts, arbitration_id=msg.frame_id,
                                        is_extended_id=msg.is_extended_frame, data=data, channel=bus))

    def noise(s):
        return float(rng.normal(0, s))

    add("can0", "WFT_RL_Force", 500, lambda i, t: {"Fx_w": 2000 * np.sin(t) + noise(20), "Fy_w": noise(50),
                                                    "Fz_w": 9000 + 500 * np.cos(t) + noise(30), "Counter": i % 256, "Status": 0})
    add("can0", "WFT_RL_Moment", 500, lambda i, t: {"Mx_w": noise(5), "My": 900 * np.sin(t / 3) + noise(5),
                                                     "Mz_w": noise(5), "Counter": i % 256, "Status": 0})
    add("can0", "WFT_RL_Angle", 500, lambda i, t: {"WheelAngle": (t * 200) % 360, "Counter": i % 256, "Status": 0})
    add("can0", "WFT_RL_Diag", 1, lambda i, t: {"DiagMux": 0, "BridgeTemp": 31.5, "SupplyVoltage": 12.1})
    add("can1", "WSS_WheelSpeeds", 100, lambda i, t: {f"WheelSpeed_{w}": 60 + 10 * np.sin(t) + abs(noise(0.3))
                                                       for w in ("FL", "FR", "RL", "RR")})
    add("can1", "WSS_Status", 10, lambda i, t: {"RollingCounter": i % 16, "SensorFault_FL": 0, "SensorFault_FR": 0,
                                                "SensorFault_RL": 0, "SensorFault_RR": 0})
    add("can1", "RT_SB_GPS_Speed", 20, lambda i, t: {"GPS_Speed_3D": 2 + np.sin(t), "GPS_Speed_2D": 2 + np.sin(t),
                                                     "Accuracy_GPS_Speed": 3, "Validity_GPS_Speed_3D": 1,
                                                     "Validity_GPS_Speed_2D": 1})
    add("can1", "RT_SB_INS_Vel_Body_Axes", 20, lambda i, t: {"INS_Vel_Sideways_2D": noise(0.02),
                                                             "INS_Vel_Forwards_2D": 2 + np.sin(t),
                                                             "Accuracy_INS_Vel_Body": 3, "Validity_INS_Vel_Sideways": 1,
                                                             "Validity_INS_Vel_Forwards": 1})
    add("can1", "RT_SB_GPS_Time", 20, lambda i, t: {"GPS_Week": 2290, "GPS_Time": 345600 + t, "Accuracy_GPS_Time": 1,
                                                    "Validity_GPS_Week": 1, "Validity_GPS_Time": 1})
    for bus in out:
        out[bus].sort(key=lambda m: m.timestamp)
    return out


def _feed(channel_prefix: str, traffic, n_total: int):
    """Open receiving virtual buses, send ``n_total`` frames round-robin from the traffic."""
    rx = {b: can.Bus(interface="virtual", channel=f"{channel_prefix}-{b}") for b in traffic}
    tx = {b: can.Bus(interface="virtual", channel=f"{channel_prefix}-{b}") for b in traffic}
    sent = 0
    while sent < n_total:
        for b, msgs in traffic.items():
            for m in msgs:
                if sent >= n_total:
                    break
                tx[b].send(m)
                sent += 1
    for b in tx.values():
        b.shutdown()
    return rx


def bench_wheelsoil(traffic, n, tmp: Path) -> float:
    rx = _feed("bws", traffic, n)
    logger = CanLogger(rx, tmp / "bench.mcap", config=load_vehicle_config())
    c0 = time.process_time()
    res = logger.run(max_frames=n)
    cpu = time.process_time() - c0
    for b in rx.values():
        b.shutdown()
    assert sum(res.frames.values()) == n, res.frames
    return cpu / n * 1e6


def _python_can_path(rx, n, log_path: Path) -> None:
    """python-can's own logging path: buses -> Notifier -> CanutilsLogWriter, until ``n`` frames."""
    done = threading.Event()
    count = [0]

    class Count(can.Listener):
        def on_message_received(self, msg):
            count[0] += 1
            if count[0] >= n:
                done.set()

    writer = can.CanutilsLogWriter(str(log_path))
    notifier = can.Notifier(list(rx.values()), [writer, Count()], timeout=0.1)
    done.wait(600)
    notifier.stop()
    writer.stop()


def bench_python_can(traffic, n, tmp: Path) -> float:
    rx = _feed("bpc", traffic, n)
    c0 = time.process_time()
    _python_can_path(rx, n, tmp / "bench.log")
    cpu = time.process_time() - c0
    for b in rx.values():
        b.shutdown()
    return cpu / n * 1e6


def _live(prefix, traffic, n, run_consumer):
    """Sender thread feeds ``n`` frames as fast as it can while the consumer runs;
    returns process CPU per frame including the sending (same for both paths)."""
    rx = {b: can.Bus(interface="virtual", channel=f"{prefix}-{b}") for b in traffic}
    tx = {b: can.Bus(interface="virtual", channel=f"{prefix}-{b}") for b in traffic}

    def send():
        sent = 0
        while sent < n:
            for b, msgs in traffic.items():
                for m in msgs[:2000]:
                    if sent >= n:
                        return
                    tx[b].send(m)
                    sent += 1

    th = threading.Thread(target=send)
    c0 = time.process_time()
    th.start()
    run_consumer(rx)
    th.join()
    cpu = time.process_time() - c0
    for b in list(rx.values()) + list(tx.values()):
        b.shutdown()
    return cpu / n * 1e6


def bench_live(traffic, n, tmp: Path) -> tuple[float, float]:
    def ws(rx):
        CanLogger(rx, tmp / "live.mcap", config=load_vehicle_config()).run(max_frames=n)

    def pc(rx):
        _python_can_path(rx, n, tmp / "live.log")

    return _live("lws", traffic, n, ws), _live("lpc", traffic, n, pc)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--frames", type=int, default=200_000, help="frames per logger run (default 200000)")
    ap.add_argument("--repeat", type=int, default=3, help="runs per path, median reported (default 3)")
    args = ap.parse_args(argv)

    traffic = vehicle_traffic(20.0)
    n_traffic = sum(len(v) for v in traffic.values())
    print(f"feed: vehicle traffic, {n_traffic} frames per 20 s ({n_traffic / 20:.0f} frames/s), "
          f"{args.frames} frames per run, {args.repeat} runs, {os.cpu_count()} CPUs, python {sys.version.split()[0]}, "
          f"python-can {can.__version__}")
    with tempfile.TemporaryDirectory() as td:
        tmp = Path(td)
        ws, pc = [], []
        for _ in range(args.repeat):
            pc.append(bench_python_can(traffic, args.frames, tmp))
            ws.append(bench_wheelsoil(traffic, args.frames, tmp))
        w, p = statistics.median(ws), statistics.median(pc)
        print("\nlogger CPU time per frame (median; process CPU, all threads)")
        print(f"  wheelsoil log  (bus -> batches -> MCAP zstd)        {w:6.2f} us/frame   runs {', '.join(f'{x:.2f}' for x in ws)}")
        print(f"  python-can     (bus -> Notifier -> CanutilsLogWriter) {p:6.2f} us/frame   runs {', '.join(f'{x:.2f}' for x in pc)}")
        print(f"  ratio wheelsoil/python-can: {w / p:.2f}  (target <= 1.25; absolute target <= 20 us/frame: "
              f"{'met' if w <= 20 and w / p <= 1.25 else 'NOT met'})")
        lw, lp = zip(*[bench_live(traffic, args.frames // 2, tmp) for _ in range(args.repeat)])
        w2, p2 = statistics.median(lw), statistics.median(lp)
        print("live feed (a sender thread in the same process sends while the logger reads; CPU includes sending)")
        print(f"  wheelsoil log {w2:6.2f} us/frame | python-can path {p2:6.2f} us/frame | ratio {w2 / p2:.2f}")

        # file sizes for the same frames
        log_path, blf_path, mcap_path = tmp / "t.log", tmp / "t.blf", tmp / "t.mcap"
        merged = sorted((m for v in traffic.values() for m in v), key=lambda m: m.timestamp)
        for path in (log_path, blf_path):
            with can.Logger(str(path)) as wr:
                for m in merged:
                    wr.on_message_received(m)
        with RecordingWriter(mcap_path, config=load_vehicle_config(), fsync=False) as wr:
            # as the logger writes: a batch per bus every 100 ms, a chunk closed every 0.5 s
            batches = {b: FrameBatch.from_messages(b, m) for b, m in traffic.items()}
            t0 = min(int(b.timestamp_ns[0]) for b in batches.values())
            t1 = max(int(b.timestamp_ns[-1]) for b in batches.values())
            edges = np.arange(t0, t1 + 200_000_000, 100_000_000)
            for k in range(len(edges) - 1):
                for b in batches.values():
                    lo, hi = np.searchsorted(b.timestamp_ns, edges[k:k + 2])
                    wr.write_batch(b.select(slice(lo, hi)))
                if k % 5 == 4:
                    wr.flush()
        print(f"\nbytes per frame, {n_traffic} frames of vehicle traffic (MCAP includes the attached DBCs and config)")
        for name, path in (("MCAP (wheelsoil)", mcap_path), ("candump .log", log_path), ("BLF", blf_path)):
            print(f"  {name:<18} {path.stat().st_size / n_traffic:6.1f} B/frame   ({path.stat().st_size / 1e6:.2f} MB)")

        # import and read rates
        t = time.perf_counter()
        res = import_log(log_path, tmp / "imp.mcap")
        dt = time.perf_counter() - t
        print(f"\nimport candump .log -> MCAP: {res.total / dt:,.0f} frames/s ({res.total} frames in {dt:.2f} s)")
        t = time.perf_counter()
        res = import_log(blf_path, tmp / "impb.mcap")
        dt = time.perf_counter() - t
        print(f"import BLF -> MCAP:          {res.total / dt:,.0f} frames/s")
        big = tmp / "big.mcap"
        reps = 20
        with RecordingWriter(big, fsync=False) as wr:
            batches = {b: FrameBatch.from_messages(b, m) for b, m in traffic.items()}
            for _ in range(reps):
                for b in batches.values():
                    for lo in range(0, len(b), 2000):
                        wr.write_batch(b.select(slice(lo, lo + 2000)))
        t = time.perf_counter()
        n = sum(len(b) for b in iter_frame_batches(big))
        dt = time.perf_counter() - t
        print(f"read MCAP -> FrameBatch arrays (iter_frame_batches): {n / dt / 1e6:.1f} M frames/s ({n} frames)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
