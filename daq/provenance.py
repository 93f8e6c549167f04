"""Where a recording came from: recorded, imported or simulated.

Every recording carries one ``wheelsoil.provenance`` MCAP metadata record.
MCAP metadata maps strings to strings, so each value is stored JSON-encoded;
:func:`provenance_to_metadata` and :func:`provenance_from_metadata` convert.

The record (a dict) always has:

- ``kind``: ``"recorded"`` (``wheelsoil log`` on the vehicle), ``"imported"``
  (``wheelsoil import`` of a candump/ASC/BLF/TRC log) or ``"simulated"``
  (``wheelsoil simulate``);
- ``wheelsoil_version``: the version that wrote the file;
- ``created_utc``: ISO 8601 time the file was written (UTC);
- ``host``: the machine that wrote the file;
- ``command``: the argument list of the command that wrote it (list of str,
  or ``None`` when written by a library call).

plus per kind:

- recorded: ``adapters`` (list of bus specs, e.g. ``"can0=socketcan:can0"``);
- imported: ``sources`` (list of ``{"path", "sha256", "size_bytes"}``);
- simulated: ``seed`` (int or None) and ``simulator`` (name and version).
  Never the hidden effect: it stays hidden.
"""

from __future__ import annotations

import hashlib
import json
import socket
import sys
import time
from pathlib import Path
from typing import Any, Mapping, Sequence

__all__ = ["PROVENANCE_RECORD", "KINDS", "make_provenance", "file_sha256",
           "provenance_to_metadata", "provenance_from_metadata"]

#: Name of the MCAP metadata record.
PROVENANCE_RECORD = "wheelsoil.provenance"
#: The kinds of origin.
KINDS = ("recorded", "imported", "simulated")


def _version() -> str:
    try:
        from importlib.metadata import version

        return version("wheelsoil")
    except Exception:  # noqa: BLE001 - not installed (source tree)
        return "unknown"


def file_sha256(path, chunk_bytes: int = 1 << 20) -> str:
    """SHA-256 hex digest of the file at ``path`` (read in 1 MiB chunks).

    Raises ``OSError`` when the file cannot be read.
    """
    h = hashlib.sha256()
    with open(path, "rb") as f:
        for block in iter(lambda: f.read(chunk_bytes), b""):
            h.update(block)
    return h.hexdigest()


def make_provenance(kind: str, *, command: Sequence[str] | None = None, **fields: Any) -> dict:
    """A provenance record of ``kind`` (see the module docstring).

    ``command`` defaults to ``sys.argv`` when the program is the ``wheelsoil``
    CLI, else ``None``. ``fields`` are the kind's own keys (``adapters``,
    ``sources``, ``seed``, ``simulator``...), JSON-serialisable.

    Raises ``ValueError`` for an unknown kind.
    """
    if kind not in KINDS:
        raise ValueError(f"provenance kind must be one of {', '.join(KINDS)}, got {kind!r}")
    if command is None and sys.argv and Path(sys.argv[0]).name.startswith("wheelsoil"):
        command = ["wheelsoil", *sys.argv[1:]]
    now = time.time()
    rec = {
        "kind": kind,
        "wheelsoil_version": _version(),
        "created_utc": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime(now)),
        "host": socket.gethostname(),
        "command": list(command) if command is not None else None,
    }
    rec.update(fields)
    return rec


def provenance_to_metadata(prov: Mapping[str, Any]) -> dict[str, str]:
    """The record as an MCAP metadata string map (every value JSON-encoded)."""
    return {str(k): json.dumps(v, sort_keys=True) for k, v in prov.items()}


def provenance_from_metadata(meta: Mapping[str, str] | None) -> dict | None:
    """Inverse of :func:`provenance_to_metadata`; ``None`` when ``meta`` is None/empty.

    A value that is not valid JSON is kept as the raw string (never raises).
    """
    if not meta:
        return None
    out: dict[str, Any] = {}
    for k, v in meta.items():
        try:
            out[k] = json.loads(v)
        except (TypeError, ValueError):
            out[k] = v
    return out
