"""Fuzz benchmark (issue 12, item 8): mutated recordings and logs through info, export,
process and fit.

Inputs (made at start, small so the run takes minutes): a 20 s cut of
``recordings/clay-run1.mcap`` rewritten with :class:`RecordingWriter` (one chunk per
half-second batch, as the logger writes) and its candump ``.log`` export.

Mutations of the recording: truncation at a random offset, 1 and several random
byte flips, a flip inside a chunk's payload, a corrupted record header (type or
length), a zeroed run of bytes, and rewritten recordings with outlier timestamps
(one frame 6 h off, a day off, 0, a huge NaN-like value) and shuffled batch order
(logs joined out of order). Mutations of the log: junk lines, a cut at a random
offset, byte flips, shuffled lines, outlier and ``nan``/``1e20`` timestamps.

Each case goes through the library functions behind the CLI:
``read_recording_info`` (info), ``export_recording`` (export), ``read_frames``
(every frame delivered), and on a subset ``process_recording`` and ``run_fit``.

Counted:

- tracebacks: any exception other than the documented clean errors
  (``ValueError``/``RecordingError``/``OSError``) whose message names the file;
- altered frames delivered: frames read from a mutated recording that are not in
  the original, by (bus, timestamp, id, flags, DLC, data) (target 0). For logs (no checksum
  in a text log: a flipped hex digit is a different, valid frame) frames imported
  from flipped/shuffled/re-timed lines are reported apart; junk lines and cuts
  must not alter any frame;
- loss beyond the damaged chunk: frames of the original missing from a mutated
  recording beyond those of the chunks the mutation touched (target 0);
- peak memory: tracemalloc peak of one case and the process's ru_maxrss
  (target < 1 GB).

    .venv/bin/python benchmarks/bench_fuzz.py [--n 200] [--seed 0] [--process-every 10] [--fit-every 50]
"""

from __future__ import annotations

import argparse
import random
import re
import resource
import shutil
import sys
import tempfile
import time
import tracemalloc
import traceback
import warnings
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
CLEAN = (ValueError, OSError)


def _frame_keys(batches) -> set:
    """{(bus, timestamp ns, id, flags, dlc, first 8 data bytes, rest of the payload)} of all
    frames (the same frame gives the same key in a classic or an FD-width batch)."""
    out = set()
    for b in batches:
        d = np.ascontiguousarray(b.data)
        first = np.ascontiguousarray(d[:, :8]).view("<u8").ravel().tolist()
        rest = [bytes(r).rstrip(b"\0") for r in d[:, 8:]] if b.data_width > 8 else [b""] * len(b)
        out.update(zip([b.bus] * len(b), b.timestamp_ns.tolist(), b.arbitration_id.tolist(),
                       b.flags.tolist(), b.dlc.tolist(), first, rest))
    return out


def _layout(path):
    """Top-level records of a clean recording: [(start, end, opcode, frames)]."""
    import struct

    from wheelsoil.daq.recording import _chunk_records, _inflate, _parse_chunk, _batch_len

    data = Path(path).read_bytes()
    pos, out = 8, []
    while pos + 9 <= len(data):
        op, ln = struct.unpack_from("<BQ", data, pos)
        end = pos + 9 + ln
        frames = 0
        if op == 0x06:
            _t0, _t1, usize, _crc, comp, payload = _parse_chunk(data[pos + 9:end])
            for op2, r in _chunk_records(_inflate(comp, payload, usize)):
                if op2 == 0x05:
                    frames += _batch_len(r[2]) or 0
        out.append((pos, end, op, frames))
        if op == 0x02:
            break
        pos = end
    return out


def _allowed_loss(layout, ranges, truncate_at=None) -> int:
    """Frames in the chunks a mutation touched (a cut: every chunk not wholly before it)."""
    n = 0
    for s, e, op, fr in layout:
        if op != 0x06:
            continue
        if truncate_at is not None and e > truncate_at:
            n += fr
        elif any(a < e and b > s for a, b in ranges):
            n += fr
    return n


def make_inputs(work: Path, seconds: float = 20.0):
    """The base recording (a cut of clay-run1) and its candump log."""
    from wheelsoil.daq import RecordingWriter, iter_frame_batches
    from wheelsoil.daq.convert import export_recording
    from wheelsoil.daq.info import load_recording_config
    from wheelsoil.daq.provenance import make_provenance

    src = ROOT / "recordings" / "clay-run1.mcap"
    cfg = load_recording_config(src)
    bs = list(iter_frame_batches(src))
    t0 = min(int(b.timestamp_ns[0]) for b in bs)
    sel = [b for b in bs if b.timestamp_ns[0] < t0 + seconds * 1e9]
    base = work / "base.mcap"
    with RecordingWriter(base, config=cfg, provenance=make_provenance("simulated", command=None, seed=None,
                                                                      simulator="bench_fuzz cut")) as w:
        for b in sel:
            w.write_batch(b)
            w.flush()
    log = work / "base.log"
    export_recording(base, log)
    return base, log, cfg, sel


# ----------------------------------------------------------------------------- mutations
def mutate_mcap(rng: random.Random, data: bytes, layout, kind: str):
    """(bytes, damaged byte ranges, truncate_at) for a byte-level mutation."""
    b = bytearray(data)
    n = len(b)
    if kind == "truncate":
        cut = rng.randrange(9, n)
        return bytes(b[:cut]), [], cut
    if kind == "flip1":
        i = rng.randrange(8, n)
        b[i] ^= 1 << rng.randrange(8)
        return bytes(b), [(i, i + 1)], None
    if kind == "flipN":
        rs = []
        for _ in range(rng.randint(2, 8)):
            i = rng.randrange(8, n)
            b[i] ^= rng.randrange(1, 256)
            rs.append((i, i + 1))
        return bytes(b), rs, None
    chunks = [r for r in layout if r[2] == 0x06]
    if kind == "chunkflip":
        s, e, _op, _fr = rng.choice(chunks)
        i = rng.randrange(s + 9 + 40, e)
        b[i] ^= 1 << rng.randrange(8)
        return bytes(b), [(i, i + 1)], None
    if kind == "header":
        s, e, op, _fr = rng.choice(layout[:-1])
        if rng.random() < 0.5:
            b[s] = rng.choice([0x00, 0x03, 0x07, 0x0C, 0x0F, 0x55, 0xFF, 0x02, 0x08])
        else:
            j = rng.randrange(1, 9)
            b[s + j] ^= rng.randrange(1, 256)
        return bytes(b), [(s, s + 9)], None
    if kind == "zeros":
        i = rng.randrange(8, n - 1)
        k = rng.randint(1, 200)
        b[i:i + k] = bytes(len(b[i:i + k]))
        return bytes(b), [(i, i + k)], None
    raise ValueError(kind)


def rewrite_times(rng: random.Random, path: Path, batches, cfg, kind: str):
    """A recording whose timestamps are odd (outliers / joined out of order)."""
    from wheelsoil.daq import RecordingWriter

    bs = [b.select(slice(0, len(b))) for b in batches]
    for b in bs:
        b.timestamp_ns = np.array(b.timestamp_ns, np.int64)
    if kind == "outlier":
        for _ in range(rng.randint(1, 4)):
            b = rng.choice(bs)
            i = rng.randrange(len(b))
            b.timestamp_ns[i] = rng.choice([b.timestamp_ns[i] + 6 * 3600 * 10**9, b.timestamp_ns[i] - 86400 * 10**9,
                                            0, 9_000_000_000_000_000_000, b.timestamp_ns[i] + 10**15])
    elif kind == "shuffle":
        k = len(bs) // 2
        bs = bs[k:] + bs[:k]
    with RecordingWriter(path, config=cfg) as w:
        for b in bs:
            w.write_batch(b)
            w.flush()
    return bs


def mutate_log(rng: random.Random, text: str, kind: str) -> tuple[str, bool]:
    """(mutated text, frames may legitimately differ) for a candump log."""
    lines = text.splitlines(keepends=True)
    if kind == "junk":
        for _ in range(rng.randint(1, 20)):
            junk = rng.choice(["garbage\n", "(abc) can0 123#11\n", "(1700000000.0) can0 XYZ#00\n",
                               "(1700000000.000000) can0 123#0011223\n", "\x00\x01\x02\n", "#####\n",
                               "(1700000000.000000) can0 123#001122334455667788\n",
                               "(1700000000.000000) can0 12345#00\n", "\n", "(1e400) can0 123#00\n"])
            lines.insert(rng.randrange(len(lines) + 1), junk)
        return "".join(lines), False
    if kind == "cut":
        t = "".join(lines)
        return t[:rng.randrange(1, len(t))], False
    if kind == "flip":
        t = bytearray("".join(lines).encode())
        for _ in range(rng.randint(1, 10)):
            i = rng.randrange(len(t))
            t[i] = rng.randrange(32, 127)
        return t.decode("ascii", "replace"), True
    if kind == "shuffle":
        k = len(lines) // 2
        return "".join(lines[k:] + lines[:k]), True
    if kind == "times":
        for _ in range(rng.randint(1, 5)):
            i = rng.randrange(len(lines))
            m = re.match(r"\((\d+\.\d+)\)(.*)", lines[i], re.S)
            if m:
                v = rng.choice(["nan", "1e20", "0.000000", f"{float(m.group(1)) + 21600:.6f}", "inf", "-5.0"])
                lines[i] = f"({v}){m.group(2)}"
        return "".join(lines), True
    raise ValueError(kind)


# ----------------------------------------------------------------------------- running
class Tally:
    def __init__(self):
        self.cases = 0
        self.calls = {}
        self.tracebacks: list[str] = []
        self.clean_errors = 0
        self.altered = 0
        self.altered_import = 0
        self.altered_log_expected = 0
        self.excess_loss = 0
        self.excess_cases: list[str] = []
        self.peak = 0
        self.peak_failed = 0

    def call(self, name: str, path: Path, fn):
        """Run ``fn``; a clean error names the file; anything else is a traceback.
        Memory of the daq calls (info, read, export, import) is traced with tracemalloc;
        process and fit run untraced (ru_maxrss covers them)."""
        self.calls[name] = self.calls.get(name, 0) + 1
        traced = name in ("info", "read", "export", "import")
        failed = False
        if traced:
            tracemalloc.start()
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                return fn()
        except CLEAN as exc:
            msg = str(exc)
            if path.name not in msg and str(path) not in msg:
                self.tracebacks.append(f"{name} {path.name}: error without the file name: "
                                       f"{type(exc).__name__}: {msg[:200]}")
            else:
                self.clean_errors += 1
            return None
        except Exception as exc:  # noqa: BLE001 - what we count
            failed = True
            tb = traceback.format_exc().strip().splitlines()
            self.tracebacks.append(f"{name} {path.name}: {type(exc).__name__}: {str(exc)[:200]} | "
                                   + " / ".join(tb[-4:-1]))
            return None
        finally:
            if traced:
                peak = tracemalloc.get_traced_memory()[1]
                tracemalloc.stop()
                if failed:  # a failed huge allocation is counted by tracemalloc though never made
                    self.peak_failed = max(self.peak_failed, peak)
                else:
                    self.peak = max(self.peak, peak)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--n", type=int, default=200, help="mutated inputs (default 200)")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--process-every", type=int, default=10, help="process every k-th case (default 10)")
    ap.add_argument("--fit-every", type=int, default=50, help="fit every k-th case (default 50; 0 = never)")
    ap.add_argument("--keep", default=None, metavar="DIR", help="keep the mutated files here")
    ap.add_argument("-v", "--verbose", action="store_true")
    args = ap.parse_args(argv)

    from wheelsoil.daq import read_frames, read_recording_info
    from wheelsoil.daq.convert import export_recording, import_log
    from wheelsoil.processing import process_recording
    from wheelsoil.pipeline import run_fit

    rng = random.Random(args.seed)
    work = Path(args.keep) if args.keep else Path(tempfile.mkdtemp(prefix="wheelsoil-fuzz-"))
    work.mkdir(parents=True, exist_ok=True)
    t_start = time.perf_counter()
    try:
        base, log, cfg, batches = make_inputs(work)
        data = base.read_bytes()
        layout = _layout(base)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            orig = _frame_keys(read_frames(base).values())
        log_text = log.read_text()
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            import_log(log, work / "base-log.mcap", config=cfg)
            orig_log = _frame_keys(read_frames(work / "base-log.mcap").values())
        print(f"base: {base.stat().st_size} bytes, {len(orig)} frames, "
              f"{sum(1 for r in layout if r[2] == 6)} chunks; log {len(log_text)} bytes")
        tally = Tally()
        mc_kinds = ["truncate", "flip1", "flipN", "chunkflip", "header", "zeros", "outlier", "shuffle"]
        log_kinds = ["junk", "cut", "flip", "shuffle", "times"]
        by_kind: dict[str, int] = {}
        for case in range(args.n):
            tally.cases += 1
            is_log = rng.random() < 0.3
            kind = rng.choice(log_kinds if is_log else mc_kinds)
            by_kind[("log:" if is_log else "mcap:") + kind] = by_kind.get(("log:" if is_log else "mcap:") + kind, 0) + 1
            do_process = args.process_every and case % args.process_every == 0
            do_fit = args.fit_every and case % args.fit_every == 0
            if is_log:
                p = work / f"case{case:04d}-{kind}.log"
                text, may_differ = mutate_log(rng, log_text, kind)
                p.write_text(text, encoding="utf-8", errors="replace")
                out = work / f"case{case:04d}.mcap"
                res = tally.call("import", p, lambda: import_log(p, out, config=cfg))
                if res is not None and out.exists():
                    tally.call("info", out, lambda: read_recording_info(out))
                    got = tally.call("read", out, lambda: read_frames(out))
                    if got is not None:
                        bad = len(_frame_keys(got.values()) - orig_log)
                        if may_differ:
                            tally.altered_log_expected += bad
                        else:
                            tally.altered_import += bad
                            if bad and args.verbose:
                                print(f"  altered frames from {p.name}: {bad}")
                if do_process:
                    tally.call("process", p, lambda: process_recording(p))
                if do_fit:
                    tally.call("fit", p, lambda: run_fit([p], "clay", work / f"fit{case:04d}"))
            else:
                p = work / f"case{case:04d}-{kind}.mcap"
                trunc, ranges, orig_case = None, [], orig
                if kind in ("outlier", "shuffle"):
                    bs = rewrite_times(rng, p, batches, cfg, kind)
                    orig_case = _frame_keys(bs)
                    allowed = 0
                else:
                    mdata, ranges, trunc = mutate_mcap(rng, data, layout, kind)
                    p.write_bytes(mdata)
                    allowed = _allowed_loss(layout, ranges, trunc)
                tally.call("info", p, lambda: read_recording_info(p))
                got = tally.call("read", p, lambda: read_frames(p))
                if got is not None:
                    keys = _frame_keys(got.values())
                    bad = len(keys - orig_case)
                    tally.altered += bad
                    lost = len(orig_case - keys)
                    if lost > allowed:
                        tally.excess_loss += lost - allowed
                        tally.excess_cases.append(f"{p.name}: lost {lost}, damaged chunks held {allowed}")
                    if args.verbose and (bad or lost > allowed):
                        print(f"  {p.name}: altered {bad}, lost {lost} (allowed {allowed})")
                ex = work / f"case{case:04d}.log"
                tally.call("export", p, lambda: export_recording(p, ex))
                if do_process:
                    tally.call("process", p, lambda: process_recording(p))
                if do_fit:
                    tally.call("fit", p, lambda: run_fit([p], "clay", work / f"fit{case:04d}"))
            for q in work.glob(f"case{case:04d}*"):
                if not args.keep:
                    q.unlink() if q.is_file() else shutil.rmtree(q, ignore_errors=True)
            for q in work.glob(f"fit{case:04d}"):
                if not args.keep:
                    shutil.rmtree(q, ignore_errors=True)
            if (case + 1) % 50 == 0:
                print(f"  {case + 1}/{args.n} cases, {len(tally.tracebacks)} tracebacks, "
                      f"{tally.altered} altered, {time.perf_counter() - t_start:.0f} s", flush=True)
    finally:
        if not args.keep:
            shutil.rmtree(work, ignore_errors=True)
    rss = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024  # Linux: KiB
    print(f"\nfuzz: {tally.cases} mutated inputs (seed {args.seed}): "
          + ", ".join(f"{k} {v}" for k, v in sorted(by_kind.items())))
    print("calls: " + ", ".join(f"{k} {v}" for k, v in sorted(tally.calls.items()))
          + f"; clean errors (naming the file): {tally.clean_errors}")
    print(f"{'tracebacks':<46}{len(tally.tracebacks):>12}   target 0")
    print(f"{'altered frames delivered':<46}{tally.altered:>12}   target 0")
    print(f"{'frames lost beyond the damaged chunks':<46}{tally.excess_loss:>12}   target 0")
    print(f"{'altered frames imported (junk lines, cut logs)':<46}{tally.altered_import:>12}   target 0 "
          "(import validation)")
    print(f"{'(log lines flipped/re-timed: differing frames)':<46}{tally.altered_log_expected:>12}   "
          "(no checksum in text logs)")
    print(f"{'peak memory, tracemalloc (one daq call)':<46}{tally.peak / 2**20:>10.1f} MiB")
    if tally.peak_failed:
        print(f"{'  (attempted by a call that raised)':<46}{tally.peak_failed / 2**20:>10.1f} MiB")
    print(f"{'peak memory, ru_maxrss (process)':<46}{rss / 2**20:>10.1f} MiB   target < 1024 MiB")
    print(f"{'wall time':<46}{time.perf_counter() - t_start:>10.1f} s")
    for t in tally.tracebacks[:20]:
        print("  TRACEBACK " + t)
    for t in tally.excess_cases[:10]:
        print("  LOSS " + t)
    ok = not tally.tracebacks and not tally.altered and not tally.altered_import and not tally.excess_loss \
        and rss < 2**30
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
