"""Guest-side: the field logger under a 10,000-frame burst on a real vcan0 (run inside the VM).

The burst is sent while the logger's bus socket is open but before the logger
reads (the worst case: a reader that falls behind).  With the logger's default
receive buffer every frame is recorded; with a tiny buffer the kernel drops
most of them and the logger reports exactly that many drops in its status and
in the recording's summary: recorded + reported drops == sent, never a silent loss.
"""

import time

import can
import pytest

from wheelsoil.daq import read_frames, read_recording_info
from wheelsoil.daq.buses import DEFAULT_RCVBUF_BYTES, open_bus, parse_bus_spec
from wheelsoil.daq.logger import CanLogger
from wheelsoil.daq.socketcan import OverflowAwareSocketcanBus

N_BURST = 10_000


@pytest.mark.parametrize("rcvbuf_bytes", [DEFAULT_RCVBUF_BYTES, 8192], ids=["logger-default", "tiny"])
def test_logger_burst_no_silent_loss(vcan0, tmp_path, rcvbuf_bytes, record_property):
    bus = open_bus(parse_bus_spec(f"can0=socketcan:{vcan0}"), rcvbuf_bytes=rcvbuf_bytes)
    try:
        assert isinstance(bus, OverflowAwareSocketcanBus), type(bus)
        with can.Bus(interface="socketcan", channel=vcan0) as tx:
            for i in range(N_BURST):
                tx.send(can.Message(arbitration_id=0x100 + i % 0x600, is_extended_id=False,
                                    data=i.to_bytes(4, "little")))
        dropped_before = bus.rx_dropped  # what the kernel says it dropped (SO_MEMINFO)
        out = tmp_path / "burst.mcap"
        t0 = time.monotonic()
        result = CanLogger({"can0": bus}, out).run(duration_s=90, max_frames=N_BURST - dropped_before)
        log_s = time.monotonic() - t0
    finally:
        bus.shutdown()

    recorded = result.frames.get("can0", 0)
    reported = result.status["buses"]["can0"]["rx_dropped"]
    for k, v in dict(rcvbuf_granted=bus.rcvbuf_bytes, recorded=recorded, rx_dropped=reported,
                     log_s=round(log_s, 1), stop_reason=result.stop_reason).items():
        record_property(k, v)
    print(f"logger with {bus.rcvbuf_bytes} B receive buffer: {recorded} of {N_BURST} recorded, "
          f"{reported} reported dropped ({result.stop_reason} after {log_s:.1f} s)")
    assert result.stop_reason == "max_frames", "fewer frames arrived than the kernel's count explains"
    assert recorded + reported == N_BURST
    assert reported == dropped_before

    frames = read_frames(out)["can0"]
    assert len(frames) == recorded
    seq = [int.from_bytes(bytes(row[:4]), "little") for row in frames.data]
    assert seq == list(range(recorded)), "recorded frames are not the first ones in order"
    info = read_recording_info(out)
    assert info.complete and info.rx_dropped() == {"can0": reported}
    if rcvbuf_bytes == DEFAULT_RCVBUF_BYTES:
        assert reported == 0 and recorded == N_BURST
    else:
        assert reported > 0
