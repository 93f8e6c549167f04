"""foreign10: vectorised CAN frame packing driven by the sensors' DBC files
(cantools provides the signal layouts; bytes are verified against
cantools' own encoder for the first frames of every message), and the log
writers (python-can) for candump .log, Vector .asc, .blf and PEAK .trc."""
import os
import io
import numpy as np
import cantools
import can

HERE = os.path.dirname(os.path.abspath(__file__))
DBC_DIR = os.path.join(HERE, "dbc")


def load_db():
    db = cantools.database.Database()
    for f in ("wft.dbc", "wheel_speed.dbc", "gps_rt_speedbox.dbc"):
        db.add_dbc_file(os.path.join(DBC_DIR, f))
    return db


def _bit_positions(sig):
    """(byte, bit) of each raw bit, raw bit 0 (LSB) first."""
    pos = []
    if sig.byte_order == "little_endian":
        for k in range(sig.length):
            p = sig.start + k
            pos.append((p // 8, p % 8))
    else:  # Motorola: DBC start bit is the MSB, sawtooth numbering
        p = sig.start
        msb_first = []
        for _ in range(sig.length):
            msb_first.append((p // 8, p % 8))
            p = p + 15 if p % 8 == 0 else p - 1
        pos = msb_first[::-1]
    return pos


def to_raw(sig, phys):
    raw = np.rint((np.asarray(phys, float) - sig.offset) / sig.scale).astype(np.int64)
    if sig.is_signed:
        lo, hi = -(1 << (sig.length - 1)), (1 << (sig.length - 1)) - 1
    else:
        lo, hi = 0, (1 << sig.length) - 1
    sat = (raw < lo) | (raw > hi)
    raw = np.clip(raw, lo, hi)
    return raw & ((1 << sig.length) - 1), sat


def pack(msg, values, n):
    """values: signal name -> array (physical units) of length n.
    Returns uint8 array (n, msg.length) and a saturation flag per frame."""
    data = np.zeros((n, msg.length), np.uint8)
    sat_any = np.zeros(n, bool)
    for sig in msg.signals:
        if sig.name not in values:
            continue
        raw, sat = to_raw(sig, np.broadcast_to(values[sig.name], (n,)))
        sat_any |= sat
        for k, (byte, bit) in enumerate(_bit_positions(sig)):
            data[:, byte] |= (((raw >> k) & 1) << bit).astype(np.uint8)
    return data, sat_any


def verify(db, msg_name, values, data, idx=(0, 1, 2)):
    """Check our bytes against cantools' encoder for a few frames."""
    msg = db.get_message_by_name(msg_name)
    for i in idx:
        if i >= data.shape[0]:
            continue
        sig_vals = {}
        for s in msg.signals:
            if s.name in values:
                raw, _ = to_raw(s, np.asarray(values[s.name]).reshape(-1)[[i]] if np.ndim(values[s.name]) else [values[s.name]])
                r = int(raw[0])
                if s.is_signed and r >= (1 << (s.length - 1)):
                    r -= 1 << s.length
                sig_vals[s.name] = r * s.scale + s.offset
        ref = msg.encode(sig_vals, scaling=True, strict=False)
        if bytes(data[i]) != bytes(ref):
            raise AssertionError(f"packing mismatch {msg_name} frame {i}: {bytes(data[i]).hex()} != {ref.hex()}")


# ---------------------------------------------------------------------------
FORMATS = ("log", "asc", "blf", "trc")


def write_log(path, ts, ids, ext_flags, datas, chans):
    """ts: host timestamps (s, epoch), chans: 'can0'|'can1'."""
    ext = os.path.splitext(path)[1][1:]
    if ext == "log":
        w = can.CanutilsLogWriter(path, channel="can0")
    elif ext == "asc":
        w = can.ASCWriter(path, channel=1)
    elif ext == "blf":
        w = can.BLFWriter(path, channel=1)
    elif ext == "trc":
        w = can.TRCWriter(path, channel=1)
    else:
        raise ValueError(ext)
    Message = can.Message
    if ext != "log":   # integer channels: 0 -> "1" (can0), 1 -> "2" (can1) in ASC/BLF/TRC
        chans = [int(c[-1]) for c in chans]
    for t, i, e, d, c in zip(ts.tolist(), ids.tolist(), ext_flags.tolist(), datas, chans):
        w.on_message_received(Message(timestamp=t, arbitration_id=i, is_extended_id=e,
                                      data=d, channel=c, is_rx=True))
    w.stop()
    # make the text headers reproducible (no wall-clock date, no absolute path)
    if ext in ("asc", "trc"):
        with open(path, "r", newline="") as f:
            txt = f.read()
        lines = txt.split("\n")
        if ext == "asc" and lines[0].startswith("date "):
            # use the date of the first frame, as the Begin Triggerblock line does
            for ln in lines:
                if ln.startswith("Begin Triggerblock "):
                    lines[0] = "date " + ln[len("Begin Triggerblock "):].rstrip("\r")
                    break
        if ext == "trc":
            for k, ln in enumerate(lines[:8]):
                if ln.startswith(";   ") and os.sep in ln and os.path.abspath(path) in ln.replace("\r", ""):
                    lines[k] = ";   " + os.path.basename(path) + ("\r" if ln.endswith("\r") else "")
        with open(path, "w", newline="") as f:
            f.write("\n".join(lines))
