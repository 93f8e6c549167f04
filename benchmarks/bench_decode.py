"""Decode throughput: wheelsoil's vectorised decoder vs a cantools per-frame loop.

Generates a >= 10-minute recording of all three devices (WFT 3 x 500 Hz +
diagnostics, wheel speeds 100 Hz + status, GNSS 4 messages at 20/1 Hz;
about 1.67 k frames/s) with ``wheelsoil.simulate`` into a temporary
directory, then, in one run on the same frames:

* ours: ``decode_batches(iter_frame_batches(path), Decoder(all DBCs))``, all
  signals of all messages, MCAP reading included (best of 3);
* cantools: ``Message.decode(bytes)`` for every frame (the message looked up
  in a dict by id), over frames already in memory (reading excluded, which
  favours cantools), ``decode_choices=False``;
* ours on the same frames re-written as 2000-frame MCAP messages (the
  logger's 100 ms batches make ~12 k messages for 10 min; reading cost is
  mostly per message);
* peak memory of our decode (tracemalloc, separate run) next to the size of
  its output arrays, and the process's max RSS;
* ``process_recording`` on the same file (the whole processing chain).

Run: ``python benchmarks/bench_decode.py [--minutes 10]``.
"""

from __future__ import annotations

import argparse
import resource
import sys
import tempfile
import time
import tracemalloc
from pathlib import Path

import numpy as np


def make_recording(path: Path, minutes: float) -> None:
    from wheelsoil.model import load_terrain
    from wheelsoil.simulate import simulate_run, write_simulation

    run = simulate_run(load_terrain("clay"), wheel=(0.55, 0.40), duration_s=minutes * 60.0, gnss_latency_s=0.1,
                       drop_rate=0.0005, seed=1)
    write_simulation(run, path)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--minutes", type=float, default=10.0, help="recording length (default 10)")
    args = ap.parse_args(argv)

    import cantools

    from wheelsoil.daq import RecordingWriter, iter_frame_batches, load_vehicle_config, read_frames
    from wheelsoil.processing import Decoder, decode_batches, process_recording

    cfg = load_vehicle_config()
    with tempfile.TemporaryDirectory(prefix="wheelsoil-bench-") as tmp:
        path = Path(tmp) / "bench.mcap"
        t = time.perf_counter()
        make_recording(path, args.minutes)
        size_mb = path.stat().st_size / 1e6
        print(f"recording: {args.minutes:g} min, {size_mb:.1f} MB, generated in {time.perf_counter() - t:.1f} s")

        dbcs = {bus: [cfg.database(bus)] for bus in cfg.buses}
        decoder = Decoder(dbcs)  # compiled once, all messages and signals

        # ---- ours: read + decode, best of 3
        best = np.inf
        for _ in range(3):
            t = time.perf_counter()
            out = decode_batches(iter_frame_batches(path), decoder)
            best = min(best, time.perf_counter() - t)
        n_frames = sum(len(m) for m in out.values())
        out_bytes = sum(m.timestamp_ns.nbytes + sum(a.nbytes for a in m.signals.values()) for m in out.values())
        n_sig = sum(len(m.signals) for m in out.values())
        del out

        # read only, and decode only (batches already in memory), to split the time
        t_read = np.inf
        for _ in range(3):
            t = time.perf_counter()
            n_read = sum(len(b) for b in iter_frame_batches(path))
            t_read = min(t_read, time.perf_counter() - t)
        in_memory = list(iter_frame_batches(path))
        n_batches = len(in_memory)
        t_dec = np.inf
        for _ in range(3):
            t = time.perf_counter()
            decode_batches(in_memory, decoder)
            t_dec = min(t_dec, time.perf_counter() - t)
        del in_memory

        # ---- peak memory of our streaming decode
        tracemalloc.start()
        out = decode_batches(iter_frame_batches(path), decoder)
        _, peak = tracemalloc.get_traced_memory()
        tracemalloc.stop()
        del out

        # ---- cantools per-frame loop over the same frames (already in memory)
        frames = read_frames(path)

        # ---- the same frames re-written in 2000-frame MCAP messages (the writer's maximum;
        # the logger cuts a batch every 100 ms): how much of the time is per-message overhead
        big = Path(tmp) / "bench_2000.mcap"
        with RecordingWriter(big, config=cfg, metadata={}) as w:
            for bus, fb in frames.items():
                for a in range(0, len(fb), 2000):
                    w.write_batch(fb.select(slice(a, a + 2000)))
        best_big = np.inf
        for _ in range(3):
            t = time.perf_counter()
            decode_batches(iter_frame_batches(big), decoder)
            best_big = min(best_big, time.perf_counter() - t)
        lookup = {}
        for bus, dbs in dbcs.items():
            for db in dbs:
                for m in db.messages:
                    lookup[(bus, m.frame_id, bool(m.is_extended_frame))] = m
        t = time.perf_counter()
        n_ct = 0
        for bus, fb in frames.items():
            ids = fb.arbitration_id.tolist()
            ext = fb.is_extended.tolist()
            dlc = fb.dlc.tolist()
            data = fb.data
            for i in range(len(ids)):
                msg = lookup.get((bus, ids[i], ext[i]))
                if msg is None:
                    continue
                msg.decode(data[i, :dlc[i]].tobytes(), decode_choices=False)
                n_ct += 1
        t_ct = time.perf_counter() - t
        del frames

        # ---- the whole processing chain
        t = time.perf_counter()
        res = process_recording(path)
        t_proc = time.perf_counter() - t

    ours = n_frames / best
    ct = n_ct / t_ct
    rss_mb = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    print(f"frames decoded: {n_frames} ({n_read} in file, {n_batches} MCAP messages), {n_sig} signals")
    print(f"{'method':<44}{'frames/s':>14}{'time [s]':>10}")
    print(f"{'wheelsoil decode (MCAP read + decode)':<44}{ours:>14,.0f}{best:>10.3f}")
    print(f"{'  MCAP reading alone (iter_frame_batches)':<44}{n_read / t_read:>14,.0f}{t_read:>10.3f}")
    print(f"{'  decode alone (batches in memory)':<44}{n_frames / t_dec:>14,.0f}{t_dec:>10.3f}")
    print(f"{'wheelsoil, same frames in 2000-frame messages':<44}{n_frames / best_big:>14,.0f}{best_big:>10.3f}")
    print(f"{'cantools Message.decode loop (no reading)':<44}{ct:>14,.0f}{t_ct:>10.3f}")
    print(f"speed-up vs the cantools loop: {ours / ct:.1f}x with reading (target >= 20x), "
          f"{n_frames / best_big / ct:.1f}x with 2000-frame messages, decode alone {n_frames / t_dec / ct:.1f}x")
    print(f"peak traced memory of the streaming decode: {peak / 1e6:.1f} MB "
          f"(output arrays {out_bytes / 1e6:.1f} MB, file {size_mb:.1f} MB); process max RSS {rss_mb:.0f} MB")
    print(f"process_recording on the same file: {t_proc:.2f} s ({n_read / t_proc:,.0f} frames/s), "
          f"latency {res.gnss_latency_s * 1e3:.1f} ms (true 100.0), valid {res.signals['valid'].mean() * 100:.1f} %")
    return 0


if __name__ == "__main__":
    sys.exit(main())
