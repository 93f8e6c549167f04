"""wheelsoil.daq: CAN capture on the vehicle, MCAP recordings, import/export, replay.

Public API (contract in docs/architecture.md)::

    from wheelsoil.daq import FrameBatch, iter_frame_batches, read_frames, RecordingWriter
    from wheelsoil.daq import VehicleConfig, load_vehicle_config, read_recording_info

Behind the commands: ``log_buses``/``CanLogger`` (wheelsoil log), ``import_log``,
``export_recording``, ``read_recording_info`` (info), ``replay_recording``,
``recover_recording``, ``decode_recording``; ``compare_recordings`` checks that
two recordings hold the same raw frames. The MCAP layout is described in
docs/mcap-layout.md.
"""

from .config import REQUIRED_SIGNALS, SignalRef, VehicleConfig, load_vehicle_config
from .frames import FrameBatch
from .info import RecordingInfo, load_recording_config, read_recording_info
from .recording import RecordingError, RecordingWriter, iter_frame_batches, read_frames
from .stats import FrameStats, frame_stats

# library functions behind the CLI commands (log, import, export, replay, recover, decode)
from .compare import compare_recordings, frame_differences
from .convert import export_recording, import_log, recover_recording
from .decode_json import decode_recording
from .logger import CanLogger, log_buses
from .replay import replay_recording

__all__ = [
    "FrameBatch", "iter_frame_batches", "read_frames", "RecordingWriter", "RecordingError",
    "VehicleConfig", "SignalRef", "load_vehicle_config", "REQUIRED_SIGNALS",
    "read_recording_info", "RecordingInfo", "load_recording_config", "FrameStats", "frame_stats",
    "CanLogger", "log_buses", "import_log", "export_recording", "recover_recording", "replay_recording",
    "decode_recording", "compare_recordings", "frame_differences",
]
