"""CPU time per received frame: python-can's SocketcanBus vs wheelsoil's OverflowAwareSocketcanBus.

Both receive the same 8-byte classic frames through the same kind of kernel
socket.  This host has no AF_CAN, so a loopback UDP socket stands in for the
raw CAN socket (queued datagrams carry python-can's ``struct can_frame`` bytes;
the receive queue, SO_TIMESTAMPNS and SO_RXQ_OVFL are the generic socket
layer's).  What differs is only the Python code per frame: the overflow tap
(a larger ancillary buffer, filtering the SO_RXQ_OVFL control message).

Run: ``python benchmarks/bench_socketcan_recv.py`` (about 5 s).
"""

import logging
import socket
import time

import can
from can.interfaces.socketcan import socketcan as pycan_socketcan

from wheelsoil.daq.socketcan import SO_RCVBUFFORCE, OverflowAwareSocketcanBus

N = 50_000
ROUNDS = 3


def _open(cls):
    rx = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    pycan_socketcan.create_socket = lambda: rx
    pycan_socketcan.bind_socket = lambda sock, channel: sock.bind(("127.0.0.1", 0))
    bus = cls(channel="vcan0")
    if cls is pycan_socketcan.SocketcanBus:  # same queue size for both
        try:
            bus.socket.setsockopt(socket.SOL_SOCKET, SO_RCVBUFFORCE, 64 * 2**20)
        except PermissionError:
            bus.socket.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 64 * 2**20)
    return bus


def _us_per_frame(cls, tx, frame) -> float:
    bus = _open(cls)
    try:
        addr = bus.socket.getsockname()
        for _ in range(N):
            tx.sendto(frame, addr)
        t0 = time.process_time()
        for _ in range(N):
            if bus.recv(0) is None:
                raise RuntimeError("frame lost in the benchmark (receive buffer too small?)")
        return (time.process_time() - t0) / N * 1e6
    finally:
        bus.shutdown()


def main() -> None:
    logging.disable(logging.ERROR)  # python-can logs the CAN-only options the UDP socket refuses
    frame = pycan_socketcan.build_can_frame(can.Message(arbitration_id=0x123, is_extended_id=False, data=bytes(8)))
    tx = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    results = {pycan_socketcan.SocketcanBus: [], OverflowAwareSocketcanBus: []}
    for _ in range(ROUNDS):
        for cls in results:
            results[cls].append(_us_per_frame(cls, tx, frame))
    base, ours = (min(v) for v in results.values())
    print(f"recv CPU per frame, best of {ROUNDS} x {N} frames (UDP stand-in socket):")
    print(f"  python-can SocketcanBus       {base:6.2f} us")
    print(f"  OverflowAwareSocketcanBus     {ours:6.2f} us   ({ours / base:.2f}x, +{ours - base:.2f} us)")


if __name__ == "__main__":
    main()
