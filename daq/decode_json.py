"""``wheelsoil decode``: add decoded signals as JSON channels (for Foxglove) to a recording.

An offline step, so the logger stays lean: the output is a copy of the
recording (raw frames, metadata, attachments, status) plus one JSON channel
per DBC message, topic ``/decoded/<bus>/<Message>``, one message per frame
with the physical signal values (cantools, DBC factor/offset applied) and
``log_time`` = the frame's receive time. Frames that do not decode (DLC
shorter than the DBC, unknown mux value) are counted per message.
"""

from __future__ import annotations

from pathlib import Path

from .frames import FLAG_ERROR, FLAG_REMOTE

DECODED_TOPIC = "/decoded/{bus}/{message}"


def _schema(msg) -> dict:
    props = {}
    for s in msg.signals:
        desc = s.comment or ""
        props[s.name] = {"type": "number", "description": f"[{s.unit or '-'}] {desc}".strip()}
    return {"title": f"wheelsoil.decoded.{msg.name}", "type": "object", "properties": props,
            "description": f"DBC message {msg.name} (0x{msg.frame_id:X}), physical values"}


def decode_recording(path, output, *, config=None, buses=None):
    """Copy ``path`` to ``output`` adding ``/decoded/<bus>/<Message>`` JSON channels.

    Args:
        config: :class:`VehicleConfig` for the DBCs; None: the one attached to
            the recording, else the shipped default.
        buses: buses to decode (None: all with DBCs).

    Returns:
        :class:`~wheelsoil.daq.convert.ConvertResult`; ``warnings`` lists
        frames that did not decode (per bus and message) and unknown ids.

    Raises:
        OSError: unreadable input/unwritable output. ValueError: not an MCAP file,
        output = input.
    """
    from .config import load_vehicle_config
    from .convert import rewrite_recording
    from .info import load_recording_config

    fallback = None
    if config is None:
        try:
            config = load_recording_config(path)
        except ValueError as exc:  # a malformed attached configuration: say so, use the default
            fallback = (f"{path}: the vehicle configuration attached to the recording is unusable ({exc}); "
                        "decoded with the default vehicle.toml instead")
            config = None
        config = config or load_vehicle_config()
    channels: dict[tuple, int] = {}
    errors: dict[tuple, int] = {}
    unknown: dict[tuple, int] = {}
    decoded = [0]
    lookup: dict[str, dict] = {}
    for bus in config.buses:
        if buses is None or bus in buses:
            lookup[bus] = {(m.frame_id, bool(m.is_extended_frame)): m for m in config.database(bus).messages}

    def on_batch(w, b):
        table = lookup.get(b.bus)
        if not table:
            return
        n = b.payload_lengths().tolist()
        skip = ((b.flags & (FLAG_ERROR | FLAG_REMOTE)) != 0).tolist()
        for t, fid, ext, ln, sk, row in zip(b.timestamp_ns.tolist(), b.arbitration_id.tolist(),
                                            b.is_extended.tolist(), n, skip, b.data):
            if sk:
                continue
            msg = table.get((fid, ext))
            if msg is None:
                unknown[(b.bus, fid, ext)] = unknown.get((b.bus, fid, ext), 0) + 1
                continue
            try:
                values = msg.decode(bytes(row[:ln]), decode_choices=False)
            except Exception:  # short DLC, bad mux value: count, keep going
                errors[(b.bus, msg.name)] = errors.get((b.bus, msg.name), 0) + 1
                continue
            key = (b.bus, msg.name)
            cid = channels.get(key)
            if cid is None:
                cid = channels[key] = w.add_json_channel(
                    DECODED_TOPIC.format(bus=b.bus, message=msg.name), _schema(msg),
                    {"bus": b.bus, "frame_id": f"0x{msg.frame_id:X}", "dbc_message": msg.name})
            w.write_json(cid, t, {k: float(v) for k, v in values.items()})
            decoded[0] += 1

    res = rewrite_recording(path, output, on_batch=on_batch, note=("wheelsoil.decoded", {}))
    for (bus, name), c in sorted(errors.items()):
        res.warnings.append(f"{path}: bus {bus}: {c} {name} frame(s) did not decode (DLC or mux value "
                            "does not match the DBC); raw frames kept")
    for (bus, fid, ext), c in sorted(unknown.items()):
        res.warnings.append(f"{path}: bus {bus}: {c} frame(s) with id 0x{fid:X}{' (ext)' if ext else ''} "
                            "not in the DBCs; raw frames kept")
    if fallback:
        res.warnings.insert(0, fallback)
    res.skipped = sum(errors.values())
    res.output = Path(output)
    res.decoded = decoded[0]
    return res
