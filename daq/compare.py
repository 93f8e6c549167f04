"""Compare the raw frames of two recordings (replay -> log acceptance checks)."""

from __future__ import annotations

import numpy as np

from .frames import FrameBatch
from .recording import read_frames

#: Flag bits compared by default: extended, remote, error, FD, BRS, ESI (not bit6
#: "transmitted", which differs between the replaying and the logging side).
DEFAULT_FLAG_MASK = 0x3F


def frame_differences(want: dict[str, FrameBatch], got: dict[str, FrameBatch], *, buses=None,
                      flag_mask: int = DEFAULT_FLAG_MASK, max_report: int = 5) -> list[str]:
    """Differences between two sets of frames per bus (ids, flags, DLC, payload, order).

    Timestamps are not compared (a replay re-times frames). Payload bytes are
    compared over the payload length only.

    Args:
        want, got: bus -> :class:`FrameBatch` (e.g. from :func:`read_frames`).
        buses: buses to compare (None: the union of both).
        flag_mask: flag bits that must agree.
        max_report: first differing frames listed per bus.

    Returns:
        Human-readable differences; empty when the frames are the same.
    """
    out = []
    names = sorted(set(want) | set(got)) if buses is None else list(buses)
    for bus in names:
        w, g = want.get(bus), got.get(bus)
        if w is None or g is None:
            out.append(f"bus {bus}: {'missing in the first' if w is None else 'missing in the second'} recording")
            continue
        if len(w) != len(g):
            out.append(f"bus {bus}: {len(w)} frames vs {len(g)}")
        n = min(len(w), len(g))
        width = min(w.data_width, g.data_width)
        wl, gl = w.payload_lengths()[:n], g.payload_lengths()[:n]
        cols = np.arange(width)
        wd = np.where(cols < wl[:, None], w.data[:n, :width], 0)
        gd = np.where(cols < gl[:, None], g.data[:n, :width], 0)
        bad = ((w.arbitration_id[:n] != g.arbitration_id[:n])
               | ((w.flags[:n] ^ g.flags[:n]) & flag_mask != 0)
               | (w.dlc[:n] != g.dlc[:n]) | (wd != gd).any(axis=1))
        idx = np.flatnonzero(bad)
        if idx.size:
            out.append(f"bus {bus}: {idx.size} of {n} frames differ")
            for i in idx[:max_report].tolist():
                out.append(f"  frame {i}: id {w.arbitration_id[i]:X}/{g.arbitration_id[i]:X} "
                           f"flags {w.flags[i]:02X}/{g.flags[i]:02X} dlc {w.dlc[i]}/{g.dlc[i]} "
                           f"data {bytes(wd[i]).hex()}/{bytes(gd[i]).hex()}")
    return out


def compare_recordings(a, b, **kw) -> list[str]:
    """:func:`frame_differences` of two MCAP recordings (paths); empty list = same frames."""
    return frame_differences(read_frames(a), read_frames(b), **kw)
