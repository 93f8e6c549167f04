"""wheelsoil.processing: from raw CAN frames to the signals of the wheel-soil fit.

Public API (contract in docs/architecture.md)::

    from wheelsoil.processing import process_recording, ProcessResult, decode_batches

- :func:`decode_batches` / :class:`Decoder` (``decode.py``): vectorised DBC decoding.
- :func:`process_recording` (``pipeline.py``): decode, WFT rotation and lost
  frames (``wft.py``), GPS time mapping and GNSS latency (``timesync.py``),
  zero-phase filtering and resampling (``filters.py``), slip by the paper's
  Eq. (6), phases and accelerate cycles (``slip.py``).
"""

from .decode import DecodedMessage, Decoder, decode_batches
from .filters import DEFAULT_CUTOFF_HZ
from .pipeline import COLUMNS, ProcessResult, process_recording

__all__ = ["process_recording", "ProcessResult", "COLUMNS", "decode_batches", "Decoder",
           "DecodedMessage", "DEFAULT_CUTOFF_HZ"]
