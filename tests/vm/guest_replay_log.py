"""Guest-side acceptance of issue 4 on real vcan0/vcan1 (run inside the VM).

A recording made with :class:`wheelsoil.daq.RecordingWriter` (two buses, mixed
standard/extended/remote frames, every classic DLC) is replayed with
``wheelsoil replay REC --bus ...`` while ``wheelsoil log --bus ... -o out.mcap``
runs in another process; the logged raw frames equal the recorded ones (ids,
extended/remote flags, DLC, data, order per bus) and the replay keeps the
recorded timing (it is never faster than the recording / speed).
"""

import signal
import subprocess
import sys
import time
import warnings

import numpy as np
import pytest

can = pytest.importorskip("can")

from wheelsoil.daq import RecordingWriter, read_frames, read_recording_info  # noqa: E402

N_PER_BUS = 1500
SPACING_S = 0.5e-3  # recorded frame spacing per bus
SPEED = 1.0
# flag bits compared: extended, remote, error, FD, BRS, ESI (bit6 "transmitted by this
# host" differs by nature: every frame on a vcan comes from this host)
FLAG_MASK = 0x3F


def _recorded_messages(bus_index):
    t0 = 1_700_000_000.0
    out = []
    for i in range(N_PER_BUS):
        ext = (i + bus_index) % 3 == 0
        arb = (i * 7919 + bus_index * 131) % (0x20000000 if ext else 0x800)
        if i % 97 == 5:
            out.append(can.Message(timestamp=t0 + i * SPACING_S, arbitration_id=arb, is_extended_id=ext,
                                   is_remote_frame=True, dlc=i % 9))
        else:
            out.append(can.Message(timestamp=t0 + i * SPACING_S, arbitration_id=arb, is_extended_id=ext,
                                   data=bytes((i * 3 + k + bus_index) % 256 for k in range(i % 9))))
    return out


#: `wheelsoil ARGS...` (the console script's function, wheelsoil.cli:main), imported
#: first and run once the file argv[1] appears.
_REPLAYER = """
import os, sys, time
import wheelsoil.cli as cli
cli.build_parser()
while not os.path.exists(sys.argv[1]):
    time.sleep(0.05)
sys.exit(cli.main(sys.argv[2:]))
"""
STARTUP_TIMEOUT_S = 240


def _require_cli():
    """Skip with the exact reason when `wheelsoil log`/`replay` are not there (yet)."""
    import argparse

    try:
        from wheelsoil.daq import cli
    except ImportError as exc:
        pytest.skip(f"wheelsoil.daq.cli cannot be imported: {exc}")
    sub = argparse.ArgumentParser().add_subparsers()
    cli.register(sub)  # only daq's commands: the full parser imports every package (slow under TCG)
    missing = [c for c in ("log", "replay") if c not in sub.choices]
    if missing:
        pytest.skip(f"wheelsoil subcommand(s) {', '.join(missing)} not registered by wheelsoil.daq.cli "
                    f"in this checkout; it has: {', '.join(sorted(sub.choices))}")


def _wait_until_logged(path, n_per_bus, timeout_s):
    """Poll the growing recording (chunks are flushed every 0.5 s) until every bus has
    ``n_per_bus`` frames or ``timeout_s`` passed; the comparison afterwards tells what is missing."""
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        time.sleep(0.5)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # the open file has no footer yet
            counts = {b: len(v) for b, v in read_frames(path).items()}
        if counts and all(counts.get(b, 0) >= n_per_bus for b in ("can0", "can1")):
            return


def test_replay_then_log_same_frames(vcan0, vcan1, tmp_path, record_property):
    _require_cli()
    t_start = time.monotonic()
    rec = tmp_path / "rec.mcap"
    out = tmp_path / "out.mcap"
    with RecordingWriter(rec, metadata={"purpose": "vm replay test"}) as w:
        w.write_frames("can0", _recorded_messages(0))
        w.write_frames("can1", _recorded_messages(1))
    want = read_frames(rec)
    assert {b: len(v) for b, v in want.items()} == {"can0": N_PER_BUS, "can1": N_PER_BUS}

    buses = ["--bus", f"can0=socketcan:{vcan0}", "--bus", f"can1=socketcan:{vcan1}"]
    go = tmp_path / "go"
    # Both processes start at once: under TCG, python start-up dominates (`wheelsoil`
    # imports every package, about a minute cold over 9p). The replayer is the
    # `wheelsoil` entry point (wheelsoil.cli.main) started early that waits for `go`.
    logger = subprocess.Popen([sys.executable, "-m", "wheelsoil", "log", *buses, "-o", str(out)],
                              stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    replayer = subprocess.Popen([sys.executable, "-c", _REPLAYER, str(go), "replay", str(rec), *buses,
                                 "--speed", str(SPEED)], stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    try:
        deadline = time.monotonic() + STARTUP_TIMEOUT_S
        while not out.exists() or out.stat().st_size == 0:  # the file exists once the buses are open
            assert logger.poll() is None, f"logger exited early:\n{logger.stdout.read()}"
            assert time.monotonic() < deadline, f"logger did not start within {STARTUP_TIMEOUT_S} s"
            time.sleep(0.2)
        logger_start_s = time.monotonic() - t_start
        time.sleep(0.5)
        t0 = time.monotonic()
        go.touch()
        rep_out, _ = replayer.communicate(timeout=STARTUP_TIMEOUT_S)
        replay_s = time.monotonic() - t0
        assert replayer.returncode == 0, rep_out
        _wait_until_logged(out, N_PER_BUS, timeout_s=60)  # a slow guest may lag behind the replay
    finally:
        t_stop = time.monotonic()
        logger.send_signal(signal.SIGINT)
        try:
            log_out, _ = logger.communicate(timeout=60)
        except subprocess.TimeoutExpired:
            logger.kill()
            log_out, _ = logger.communicate()
        if replayer.poll() is None:
            replayer.kill()
            replayer.communicate()
    logger_stop_s = time.monotonic() - t_stop
    assert logger.returncode == 0, log_out
    for k, v in dict(logger_start_s=logger_start_s, replay_s=replay_s, logger_stop_s=logger_stop_s).items():
        record_property(k, round(v, 1))  # guest seconds under TCG
    print(f"logger up after {logger_start_s:.1f} s, replay {replay_s:.1f} s after go, logger stop "
          f"{logger_stop_s:.1f} s (guest, TCG)\nreplay said:\n{rep_out[-800:]}\nlogger said:\n{log_out[-1500:]}")

    got = read_frames(out)
    # the CLI logger read through OverflowAwareSocketcanBus: kernel drop counts recorded (none here)
    assert read_recording_info(out).rx_dropped() == {"can0": 0, "can1": 0}
    for bus in ("can0", "can1"):
        w, g = want[bus], got.get(bus)
        assert g is not None, f"no frames logged on {bus}; logged buses {sorted(got)}"
        assert len(g) == len(w), f"{bus}: {len(g)} frames logged, {len(w)} replayed"
        np.testing.assert_array_equal(g.arbitration_id, w.arbitration_id, err_msg=bus)
        np.testing.assert_array_equal(g.flags & FLAG_MASK, w.flags & FLAG_MASK, err_msg=bus)
        np.testing.assert_array_equal(g.dlc, w.dlc, err_msg=bus)
        np.testing.assert_array_equal(g.data[:, :8], w.data[:, :8], err_msg=bus)
        # recorded timing: never faster than recording/speed (slower is allowed under TCG)
        span_rec = (w.timestamp_ns[-1] - w.timestamp_ns[0]) / 1e9 / SPEED
        span_got = (g.timestamp_ns[-1] - g.timestamp_ns[0]) / 1e9
        assert span_got >= 0.9 * span_rec, (bus, span_got, span_rec)
        assert np.all(np.diff(g.timestamp_ns) >= 0), bus
