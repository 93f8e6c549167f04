"""Fixtures for the guest-side tests in this folder (``guest_*.py``).

Those files run *inside* the qemu guest (see ``vcanvm.py`` and
``tests/test_vm_vcan.py``), where ``vcan0`` is real; pytest's default file
pattern (``test_*.py``) keeps them out of the host's test run.  Run by hand on a
host without AF_CAN they skip.
"""

import socket

import pytest


def _vcan0_reason():
    """None when a raw CAN socket can bind to vcan0, else why not."""
    if not hasattr(socket, "AF_CAN"):
        return "this Python has no socket.AF_CAN"
    try:
        s = socket.socket(socket.AF_CAN, socket.SOCK_RAW, socket.CAN_RAW)
    except OSError as exc:
        return f"no AF_CAN in this kernel ({exc})"
    try:
        s.bind(("vcan0",))
    except OSError as exc:
        return f"no vcan0 interface ({exc})"
    finally:
        s.close()
    return None


@pytest.fixture(scope="session")
def vcan0():
    """The name of a real, up SocketCAN interface ("vcan0"); skips without one."""
    reason = _vcan0_reason()
    if reason:
        pytest.skip(reason)
    return "vcan0"
