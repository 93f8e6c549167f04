"""Helpers shared by the daq tests (and reusable by the VM harness).

``random_messages`` builds python-can frames that exercise every raw-frame
field; ``compare_recordings`` / ``frame_differences`` live in
``wheelsoil.daq.compare`` so a VM guest can use them without the tests folder.
"""

from __future__ import annotations

import os
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import can
import numpy as np

from wheelsoil.daq.compare import compare_recordings, frame_differences  # noqa: F401  (re-export)

T0 = 1_700_000_000.0


def random_messages(n, *, seed=0, t0=T0, spacing_s=1e-3, fd=False, channel=None, remote=True):
    """``n`` python-can messages: standard and extended ids, every classic DLC,
    some remote frames (``remote``), optional FD frames; timestamps on whole µs."""
    rng = np.random.default_rng(seed)
    out = []
    for i in range(n):
        ext = bool(rng.integers(0, 3) == 0)
        arb = int(rng.integers(0, 0x20000000 if ext else 0x800))
        ts = round(t0 + i * spacing_s + float(rng.integers(0, 500)) * 1e-6, 6)
        if remote and i % 37 == 5:
            out.append(can.Message(timestamp=ts, arbitration_id=arb, is_extended_id=ext, is_remote_frame=True,
                                   dlc=int(rng.integers(0, 9)), channel=channel))
        elif fd and i % 11 == 3:
            size = int(rng.choice([12, 16, 20, 24, 32, 48, 64]))
            out.append(can.Message(timestamp=ts, arbitration_id=arb, is_extended_id=ext, is_fd=True,
                                   bitrate_switch=bool(i % 2), data=rng.integers(0, 256, size, dtype=np.uint8).tobytes(),
                                   channel=channel))
        else:
            out.append(can.Message(timestamp=ts, arbitration_id=arb, is_extended_id=ext,
                                   data=rng.integers(0, 256, int(rng.integers(0, 9)), dtype=np.uint8).tobytes(),
                                   channel=channel))
    return out


def wheelsoil_cmd(*args):
    """argv running the wheelsoil CLI with this interpreter."""
    return [sys.executable, "-m", "wheelsoil", *map(str, args)]


def run_wheelsoil(*args, timeout=60):
    """Run the CLI; returns the CompletedProcess (text)."""
    return subprocess.run(wheelsoil_cmd(*args), capture_output=True, text=True, timeout=timeout)


def cli(*args) -> int:
    """Run the wheelsoil CLI in this process (fast; output goes to pytest's capture)."""
    from wheelsoil.cli import main

    return main([str(a) for a in args])


def start_logger(out, buses, *extra, wait_for=None):
    """Start ``wheelsoil log`` in another process and wait until it has opened
    its buses and the file ``wait_for`` (default ``out``; header written). Returns the Popen."""
    args = [a for b in buses for a in ("--bus", b)]
    p = subprocess.Popen(wheelsoil_cmd("log", *args, "-o", out, "-q", *extra), stdout=subprocess.PIPE,
                         stderr=subprocess.STDOUT, text=True)
    deadline = time.monotonic() + 30
    wait_for = out if wait_for is None else wait_for
    while not (os.path.exists(wait_for) and os.path.getsize(wait_for) > 0):
        if p.poll() is not None:
            raise AssertionError(f"logger exited early: {p.stdout.read()}")
        if time.monotonic() > deadline:
            p.kill()
            raise AssertionError("logger did not start in 30 s")
        time.sleep(0.05)
    time.sleep(0.3)  # reader threads running
    return p


def stop_logger(p, sig=signal.SIGINT, timeout=30):
    """Send ``sig`` and wait; returns (returncode, output)."""
    p.send_signal(sig)
    try:
        out, _ = p.communicate(timeout=timeout)
    except subprocess.TimeoutExpired:
        p.kill()
        out, _ = p.communicate()
    return p.returncode, out


def copy_default_vehicle(tmp_path) -> Path:
    """Copy the shipped vehicle.toml and its DBC files into ``tmp_path``; returns the TOML's path."""
    from wheelsoil.daq.config import default_vehicle_path

    src = default_vehicle_path()
    for f in src.parent.glob("*.dbc"):
        shutil.copy(f, tmp_path / f.name)
    dst = tmp_path / "vehicle.toml"
    dst.write_text(src.read_text())
    return dst
