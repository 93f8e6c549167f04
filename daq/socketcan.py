"""SocketCAN bus that never loses frames silently.

A raw CAN socket has a receive queue of ``SO_RCVBUF`` bytes (``net.core.rmem_default``,
212992 on Debian); every queued classic frame costs the kernel's socket-buffer
*truesize* (about 0.7-1 KiB on x86_64), so a reader that falls behind by a few
hundred frames loses the rest: a 10,000-frame burst on ``vcan0`` delivered 278
frames to a default socket.  The kernel does count those drops per socket
(``sk_drops``) and hands the count out in two ways, both used here:

- ``SO_RXQ_OVFL`` (socket(7)): each received frame carries, as ancillary data,
  the socket's cumulative drop counter at the moment the frame was queued
  (a ``uint32``; the kernel attaches it only once the counter is non-zero).
- ``SO_MEMINFO`` (Linux >= 4.6, ``include/uapi/linux/sock_diag.h``): the current
  counter at any time, so drops after the last delivered frame show as well.

:class:`OverflowAwareSocketcanBus` is python-can's
:class:`can.interfaces.socketcan.SocketcanBus` with a large receive buffer
(``SO_RCVBUFFORCE`` when the process may, else ``SO_RCVBUF``), ``SO_RXQ_OVFL``
switched on and the drop counter exposed as :attr:`~OverflowAwareSocketcanBus.rx_dropped`.
Frame parsing and the kernel receive timestamps (``SO_TIMESTAMPNS``) are
python-can's own (:func:`can.interfaces.socketcan.socketcan.capture_message`);
this module only filters the extra control message out of its way.

Linux only (AF_CAN).  Socket option numbers are those of
``include/uapi/asm-generic/socket.h`` (x86, arm, arm64, riscv, ...).
"""

from __future__ import annotations

import logging
import select
import socket
import struct
import threading
from typing import Optional

import can
from can.interfaces.socketcan.socketcan import (
    RECEIVED_TIMESTAMP_STRUCT,
    SocketcanBus,
    capture_message,
)

__all__ = [
    "OverflowAwareSocketcanBus",
    "KernelDropCounter",
    "split_overflow_cmsg",
    "read_socket_drops",
    "SO_RCVBUFFORCE",
    "SO_RXQ_OVFL",
    "SO_MEMINFO",
]

log = logging.getLogger(__name__)

#: socket(7) option numbers, include/uapi/asm-generic/socket.h (not all are in Python's socket module).
SO_RCVBUFFORCE = getattr(socket, "SO_RCVBUFFORCE", 33)
SO_RXQ_OVFL = getattr(socket, "SO_RXQ_OVFL", 40)
SO_MEMINFO = getattr(socket, "SO_MEMINFO", 55)

_DROPCOUNT = struct.Struct("=I")  # __u32, net/core/sock.c: sock_recv_drops()
_MEMINFO = struct.Struct("=9I")  # __u32[SK_MEMINFO_VARS], index 8 = SK_MEMINFO_DROPS
_SK_MEMINFO_DROPS = 8
#: Room for both control messages: the timestamp (struct timespec) and the drop counter.
ANCILLARY_BUFFER_SIZE = socket.CMSG_SPACE(RECEIVED_TIMESTAMP_STRUCT.size) + socket.CMSG_SPACE(
    _DROPCOUNT.size
)


class KernelDropCounter:
    """Unwraps the kernel's 32-bit per-socket drop counter into a cumulative count.

    The kernel's ``sk_drops`` starts at 0 when the socket opens and wraps at 2**32.
    Readings come from two places (per-frame ``SO_RXQ_OVFL`` values, which are as
    old as the frame, and live ``SO_MEMINFO`` values), so a reading that is
    *behind* the newest one seen (modular difference >= 2**31) is stale and ignored.

    Attributes:
        total: cumulative frames dropped since the socket was opened (int).

    Source: Linux net/core/sock.c (``sk_drops``, ``sock_skb_set_dropcount``).
    """

    __slots__ = ("total", "_last_raw")

    def __init__(self) -> None:
        self.total = 0
        self._last_raw = 0

    def update(self, raw: int) -> int:
        """Feed one raw ``uint32`` counter reading; return the cumulative total.

        Raises:
            ValueError: if ``raw`` is not in ``[0, 2**32)``.
        """
        if not 0 <= raw <= 0xFFFFFFFF:
            raise ValueError(f"kernel drop counter must be a uint32, got {raw}")
        delta = (raw - self._last_raw) & 0xFFFFFFFF
        if delta < 0x80000000:
            self.total += delta
            self._last_raw = raw
        return self.total


def split_overflow_cmsg(ancdata: list) -> tuple[list, Optional[int]]:
    """Take the ``SO_RXQ_OVFL`` control message out of ``socket.recvmsg`` ancillary data.

    Args:
        ancdata: list of ``(cmsg_level, cmsg_type, cmsg_data: bytes)`` tuples as
            returned by :meth:`socket.socket.recvmsg`.

    Returns:
        ``(rest, dropcount)``: the other control messages in their order (for
        python-can's timestamp parser) and the raw ``uint32`` drop counter, or
        ``None`` when the frame carried none (the kernel sends it only once
        the socket has dropped something).

    Raises:
        ValueError: if the ``SO_RXQ_OVFL`` payload is shorter than 4 bytes.

    Source: socket(7) ``SO_RXQ_OVFL``; net/core/sock.c ``sock_recv_drops()``.
    """
    rest = []
    dropcount = None
    for level, kind, data in ancdata:
        if level == socket.SOL_SOCKET and kind == SO_RXQ_OVFL:
            if len(data) < _DROPCOUNT.size:
                raise ValueError(
                    f"SO_RXQ_OVFL control message has {len(data)} bytes, expected {_DROPCOUNT.size}"
                )
            (dropcount,) = _DROPCOUNT.unpack_from(data)
        else:
            rest.append((level, kind, data))
    return rest, dropcount


def read_socket_drops(sock: socket.socket) -> Optional[int]:
    """Current raw ``uint32`` drop counter of a socket via ``SO_MEMINFO``.

    Returns:
        ``SK_MEMINFO_DROPS`` of the socket, or ``None`` where the kernel has no
        ``SO_MEMINFO`` (Linux < 4.6) or returns a shorter array.

    Source: include/uapi/linux/sock_diag.h (``SK_MEMINFO_*``), net/core/sock.c.
    """
    try:
        raw = sock.getsockopt(socket.SOL_SOCKET, SO_MEMINFO, _MEMINFO.size)
    except OSError:
        return None
    if len(raw) < _MEMINFO.size:
        return None
    return _MEMINFO.unpack_from(raw)[_SK_MEMINFO_DROPS]


def grow_receive_buffer(sock: socket.socket, nbytes: int) -> int:
    """Ask for a socket receive buffer of ``nbytes`` and return what the kernel granted.

    ``SO_RCVBUFFORCE`` (needs CAP_NET_ADMIN, e.g. root) ignores
    ``net.core.rmem_max``; without the capability it fails with EPERM and plain
    ``SO_RCVBUF`` is used, which the kernel caps at ``rmem_max``.  The kernel
    doubles the value for its bookkeeping overhead; the returned number is the
    doubled one, as ``getsockopt(SO_RCVBUF)`` reports it (socket(7)).

    Args:
        sock: the socket.
        nbytes: requested size in bytes, ``0 < nbytes < 2**30``.

    Returns:
        The granted ``SO_RCVBUF`` in bytes.

    Raises:
        ValueError: for a size outside ``(0, 2**30)``.
        OSError: if even ``SO_RCVBUF`` cannot be set.
    """
    if not 0 < nbytes < 2**30:
        raise ValueError(f"receive buffer size must be in (0, 2**30) bytes, got {nbytes}")
    try:
        sock.setsockopt(socket.SOL_SOCKET, SO_RCVBUFFORCE, nbytes)
    except PermissionError:
        sock.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, nbytes)
    return sock.getsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF)


class _OverflowTap:
    """Stands in for the socket in python-can's ``capture_message``: asks for room
    for both control messages, feeds ``SO_RXQ_OVFL`` to the drop counter and
    passes the rest (the ``SO_TIMESTAMPNS`` timestamp) on unchanged."""

    __slots__ = ("sock", "counter")

    def __init__(self, sock: socket.socket, counter: KernelDropCounter) -> None:
        self.sock = sock
        self.counter = counter  # updated by the receiving thread only

    def recvmsg(self, bufsize: int, ancbufsize: int = 0, flags: int = 0):
        data, ancdata, msg_flags, addr = self.sock.recvmsg(bufsize, ANCILLARY_BUFFER_SIZE, flags)
        rest, dropcount = split_overflow_cmsg(ancdata)
        if dropcount is not None:
            self.counter.update(dropcount)
        return data, rest, msg_flags, addr


class OverflowAwareSocketcanBus(SocketcanBus):
    """python-can's SocketCAN bus with a large receive buffer and kernel drop counts.

    Use it exactly like ``can.Bus(interface="socketcan", channel=...)``; received
    messages are python-can's (same parsing, ``timestamp`` = kernel receive time
    from ``SO_TIMESTAMPNS`` in seconds since the epoch).

    Args:
        channel: interface name, e.g. ``"can0"`` or ``"vcan0"``.
        rcvbuf_bytes: receive buffer to request in bytes (default 64 MiB, about
            10 s of both vehicle buses saturated); ``None`` or ``0`` keeps the
            kernel default (``net.core.rmem_default``).
        **kwargs: passed to :class:`can.interfaces.socketcan.SocketcanBus`
            (``fd``, ``can_filters``, ``receive_own_messages``, ...).

    Attributes:
        rcvbuf_bytes: the receive buffer the kernel granted, bytes, as
            ``getsockopt(SO_RCVBUF)`` reports it (twice the requested value when granted in full).
        rx_dropped: see the property.
        rx_dropped_at_last_frame: see the property.

    Raises:
        OSError: if the interface does not exist or AF_CAN is missing (from python-can).
        ValueError: for a receive buffer size outside ``(0, 2**30)``.

    Source: socket(7) (SO_RCVBUF, SO_RCVBUFFORCE, SO_RXQ_OVFL);
    Linux Documentation/networking/can.rst (raw sockets, timestamps).
    """

    def __init__(self, channel: str, rcvbuf_bytes: Optional[int] = 64 * 2**20, **kwargs) -> None:
        super().__init__(channel=channel, **kwargs)
        try:
            if rcvbuf_bytes:
                self.rcvbuf_bytes = grow_receive_buffer(self.socket, int(rcvbuf_bytes))
                if self.rcvbuf_bytes < rcvbuf_bytes:
                    log.warning(
                        "%s: kernel granted a receive buffer of %d bytes, %d requested "
                        "(SO_RCVBUFFORCE needs CAP_NET_ADMIN; or raise net.core.rmem_max)",
                        channel, self.rcvbuf_bytes, rcvbuf_bytes,
                    )
            else:
                self.rcvbuf_bytes = self.socket.getsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF)
            self.socket.setsockopt(socket.SOL_SOCKET, SO_RXQ_OVFL, 1)
        except BaseException:
            self.shutdown()
            raise
        # Two unwrapped views of the same kernel counter, each written by one side only, so
        # the receiving thread and a status thread never race on one: the per-frame
        # SO_RXQ_OVFL values (receiving thread) and the live SO_MEMINFO value (callers).
        self._tap = _OverflowTap(self.socket, KernelDropCounter())
        self._live_drops = KernelDropCounter()
        self._live_lock = threading.Lock()

    @property
    def rx_dropped(self) -> int:
        """Frames the kernel dropped for this socket since it opened (receive queue full).

        Cumulative int: the ``SO_RXQ_OVFL`` counts delivered with received frames,
        refreshed from ``SO_MEMINFO`` on each access so drops after the last
        delivered frame count too (one ``getsockopt`` per access).
        """
        raw = read_socket_drops(self.socket)
        with self._live_lock:
            if raw is not None:
                self._live_drops.update(raw)
            return max(self._live_drops.total, self._tap.counter.total)

    @property
    def rx_dropped_at_last_frame(self) -> int:
        """Drops the kernel reported with the most recent frame that carried a count
        (``SO_RXQ_OVFL``): frames lost *before* that frame was queued; cumulative, 0 if none yet."""
        return self._tap.counter.total

    def _recv_internal(self, timeout: Optional[float]) -> tuple[Optional[can.Message], bool]:
        # SocketcanBus._recv_internal with the socket swapped for the overflow tap.
        try:
            ready, _, _ = select.select([self.socket], [], [], timeout)
        except OSError as error:
            raise can.CanOperationError(f"Failed to receive: {error.strerror}", error.errno) from error
        if not ready:
            return None, self._is_filtered
        msg = capture_message(self._tap, self.channel == "")
        if msg is not None and not msg.channel and self.channel:
            msg.channel = self.channel
        return msg, self._is_filtered

