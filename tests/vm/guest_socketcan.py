"""Guest-side tests of ``wheelsoil.daq.socketcan`` on a real vcan0 (run inside the VM).

- a 10,000-frame burst is either delivered in full or the shortfall equals the
  kernel's reported drop count (no silent loss), for an enlarged and a default
  receive buffer; the default one must lose frames and report them through
  ``SO_RXQ_OVFL`` ancillary data;
- a round trip through :class:`OverflowAwareSocketcanBus` keeps ids, extended
  and remote flags, DLC, data, CAN FD flags and the kernel receive timestamps.
"""

import socket
import time

import can
import pytest

from wheelsoil.daq.socketcan import OverflowAwareSocketcanBus

N_BURST = 10_000


def _burst_payload(i: int) -> bytes:
    return i.to_bytes(4, "little") + bytes([i % 251, 0xA5, i % 7, 0x5A])


def _drain(bus, timeout=0.5):
    """All frames queued on ``bus`` (stops after ``timeout`` s of silence)."""
    got = []
    while (m := bus.recv(timeout=timeout)) is not None:
        got.append(m)
    return got


def _check_delivered(msgs):
    """Sequence numbers of burst frames; asserts each frame is intact and in order."""
    seq = []
    for m in msgs:
        i = int.from_bytes(m.data[:4], "little")
        assert bytes(m.data) == _burst_payload(i), m
        assert m.arbitration_id == i % 0x800 and not m.is_extended_id, m
        seq.append(i)
    assert seq == sorted(set(seq)), "frames duplicated or out of order"
    return seq


def test_burst_no_silent_loss(vcan0, record_property):
    big = OverflowAwareSocketcanBus(vcan0)  # the logger's default: 64 MiB requested
    small = OverflowAwareSocketcanBus(vcan0, rcvbuf_bytes=None)  # kernel default buffer
    tx = can.Bus(interface="socketcan", channel=vcan0)
    try:
        assert big.rcvbuf_bytes >= 64 * 2**20, "root in the guest: SO_RCVBUFFORCE must grant it"
        assert small.rcvbuf_bytes < 2**20
        t0 = time.perf_counter()
        for i in range(N_BURST):  # nobody reads while the burst runs
            tx.send(can.Message(arbitration_id=i % 0x800, is_extended_id=False, data=_burst_payload(i)))
        send_s = time.perf_counter() - t0

        got_big = _check_delivered(_drain(big))
        got_small = _check_delivered(_drain(small))
        drop_big, drop_small = big.rx_dropped, small.rx_dropped
        for name, value in [
            ("send_s", round(send_s, 3)),
            ("big_rcvbuf_bytes", big.rcvbuf_bytes), ("big_delivered", len(got_big)), ("big_rx_dropped", drop_big),
            ("default_rcvbuf_bytes", small.rcvbuf_bytes), ("default_delivered", len(got_small)),
            ("default_rx_dropped", drop_small),
        ]:
            record_property(name, value)
        print(f"burst of {N_BURST}: 64 MiB socket delivered {len(got_big)} dropped {drop_big}; "
              f"default socket ({small.rcvbuf_bytes} B) delivered {len(got_small)} dropped {drop_small}")

        # No silent loss: everything sent is either delivered or counted as dropped.
        assert len(got_big) + drop_big == N_BURST
        assert len(got_small) + drop_small == N_BURST
        # The default buffer cannot hold the burst; the enlarged one can.
        assert drop_small > 0 and len(got_small) < N_BURST
        assert drop_big == 0 and got_big == list(range(N_BURST))
        # The delivered frames of the small socket are the first ones (tail dropped).
        assert got_small == list(range(len(got_small)))

        # SO_RXQ_OVFL: the frames queued before the drops carry no count; the next
        # frame after the drops carries the kernel's cumulative counter.
        assert small.rx_dropped_at_last_frame == 0
        tx.send(can.Message(arbitration_id=0x7FF, data=b"sentinel"))
        sentinel = small.recv(timeout=2.0)
        assert sentinel is not None and bytes(sentinel.data) == b"sentinel"
        assert small.rx_dropped_at_last_frame == drop_small
        assert small.rx_dropped == drop_small  # no further drops
        assert big.recv(timeout=2.0) is not None and big.rx_dropped_at_last_frame == 0
    finally:
        for bus in (big, small, tx):
            bus.shutdown()


def _frames():
    """A mix of frames covering id ranges, extended/remote flags and every classic DLC."""
    out = []
    for i in range(600):
        ext = i % 3 == 1
        arb = (i * 7919) % (0x20000000 if ext else 0x800)
        out.append(can.Message(arbitration_id=arb, is_extended_id=ext, data=bytes((i + k) % 256 for k in range(i % 9))))
    out += [
        can.Message(arbitration_id=0x000, is_extended_id=False, data=b""),
        can.Message(arbitration_id=0x7FF, is_extended_id=False, data=b"\xff" * 8),
        can.Message(arbitration_id=0x1FFFFFFF, is_extended_id=True, data=b"\x00" * 8),
        can.Message(arbitration_id=0x00000001, is_extended_id=True, data=b"\x01"),
        can.Message(arbitration_id=0x123, is_extended_id=False, is_remote_frame=True, dlc=4),
        can.Message(arbitration_id=0x1ABCDE, is_extended_id=True, is_remote_frame=True, dlc=8),
    ]
    return out


def test_roundtrip_ids_data_flags_timestamps(vcan0):
    tx = OverflowAwareSocketcanBus(vcan0)
    rx = OverflowAwareSocketcanBus(vcan0)
    try:
        sent = _frames()
        received = []
        for msg in sent:
            t_before = time.time()
            tx.send(msg)
            got = rx.recv(timeout=2.0)
            t_after = time.time()
            assert got is not None, f"frame {msg} not received"
            # kernel receive time (SO_TIMESTAMPNS, CLOCK_REALTIME) lies between send and recv
            assert t_before - 1e-3 <= got.timestamp <= t_after + 1e-3, (t_before, got.timestamp, t_after)
            received.append(got)
        for s, r in zip(sent, received):
            assert (r.arbitration_id, r.is_extended_id, r.is_remote_frame, r.dlc) == (
                s.arbitration_id, s.is_extended_id, s.is_remote_frame, s.dlc), (s, r)
            if not s.is_remote_frame:
                assert bytes(r.data) == bytes(s.data), (s, r)
            # (python-can marks frames from this host, as all on vcan are, is_rx=False)
            assert r.channel == vcan0 and not r.is_error_frame and not r.is_fd
        stamps = [r.timestamp for r in received]
        assert stamps == sorted(stamps)
        assert rx.recv(timeout=0.2) is None
        assert rx.rx_dropped == 0 and rx.rx_dropped_at_last_frame == 0
    finally:
        tx.shutdown()
        rx.shutdown()


def test_roundtrip_canfd_and_filters(vcan0):
    with OverflowAwareSocketcanBus(vcan0, fd=True) as tx, OverflowAwareSocketcanBus(
        vcan0, fd=True, can_filters=[{"can_id": 0x123, "can_mask": 0x7FF, "extended": False}]
    ) as rx:
        std = dict(arbitration_id=0x123, is_extended_id=False, is_fd=True)
        tx.send(can.Message(arbitration_id=0x100, is_extended_id=False, data=b"skip"))
        tx.send(can.Message(arbitration_id=0x123, is_extended_id=True, data=b"extended, filtered out"[:8]))
        tx.send(can.Message(**std, bitrate_switch=True, data=bytes(range(64))))
        tx.send(can.Message(**std, error_state_indicator=True, data=bytes(12)))
        a, b = rx.recv(timeout=2.0), rx.recv(timeout=2.0)
        assert a.arbitration_id == b.arbitration_id == 0x123 and not a.is_extended_id
        assert a.is_fd and a.bitrate_switch and not a.error_state_indicator and bytes(a.data) == bytes(range(64))
        assert b.is_fd and b.error_state_indicator and b.dlc == 12 and bytes(b.data) == bytes(12)
        assert rx.recv(timeout=0.2) is None


@pytest.mark.parametrize("rcvbuf", [None, 4 * 2**20])
def test_rcvbuf_reported(vcan0, rcvbuf):
    with can.Bus(interface="socketcan", channel=vcan0) as plain:
        default = plain.socket.getsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF)  # net.core.rmem_default
    with OverflowAwareSocketcanBus(vcan0, rcvbuf_bytes=rcvbuf) as bus:
        # the kernel doubles what is asked for (socket(7)); as root SO_RCVBUFFORCE grants it all
        assert bus.rcvbuf_bytes == (default if rcvbuf is None else 2 * rcvbuf)
        assert bus.rcvbuf_bytes == bus.socket.getsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF)
