"""The vectorised decoder equals cantools' Message.decode frame by frame.

Property-based: random DBC messages (random start bit, length, byte order,
sign, float, scale, offset, multiplexing, 11/29-bit ids, classic and FD
lengths, truncated frames) and random payload bytes, decoded by cantools one
frame at a time and by ``wheelsoil.processing.decode`` in one call.
"""

from __future__ import annotations

from pathlib import Path

import cantools
import numpy as np
import pytest
from cantools.database.can import Message, Signal
from cantools.database.conversion import BaseConversion
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from wheelsoil.daq.frames import FrameBatch
from wheelsoil.processing.decode import Decoder, decode_batches

DBC_DIR = Path(__file__).resolve().parents[1] / "dbc"


def make_batch(bus, frame_ids, extended, payloads, width=8, dlc=None):
    n = len(frame_ids)
    data = np.zeros((n, width), dtype=np.uint8)
    for i, p in enumerate(payloads):
        data[i, : len(p)] = np.frombuffer(bytes(p), dtype=np.uint8)
    dlc = np.array([len(p) for p in payloads] if dlc is None else dlc, dtype=np.uint8)
    ext = np.asarray(extended, dtype=bool)
    return FrameBatch(bus, np.arange(n, dtype=np.int64) * 1000, np.asarray(frame_ids, dtype=np.uint32),
                 ext, ext.astype(np.uint8), dlc, data)


def bits_of(byte_order, start, length):
    """Set of (byte, bit) a DBC signal occupies."""
    if byte_order == "little_endian":
        return {(p // 8, p % 8) for p in range(start, start + length)}
    msb_net = 8 * (start // 8) + 7 - start % 8
    return {(p // 8, 7 - p % 8) for p in range(msb_net, msb_net + length)}


def fits(byte_order, start, length, nbits):
    if byte_order == "little_endian":
        return start + length <= nbits
    msb_net = 8 * (start // 8) + 7 - start % 8
    return msb_net + length <= nbits


@st.composite
def random_message(draw):
    length = draw(st.sampled_from([8, 8, 8, 1, 3, 5, 12, 16, 64]))
    nbits = 8 * length
    extended = draw(st.booleans())
    frame_id = draw(st.integers(0, 0x1FFFFFFF if extended else 0x7FF))
    used: set = set()
    signals = []
    mux_name = None
    mux_values = None
    if draw(st.booleans()) and nbits >= 8:
        mux_len = draw(st.integers(1, 3))
        order = draw(st.sampled_from(["little_endian", "big_endian"]))
        start = 0 if order == "little_endian" else 7
        signals.append(Signal("MUX", start, mux_len, order, is_multiplexer=True))
        used |= bits_of(order, start, mux_len)
        mux_name, mux_values = "MUX", list(range(1 << mux_len))
    for k in range(draw(st.integers(1, 8))):
        order = draw(st.sampled_from(["little_endian", "big_endian"]))
        is_float = draw(st.integers(0, 9)) == 0
        if is_float:
            sig_len = draw(st.sampled_from([32, 64]))
        else:
            sig_len = draw(st.integers(1, 64))
        start = draw(st.integers(0, nbits - 1))
        if not fits(order, start, sig_len, nbits):
            continue
        occ = bits_of(order, start, sig_len)
        if occ & used:
            continue
        used |= occ
        signed = (not is_float) and draw(st.booleans())
        if draw(st.booleans()):
            scale, offset = draw(st.integers(-4, 4).filter(bool)), draw(st.integers(-1000, 1000))
        else:
            scale = draw(st.floats(1e-4, 1e3)) * draw(st.sampled_from([1, -1]))
            offset = draw(st.floats(-1e4, 1e4))
        mux_ids = None
        if mux_name is not None and draw(st.booleans()):
            mux_ids = sorted(draw(st.sets(st.sampled_from(mux_values), min_size=1)))
        conv = BaseConversion.factory(scale=scale, offset=offset, is_float=is_float)
        signals.append(Signal(f"S{k}", start, sig_len, order, signed, conversion=conv,
                              multiplexer_ids=mux_ids,
                              multiplexer_signal=mux_name if mux_ids else None))
    return Message(frame_id, "M", length, signals, is_extended_frame=extended,
                   is_fd=length > 8, strict=False)


def assert_equal_to_cantools(msg, payloads, decoded, allow_truncated=False):
    for i, payload in enumerate(payloads):
        try:
            ref = msg.decode(bytes(payload), decode_choices=False, scaling=True,
                             allow_truncated=allow_truncated)
        except cantools.database.DecodeError:
            # unknown multiplexer value: every multiplexed signal is absent
            for s in msg.signals:
                if s.multiplexer_signal is not None:
                    assert np.isnan(decoded[s.name][i]), (s, payload)
            continue
        for s in msg.signals:
            ours = decoded[s.name][i]
            if s.name not in ref:
                assert np.isnan(ours), (s, payload.hex(), ours)
                continue
            want = float(ref[s.name])
            if np.isnan(want):
                assert np.isnan(ours), (s, payload.hex())
            else:
                assert ours == want, (s, payload.hex(), ours, want)


@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(msg=random_message(), seed=st.integers(0, 2**32 - 1))
def test_random_messages_equal_cantools(msg, seed):
    rng = np.random.default_rng(seed)
    n = 40
    payloads = [rng.integers(0, 256, msg.length, dtype=np.uint8).tobytes() for _ in range(n)]
    width = 64 if msg.length > 8 else 8
    batch = make_batch("can0", [msg.frame_id] * n, [msg.is_extended_frame] * n, payloads, width)
    db = cantools.database.Database(messages=[msg])
    out = decode_batches([batch], db)
    assert set(out) == {"M"}
    assert len(out["M"]) == n
    assert_equal_to_cantools(msg, payloads, out["M"].signals)


@settings(max_examples=60, deadline=None)
@given(msg=random_message(), seed=st.integers(0, 2**32 - 1))
def test_truncated_frames_drop_signals_like_cantools(msg, seed):
    rng = np.random.default_rng(seed)
    n = 20
    payloads = []
    for _ in range(n):
        k = int(rng.integers(0, msg.length + 1))
        payloads.append(rng.integers(0, 256, k, dtype=np.uint8).tobytes())
    width = 64 if msg.length > 8 else 8
    batch = make_batch("can0", [msg.frame_id] * n, [msg.is_extended_frame] * n, payloads, width)
    out = decode_batches([batch], cantools.database.Database(messages=[msg]))["M"]
    for i, p in enumerate(payloads):
        try:
            ref = msg.decode(bytes(p), decode_choices=False, allow_truncated=True)
        except cantools.database.DecodeError:
            continue  # unknown multiplexer value: checked in the test above
        for s in msg.signals:
            if s.name in ref:
                want = float(ref[s.name])
                assert out.signals[s.name][i] == want or (np.isnan(want) and np.isnan(out.signals[s.name][i]))
            else:
                assert np.isnan(out.signals[s.name][i]), (s, p.hex())


def test_encoded_values_round_trip_through_shipped_dbcs():
    """cantools encodes random physical values; we decode them back in one call."""
    rng = np.random.default_rng(1)
    for dbc in sorted(DBC_DIR.glob("*.dbc")):
        db = cantools.database.load_file(str(dbc))
        for msg in db.messages:
            ids, ext, payloads, values = [], [], [], []
            for _ in range(50):
                mux_choice = None
                vals = {}
                for s in msg.signals:
                    if s.is_multiplexer:
                        mux_choice = int(rng.choice(sorted({i for t in msg.signals for i in (t.multiplexer_ids or [])})))
                        vals[s.name] = mux_choice
                for s in msg.signals:
                    if s.is_multiplexer or (s.multiplexer_ids and mux_choice not in s.multiplexer_ids):
                        continue
                    lo = s.minimum if s.minimum is not None else 0
                    hi = s.maximum if s.maximum is not None else 1
                    vals[s.name] = float(rng.uniform(lo, hi))
                payloads.append(msg.encode(vals, strict=False))
                ids.append(msg.frame_id)
                ext.append(msg.is_extended_frame)
                values.append(vals)
            batch = make_batch("busX", ids, ext, payloads)
            out = decode_batches([batch], db)[msg.name]
            for i, p in enumerate(payloads):
                ref = msg.decode(p, decode_choices=False)
                for s in msg.signals:
                    if s.name in ref:
                        assert out.signals[s.name][i] == float(ref[s.name])
                        assert abs(out.signals[s.name][i] - values[i][s.name]) <= abs(s.scale) / 2 + 1e-9
                    else:
                        assert np.isnan(out.signals[s.name][i])


def test_standard_and_extended_ids_with_same_number_are_distinct():
    a = Message(0x123, "STD", 8, [Signal("A", 0, 8)], is_extended_frame=False)
    b = Message(0x123, "EXT", 8, [Signal("B", 0, 8)], is_extended_frame=True)
    db = cantools.database.Database(messages=[a, b])
    payloads = [bytes([i] + [0] * 7) for i in range(6)]
    ext = [False, True, False, True, True, False]
    batch = make_batch("can1", [0x123] * 6, ext, payloads)
    out = decode_batches([batch], db)
    np.testing.assert_array_equal(out["STD"].signals["A"], [0, 2, 5])
    np.testing.assert_array_equal(out["EXT"].signals["B"], [1, 3, 4])
    np.testing.assert_array_equal(out["EXT"].timestamp_ns, [1000, 3000, 4000])


def test_streaming_concatenates_chunks_and_skips_remote_frames():
    db = cantools.database.load_file(str(DBC_DIR / "wheel_speed.dbc"))
    msg = db.get_message_by_name("WSS_WheelSpeeds")
    chunks, want = [], []
    for c in range(3):
        payloads = []
        for i in range(10):
            v = {f"WheelSpeed_{w}": (c * 10 + i) * 1.0 for w in ("FL", "FR", "RL", "RR")}
            payloads.append(msg.encode(v))
        batch = make_batch("can1", [msg.frame_id] * 10, [False] * 10, payloads)
        batch.flags[3] = 0x02  # a remote frame: skipped
        chunks.append(batch)
        want += [c * 10 + i for i in range(10) if i != 3]
    out = decode_batches(iter(chunks), {"can1": [DBC_DIR / "wheel_speed.dbc"]},
                         select={"WSS_WheelSpeeds": ["WheelSpeed_RL"]})
    assert list(out) == ["WSS_WheelSpeeds"]
    assert list(out["WSS_WheelSpeeds"].signals) == ["WheelSpeed_RL"]
    np.testing.assert_allclose(out["WSS_WheelSpeeds"].signals["WheelSpeed_RL"], want)


def test_bus_mapping_and_bad_selection():
    with pytest.raises(ValueError, match="NoSuchMessage"):
        Decoder({"can0": [DBC_DIR / "wft.dbc"]}, select={"NoSuchMessage": None})
    with pytest.raises(ValueError, match="Nope"):
        Decoder({"can0": [DBC_DIR / "wft.dbc"]}, select={"WFT_RL_Force": ["Nope"]})
    with pytest.raises(OSError, match="missing.dbc"):
        Decoder({"can0": ["/nonexistent/missing.dbc"]})
    dec = Decoder({"can0": [DBC_DIR / "wft.dbc"]})
    db = cantools.database.load_file(str(DBC_DIR / "wft.dbc"))
    p = db.get_message_by_name("WFT_RL_Angle").encode({"WheelAngle": 90, "Counter": 3, "Status": 0})
    assert dec.decode_batch(make_batch("can1", [0x122], [False], [p])) == {}  # other bus: not decoded
    res = dec.decode_batch(make_batch("can0", [0x122], [False], [p]))
    assert res["WFT_RL_Angle"][1]["Counter"][0] == 3


def test_regrouping_into_chunks_keeps_every_frame_in_order():
    """Small, large, classic and FD batches regrouped into chunks decode as in one piece."""
    from wheelsoil.processing.decode import iter_chunks

    fd = Message(0x18FF0001, "FD", 64, [Signal("X", 500, 12), Signal("Y", 3, 16)], is_extended_frame=True,
                 is_fd=True)
    cl = Message(0x100, "CL", 8, [Signal("A", 0, 16, is_signed=True), Signal("B", 23, 9, "big_endian")])
    db = cantools.database.Database(messages=[fd, cl])
    rng = np.random.default_rng(7)
    batches = []
    for size in [3, 40, 1, 17, 100, 5, 33, 2]:
        width = 64 if rng.random() < 0.4 else 8
        is_fd = rng.random(size) < 0.5 if width == 64 else np.zeros(size, bool)
        payloads = [rng.integers(0, 256, 64 if f else 8, dtype=np.uint8).tobytes() for f in is_fd]
        ids = [fd.frame_id if f else cl.frame_id for f in is_fd]
        batches.append(make_batch("can0", ids, is_fd, payloads, width))
    whole = decode_batches(batches, db, chunk_frames=10**6)
    small = decode_batches(batches, db, chunk_frames=16)
    for name in ("FD", "CL"):
        np.testing.assert_array_equal(small[name].timestamp_ns, whole[name].timestamp_ns)
        for sig in whole[name].signals:
            np.testing.assert_array_equal(small[name].signals[sig], whole[name].signals[sig])
    n_in = sum(len(b.timestamp_ns) for b in batches)
    assert sum(len(c.timestamp_ns) for c in iter_chunks(batches, 16)) == n_in
    assert len(whole["FD"]) + len(whole["CL"]) == n_in


def test_every_frame_of_a_test_recording_equals_cantools(tmp_path):
    """All frames of a simulated recording (WFT incl. multiplexed diagnostics, wheel
    speeds, 29-bit GNSS) decoded in one pass equal cantools frame by frame."""
    import sys

    sys.path.insert(0, str(Path(__file__).resolve().parent))
    from processing_sim import truth_profile, write_recording

    from wheelsoil.daq import iter_frame_batches, load_vehicle_config, read_frames

    info = write_recording(tmp_path / "r.mcap", truth_profile(1), seed=3)
    cfg = load_vehicle_config()
    out = decode_batches(iter_frame_batches(info["path"]), cfg.buses)
    frames = read_frames(info["path"])
    checked = 0
    for bus, fb in frames.items():
        db = cfg.database(bus)
        seen: dict[str, int] = {}
        for i in range(len(fb)):
            msg = db.get_message_by_frame_id(int(fb.arbitration_id[i]))
            assert bool(fb.is_extended[i]) == msg.is_extended_frame
            k = seen.get(msg.name, 0)
            seen[msg.name] = k + 1
            ref = msg.decode(fb.data[i, :fb.dlc[i]].tobytes(), decode_choices=False)
            dm = out[msg.name]
            assert dm.timestamp_ns[k] == fb.timestamp_ns[i]
            for sig, values in dm.signals.items():
                if sig in ref:
                    assert values[k] == float(ref[sig]), (msg.name, sig, i)
                else:
                    assert np.isnan(values[k]), (msg.name, sig, i)
            checked += 1
        assert all(len(out[name]) == n for name, n in seen.items())
    assert checked == sum(len(fb) for fb in frames.values())
    assert {"WFT_RL_Diag", "WSS_Status", "RT_SB_GPS_Time", "WSS_WheelSpeeds"} <= set(out)
