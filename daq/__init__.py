"""wheelsoil.daq: CAN capture on the vehicle, MCAP recordings, import/export, replay.

Public API (contract in docs/architecture.md)::

    from wheelsoil.daq import FrameBatch, iter_frame_batches, read_frames, RecordingWriter
    from wheelsoil.daq import VehicleConfig, load_vehicle_config, read_recording_info

The MCAP layout is described in docs/mcap-layout.md.
"""

from .config import REQUIRED_SIGNALS, SignalRef, VehicleConfig, load_vehicle_config
from .frames import FrameBatch
from .info import RecordingInfo, load_recording_config, read_recording_info
from .recording import RecordingError, RecordingWriter, iter_frame_batches, read_frames
from .stats import FrameStats, frame_stats

__all__ = [
    "FrameBatch", "iter_frame_batches", "read_frames", "RecordingWriter", "RecordingError",
    "VehicleConfig", "SignalRef", "load_vehicle_config", "REQUIRED_SIGNALS",
    "read_recording_info", "RecordingInfo", "load_recording_config", "FrameStats", "frame_stats",
]
