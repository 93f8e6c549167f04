"""Bus specifications (``[NAME=]INTERFACE:CHANNEL[,key=value...]``) and opening them."""

from __future__ import annotations

import re
import warnings
from dataclasses import dataclass, field

#: Default socket receive buffer asked for on SocketCAN buses [bytes].
DEFAULT_RCVBUF_BYTES = 64 * 1024 * 1024  # ~10 s of both vehicle buses saturated

_NAME_RE = re.compile(r"^[A-Za-z_][A-Za-z0-9_.-]*$")


@dataclass(frozen=True)
class BusSpec:
    """One bus to open with python-can.

    Attributes:
        name: bus name in recordings (``can0``; ``NAME=`` prefix, else the
            channel if it is a plain name such as ``can0``/``vcan0``/``ch0``,
            else ``can<i>`` by position).
        interface: python-can interface (``socketcan``, ``virtual``, ``udp_multicast``, ...).
        channel: python-can channel (``can0``, ``239.0.0.1``, ...).
        kwargs: extra keyword arguments for :class:`can.Bus` (``bitrate=500000``).
        named: True if the name was given explicitly.
    """

    name: str
    interface: str
    channel: str
    kwargs: dict = field(default_factory=dict)
    named: bool = False


def _parse_value(v: str):
    for conv in (int, float):
        try:
            return conv(v)
        except ValueError:
            pass
    return {"true": True, "false": False}.get(v.lower(), v)


def parse_bus_spec(text: str, index: int = 0) -> BusSpec:
    """Parse ``[NAME=]INTERFACE:CHANNEL[,key=value...]``.

    Examples: ``socketcan:can0``, ``can1=socketcan:vcan0``,
    ``can0=udp_multicast:239.0.0.1``, ``virtual:ch0``,
    ``pcan:PCAN_USBBUS1,bitrate=500000``.

    Raises:
        ValueError: malformed text (names it and shows the expected form).
    """
    raw = text
    name = None
    head = text.split(":", 1)[0]
    if "=" in head:
        name, text = text.split("=", 1)
        if not _NAME_RE.match(name):
            raise ValueError(f"bus spec {raw!r}: bad bus name {name!r}")
    if ":" not in text:
        raise ValueError(f"bus spec {raw!r}: expected [NAME=]INTERFACE:CHANNEL, e.g. socketcan:can0 "
                         "or can0=udp_multicast:239.0.0.1")
    interface, rest = text.split(":", 1)
    parts = rest.split(",")
    channel = parts[0]
    kwargs = {}
    for p in parts[1:]:
        if "=" not in p:
            raise ValueError(f"bus spec {raw!r}: option {p!r} is not key=value")
        k, v = p.split("=", 1)
        kwargs[k.strip()] = _parse_value(v.strip())
    if not interface or not channel:
        raise ValueError(f"bus spec {raw!r}: empty interface or channel")
    named = name is not None
    if name is None:
        name = channel if _NAME_RE.match(channel) else f"can{index}"
    return BusSpec(name, interface, channel, kwargs, named)


def parse_bus_specs(texts) -> list[BusSpec]:
    """Parse several specs; bus names must be unique.

    Raises:
        ValueError: a malformed spec or a duplicate bus name.
    """
    specs = [parse_bus_spec(t, i) for i, t in enumerate(texts)]
    names = [s.name for s in specs]
    dup = {n for n in names if names.count(n) > 1}
    if dup:
        raise ValueError(f"duplicate bus name(s) {', '.join(sorted(dup))}: give names, "
                         "e.g. --bus can0=udp_multicast:239.0.0.1,port=43113 "
                         "--bus can1=udp_multicast:239.0.0.2,port=43114 (udp_multicast buses "
                         "on one port receive each other's frames: give each its own port)")
    return specs


def open_bus(spec: BusSpec, *, rcvbuf_bytes: int = DEFAULT_RCVBUF_BYTES, receive_own_messages=None):
    """Open a python-can bus for ``spec``.

    On ``socketcan`` this is ``wheelsoil.daq.socketcan.OverflowAwareSocketcanBus``
    (large receive buffer, kernel drop count in ``.rx_dropped``) when that
    module is available, else plain :class:`can.Bus` with a warning.

    Raises:
        ValueError/OSError: python-can cannot open it (message names the spec).
    """
    import can

    kw = dict(spec.kwargs)
    if receive_own_messages is not None:
        kw["receive_own_messages"] = receive_own_messages
    try:
        if spec.interface == "socketcan":
            try:
                from .socketcan import OverflowAwareSocketcanBus
            except ImportError as exc:
                warnings.warn(f"bus {spec.name}: kernel drop counting unavailable ({exc}); "
                              "using plain python-can socketcan", RuntimeWarning, stacklevel=2)
            else:
                return OverflowAwareSocketcanBus(spec.channel, rcvbuf_bytes=rcvbuf_bytes, **kw)
        return can.Bus(interface=spec.interface, channel=spec.channel, **kw)
    except (can.CanError, ImportError, OSError, ValueError, TypeError) as exc:
        raise OSError(f"bus {spec.name} ({spec.interface}:{spec.channel}): cannot open: {exc}") from None
