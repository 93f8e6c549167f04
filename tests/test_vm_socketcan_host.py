"""Host-side tests of ``wheelsoil.daq.socketcan`` that need no AF_CAN.

The real-vcan0 tests run in a VM (``tests/test_vm_vcan.py``); these cover the
same code on any Linux host: the drop-counter arithmetic, the ancillary-data
split on synthetic control messages, and the whole bus class on a UDP socket
standing in for the CAN socket (the kernel's receive queue, SO_RCVBUF,
SO_RXQ_OVFL, SO_MEMINFO and SO_TIMESTAMPNS are generic socket-layer features).
"""

import socket
import struct
import sys
import time

import pytest

can = pytest.importorskip("can")
from can.interfaces.socketcan import socketcan as pycan_socketcan  # noqa: E402

from wheelsoil.daq import socketcan as wsc  # noqa: E402

linux_only = pytest.mark.skipif(sys.platform != "linux", reason="Linux socket options")

TS = struct.Struct("@ll")  # struct timespec
U32 = struct.Struct("=I")


def test_drop_counter_accumulates_wraps_and_ignores_stale():
    c = wsc.KernelDropCounter()
    assert c.total == 0
    assert c.update(0) == 0
    assert c.update(5) == 5
    assert c.update(3) == 5  # older reading (a frame queued before later drops): ignored
    assert c.update(5) == 5
    assert c.update(0xFFFFFFF0) == 5  # a jump of >= 2**31 looks stale and is ignored ...
    c2 = wsc.KernelDropCounter()
    for raw in (0x70000000, 0xE0000000, 0x00000010):  # ... but steps below 2**31 wrap correctly
        c2.update(raw)
    assert c2.total == 2**32 + 0x10
    with pytest.raises(ValueError, match="uint32"):
        c.update(-1)
    with pytest.raises(ValueError, match="uint32"):
        c.update(2**32)


def test_split_overflow_cmsg_on_synthetic_control_messages():
    ts = (socket.SOL_SOCKET, 35, TS.pack(1_700_000_000, 123_456_789))
    ovfl = (socket.SOL_SOCKET, wsc.SO_RXQ_OVFL, U32.pack(9722))
    other = (263, 1, b"\x01\x02")
    assert wsc.split_overflow_cmsg([ts, ovfl]) == ([ts], 9722)
    assert wsc.split_overflow_cmsg([ovfl, other, ts]) == ([other, ts], 9722)
    assert wsc.split_overflow_cmsg([ts]) == ([ts], None)
    assert wsc.split_overflow_cmsg([]) == ([], None)
    # same type number at another level is not ours
    foreign = (socket.SOL_IP, wsc.SO_RXQ_OVFL, U32.pack(1))
    assert wsc.split_overflow_cmsg([foreign]) == ([foreign], None)
    with pytest.raises(ValueError, match="SO_RXQ_OVFL control message has 2 bytes"):
        wsc.split_overflow_cmsg([(socket.SOL_SOCKET, wsc.SO_RXQ_OVFL, b"\x01\x00")])


class _FakeCanSocket:
    """Returns queued (frame bytes, ancdata) as socket.recvmsg would; records the ancbufsize asked for."""

    def __init__(self, items):
        self.items = list(items)
        self.ancbufsizes = []

    def recvmsg(self, bufsize, ancbufsize=0, flags=0):
        self.ancbufsizes.append(ancbufsize)
        frame, anc = self.items.pop(0)
        return frame, anc, 0, ("vcan0", 0)


def test_tap_feeds_python_can_parser_and_counts_drops():
    msgs = [
        can.Message(arbitration_id=0x1ABCDE0, is_extended_id=True, data=b"\x01\x02\x03"),
        can.Message(arbitration_id=0x123, is_extended_id=False, data=bytes(range(8))),
    ]
    frames = [pycan_socketcan.build_can_frame(m) for m in msgs]
    ts0 = (socket.SOL_SOCKET, 35, TS.pack(1_700_000_000, 500_000_000))
    ts1 = (socket.SOL_SOCKET, 35, TS.pack(1_700_000_001, 1))
    sock = _FakeCanSocket([(frames[0], [ts0]), (frames[1], [ts1, (socket.SOL_SOCKET, wsc.SO_RXQ_OVFL, U32.pack(42))])])
    counter = wsc.KernelDropCounter()
    tap = wsc._OverflowTap(sock, counter)

    a = pycan_socketcan.capture_message(tap)
    assert (a.arbitration_id, a.is_extended_id, bytes(a.data)) == (0x1ABCDE0, True, b"\x01\x02\x03")
    assert a.timestamp == pytest.approx(1_700_000_000.5, abs=1e-6)
    assert counter.total == 0

    b = pycan_socketcan.capture_message(tap)  # python-can asserts a single (timestamp) cmsg
    assert (b.arbitration_id, b.is_extended_id, bytes(b.data)) == (0x123, False, bytes(range(8)))
    assert b.timestamp == pytest.approx(1_700_000_001.0, abs=1e-6)
    assert counter.total == 42
    assert sock.ancbufsizes == [wsc.ANCILLARY_BUFFER_SIZE] * 2
    assert wsc.ANCILLARY_BUFFER_SIZE >= socket.CMSG_SPACE(16) + socket.CMSG_SPACE(4)


@linux_only
def test_grow_receive_buffer_reports_grant():
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as s:
        granted = wsc.grow_receive_buffer(s, 4 * 2**20)
        assert granted == s.getsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF)
        with open("/proc/sys/net/core/rmem_max") as f:
            rmem_max = int(f.read())
        # doubled by the kernel; capped at rmem_max unless SO_RCVBUFFORCE was allowed
        assert granted in (8 * 2**20, 2 * min(rmem_max, 4 * 2**20))
        for bad in (0, -1, 2**30):
            with pytest.raises(ValueError, match="receive buffer size"):
                wsc.grow_receive_buffer(s, bad)


@pytest.fixture
def udp_bus(monkeypatch):
    """OverflowAwareSocketcanBus whose CAN socket is a loopback UDP socket; yields (factory, sender)."""
    made = []

    def factory(**kwargs):
        rx = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        monkeypatch.setattr(pycan_socketcan, "create_socket", lambda: rx)
        monkeypatch.setattr(pycan_socketcan, "bind_socket", lambda sock, channel: sock.bind(("127.0.0.1", 0)))
        bus = wsc.OverflowAwareSocketcanBus("vcan0", **kwargs)  # CAN-only options fail and are logged
        made.append(bus)
        return bus

    tx = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    yield factory, tx
    tx.close()
    for bus in made:
        bus.shutdown()


def _send(tx, bus, i):
    msg = can.Message(arbitration_id=i % 0x800, is_extended_id=False, data=i.to_bytes(4, "little"))
    tx.sendto(pycan_socketcan.build_can_frame(msg), bus.socket.getsockname())


@linux_only
def test_bus_counts_kernel_drops_without_af_can(udp_bus):
    factory, tx = udp_bus
    small = factory(rcvbuf_bytes=4096)  # room for a few datagrams only
    assert small.rcvbuf_bytes >= 4096
    n = 500
    t0 = time.time()
    for i in range(n):
        _send(tx, small, i)
    got = []
    while (m := small.recv(timeout=0.2)) is not None:
        got.append(m)
    seq = [int.from_bytes(m.data, "little") for m in got]
    assert seq == list(range(len(seq))) and 0 < len(seq) < n
    assert all(m.arbitration_id == s % 0x800 and not m.is_extended_id for m, s in zip(got, seq))
    assert all(t0 - 1 <= m.timestamp <= time.time() + 1 for m in got)  # SO_TIMESTAMPNS kept
    # no frame after the drops yet: only SO_MEMINFO knows them
    assert small.rx_dropped_at_last_frame == 0
    assert small.rx_dropped == n - len(seq)
    _send(tx, small, 999_999)
    assert int.from_bytes(small.recv(timeout=2).data, "little") == 999_999
    assert small.rx_dropped_at_last_frame == n - len(seq)  # SO_RXQ_OVFL on the next frame
    assert small.rx_dropped == n - len(seq)


@linux_only
def test_bus_large_buffer_loses_nothing_without_af_can(udp_bus):
    factory, tx = udp_bus
    big = factory()  # default 64 MiB request
    n = 2000
    for i in range(n):
        _send(tx, big, i)
    seq = []
    while (m := big.recv(timeout=0.2)) is not None:
        seq.append(int.from_bytes(m.data, "little"))
    if big.rcvbuf_bytes >= 64 * 2**20:
        assert seq == list(range(n)) and big.rx_dropped == 0
    assert len(seq) + big.rx_dropped == n
