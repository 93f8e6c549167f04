"""wheelsoil.processing: from raw CAN frames to the signals of the wheel-soil fit.

Public API (contract in docs/architecture.md)::

    from wheelsoil.processing import process_recording, ProcessResult, decode_batches

- :func:`decode_batches` / :class:`Decoder` (``decode.py``): vectorised DBC decoding.
- :func:`process_recording` (``pipeline.py``): decode, WFT rotation and lost
  frames (``wft.py``), GPS time mapping and GNSS latency (``timesync.py``),
  zero-phase filtering and resampling (``filters.py``), slip by the paper's
  Eq. (6), phases and accelerate cycles (``slip.py``).
"""

from importlib import import_module

# Names are imported on first use (PEP 562) so that ``wheelsoil --help`` and the
# subcommands that do not process do not pay for scipy.signal and pandas.
_LAZY = {
    "DecodedMessage": ".decode", "Decoder": ".decode", "decode_batches": ".decode",
    "DEFAULT_CUTOFF_HZ": ".filters",
    "COLUMNS": ".pipeline", "ProcessResult": ".pipeline", "process_recording": ".pipeline",
}


def __getattr__(name):
    if name in _LAZY:
        return getattr(import_module(_LAZY[name], __name__), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")

__all__ = ["process_recording", "ProcessResult", "COLUMNS", "decode_batches", "Decoder",
           "DecodedMessage", "DEFAULT_CUTOFF_HZ"]
