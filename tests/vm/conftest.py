"""Fixtures for the guest-side tests in this folder (``guest_*.py``).

Those files run *inside* the qemu guest (see ``vcanvm.py`` and
``tests/test_vm_vcan.py``), where ``vcan0`` is real; pytest's default file
pattern (``test_*.py``) keeps them out of the host's test run.  Run by hand on a
host without AF_CAN they skip.
"""

import socket

import pytest


def _iface_reason(name):
    """None when a raw CAN socket can bind to interface ``name``, else why not."""
    if not hasattr(socket, "AF_CAN"):
        return "this Python has no socket.AF_CAN"
    try:
        s = socket.socket(socket.AF_CAN, socket.SOCK_RAW, socket.CAN_RAW)
    except OSError as exc:
        return f"no AF_CAN in this kernel ({exc})"
    try:
        s.bind((name,))
    except OSError as exc:
        return f"no {name} interface ({exc})"
    finally:
        s.close()
    return None


@pytest.fixture(scope="session")
def vcan0():
    """The name of a real, up SocketCAN interface ("vcan0"); skips without one."""
    reason = _iface_reason("vcan0")
    if reason:
        pytest.skip(reason)
    return "vcan0"


@pytest.fixture(scope="session")
def vcan1(vcan0):
    """A second real SocketCAN interface ("vcan1"); skips without one."""
    reason = _iface_reason("vcan1")
    if reason:
        pytest.skip(reason)
    return "vcan1"
