"""Integrity of reading recordings (issue 12, item 1): every chunk's CRC checked, damaged
chunks skipped with a warning naming the file, the byte offset and the frames lost, sizes
claimed by records bounded, recover writes only verified data."""

import json
import tracemalloc
import warnings

import numpy as np
import pytest
from daq_helpers import cli, random_messages

from wheelsoil.daq import FrameBatch, RecordingWriter, read_frames, read_recording_info
from wheelsoil.daq.compare import frame_differences
from wheelsoil.daq.recording import ReadReport, _plausible_record


def _recording(path, n_chunks=8, per_chunk=500, seed=1):
    msgs = random_messages(n_chunks * per_chunk, seed=seed, remote=False)
    with RecordingWriter(path) as w:
        for lo in range(0, len(msgs), per_chunk):
            w.write_frames("can0", msgs[lo:lo + per_chunk])
            w.flush()
    return msgs


def _chunk_offsets(path):
    data = path.read_bytes()
    with open(path, "rb") as f:
        return [i for i in range(len(data)) if data[i] == 6 and _plausible_record(f, i, len(data))]


def _read(path):
    rep = ReadReport()
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        got = read_frames(path, report=rep)
    return got, rep, [str(w.message) for w in caught]


def _all_frames_in(orig: FrameBatch, got: dict) -> int:
    """Frames delivered that are not in the original (altered), by (timestamp, id, data)."""
    want = {(int(t), int(i), bytes(d)) for t, i, d in zip(orig.timestamp_ns, orig.arbitration_id, orig.data)}
    b = got.get("can0")
    if b is None:
        return 0
    return sum((int(t), int(i), bytes(d)) not in want for t, i, d in zip(b.timestamp_ns, b.arbitration_id, b.data))


def test_byte_flip_in_a_chunk_fails_its_crc_and_no_altered_frame_is_delivered(tmp_path):
    path = tmp_path / "r.mcap"
    msgs = _recording(path)
    orig = FrameBatch.from_messages("can0", msgs)
    chunks = _chunk_offsets(path)
    assert len(chunks) == 8
    data = path.read_bytes()
    found_crc = False
    # flip bytes in the payload of chunk 3 until one decompresses (wrong data): the CRC must catch it
    for k in range(60, 400, 7):
        bad = bytearray(data)
        bad[chunks[3] + k] ^= 0x04
        p = tmp_path / f"flip{k}.mcap"
        p.write_bytes(bytes(bad))
        got, rep, ws = _read(p)
        assert _all_frames_in(orig, got) == 0, f"altered frames delivered (flip at +{k})"
        assert len(got["can0"]) == 3500, k  # exactly the damaged chunk is lost
        assert rep.damage and not rep.complete
        d = rep.damage[0]
        assert d["offset"] == chunks[3] and str(p) in d["message"]
        assert any(str(p) in w and f"byte {chunks[3]}" in w for w in ws)
        if d["kind"] == "crc":
            found_crc = True
            assert d["frames_lost"] == 500 and "frames lost: 500" in d["message"]
            info = read_recording_info(p)
            assert not info.complete and info.frames_lost_to_damage == 500
            assert info.to_dict()["damage"][0]["kind"] == "crc"
            break
    assert found_crc, "no flip decompressed silently: the test did not exercise the CRC"


def test_corrupted_record_type_is_reported_with_the_frames_lost(tmp_path):
    path = tmp_path / "r.mcap"
    _recording(path)
    chunks = _chunk_offsets(path)
    bad = bytearray(path.read_bytes())
    bad[chunks[2]] = 0x55
    p = tmp_path / "op.mcap"
    p.write_bytes(bytes(bad))
    got, rep, ws = _read(p)
    assert len(got["can0"]) == 3500
    assert rep.damage[0]["frames_lost"] == 500 and rep.damage[0]["offset"] == chunks[2]
    assert any("op.mcap" in w and "frames lost: 500" in w for w in ws)


def test_corrupted_record_length_loses_only_that_chunk(tmp_path):
    path = tmp_path / "r.mcap"
    msgs = _recording(path)
    chunks = _chunk_offsets(path)
    bad = bytearray(path.read_bytes())
    bad[chunks[4] + 1:chunks[4] + 9] = (10**12).to_bytes(8, "little")
    p = tmp_path / "len.mcap"
    p.write_bytes(bytes(bad))
    got, rep, ws = _read(p)
    assert len(got["can0"]) == 3500
    ref = FrameBatch.from_messages("can0", msgs[:2000] + msgs[2500:])
    assert frame_differences({"can0": ref}, got, flag_mask=0xFF) == []
    assert rep.damage[0]["offset"] == chunks[4] and "len.mcap" in rep.damage[0]["message"]


def _crafted_mcap(path, usize, with_content_size=False):
    """A tiny MCAP whose one chunk claims ``usize`` uncompressed bytes."""
    import zlib

    import zstandard
    from mcap.data_stream import RecordBuilder
    from mcap.records import Chunk, Header

    inner = b"\x05" + (30).to_bytes(8, "little") + bytes(30)
    comp = zstandard.ZstdCompressor(write_content_size=with_content_size).compress(inner)
    rb = RecordBuilder()
    Header(profile="", library="crafted").write(rb)
    for _ in range(50):
        Chunk(compression="zstd", data=comp, message_start_time=0, message_end_time=0,
              uncompressed_crc=zlib.crc32(inner), uncompressed_size=usize).write(rb)
    path.write_bytes(b"\x89MCAP0\r\n" + rb.end())


@pytest.mark.parametrize("usize", [3_200_000_000, 200_000_000])
def test_crafted_sizes_keep_memory_bounded_and_are_reported(tmp_path, usize):
    p = tmp_path / "crafted.mcap"
    _crafted_mcap(p, usize)
    tracemalloc.start()
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            info = read_recording_info(p)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert peak < 64 * 2**20, f"peak {peak / 2**20:.0f} MiB for a {p.stat().st_size}-byte file"
    assert len(info.damage) >= 50 and all(str(p) in d["message"] for d in info.damage)
    assert not info.complete


def test_record_claiming_more_than_the_file_is_a_clear_error_without_allocation(tmp_path):
    path = tmp_path / "r.mcap"
    _recording(path, n_chunks=2)
    data = bytearray(path.read_bytes())
    # the first record after the magic (header) claims 3 GB
    data[9:17] = (3 * 10**9).to_bytes(8, "little")
    p = tmp_path / "big.mcap"
    p.write_bytes(bytes(data))
    tracemalloc.start()
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            rep = ReadReport()
            read_frames(p, report=rep)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert peak < 64 * 2**20
    assert rep.damage and "big.mcap" in rep.damage[0]["message"] and "byte 8" in rep.damage[0]["message"]


def test_recover_writes_only_verified_chunks_and_records_what_it_dropped(tmp_path, capsys):
    path = tmp_path / "r.mcap"
    msgs = _recording(path)
    chunks = _chunk_offsets(path)
    bad = bytearray(path.read_bytes())
    bad[chunks[5]] = 0x55          # one chunk with a corrupted record type
    p = tmp_path / "bad.mcap"
    p.write_bytes(bytes(bad))
    out = tmp_path / "fixed.mcap"
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        assert cli("recover", p, "-o", out) == 0
    text = capsys.readouterr()
    assert "recovered 3500 frames" in text.out
    assert "kept the 0 frames" not in text.err
    got = read_frames(out)
    ref = FrameBatch.from_messages("can0", msgs[:2500] + msgs[3000:])
    assert frame_differences({"can0": ref}, got, flag_mask=0xFF) == []
    info = read_recording_info(out)
    assert info.complete
    note = info.metadata["wheelsoil.recovered"]
    assert note["source_complete"] == "False"
    dropped = json.loads(note["damage_json"])
    assert dropped and dropped[0]["frames_lost"] == 500


def test_truncated_file_message_counts_the_frames_kept(tmp_path):
    path = tmp_path / "r.mcap"
    _recording(path, n_chunks=4)
    data = path.read_bytes()
    p = tmp_path / "cut.mcap"
    p.write_bytes(data[: int(len(data) * 0.8)])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        info = read_recording_info(p)
    n = sum(info.stats.frames.values())
    assert n > 0 and any(f"kept the {n} frames" in w for w in info.warnings), info.warnings
    assert np.isclose(n % 500, 0)


def test_damaged_first_chunk_with_the_channel_definitions_loses_only_that_chunk(tmp_path):
    """Schema and channel records live in the chunk where they were first used; losing that
    chunk must not lose the later chunks of those channels (footer intact or not)."""
    a = random_messages(1500, seed=11, remote=False)
    b = random_messages(600, seed=12, remote=False)
    path = tmp_path / "r.mcap"
    with RecordingWriter(path) as w:
        w.write_frames("can0", a[:500])
        w.flush()
        w.write_frames("can1", b[:300])   # can1's channel registered in chunk 2
        w.flush()
        w.write_frames("can0", a[500:])
        w.write_frames("can1", b[300:])
        w.flush()
    first = _chunk_offsets(path)[0]
    data = bytearray(path.read_bytes())
    for cut in (None, len(data) - 200):
        found = False
        for k in range(60, 300, 5):
            bad = bytearray(data)
            bad[first + k] ^= 0x08
            p = tmp_path / "first.mcap"
            p.write_bytes(bytes(bad if cut is None else bad[:cut]))
            got, rep, _ = _read(p)
            if rep.damage and rep.damage[0]["offset"] == first:
                found = True
                assert len(got.get("can0", [])) == 1000 and len(got.get("can1", [])) == 600, (cut, k)
                break
        assert found


def _zstd_with_content_size(payload: bytes, claimed: int) -> bytes:
    """A zstd frame of ``payload`` whose header claims ``claimed`` bytes of content."""
    import zstandard

    f = zstandard.ZstdCompressor(write_content_size=False, write_checksum=False).compress(payload)
    desc = f[4]
    assert desc & 0xC0 == 0 and desc & 0x03 == 0  # no content size, no dictionary id
    single = desc & 0x20
    hdr_len = 5 + (0 if single else 1)
    window = b"" if single else f[5:6]
    new_desc = 0xC0 | (desc & 0x3C)             # 8-byte content size field, same other flags
    return f[:4] + bytes([new_desc]) + window + claimed.to_bytes(8, "little") + f[hdr_len:]


def test_crafted_zstd_frame_claiming_a_large_size_allocates_only_what_inflates(tmp_path):
    import zlib

    import zstandard
    from mcap.data_stream import RecordBuilder
    from mcap.records import Chunk, Header

    usize = 200_000_000
    inner = b"\x05" + (30).to_bytes(8, "little") + bytes(30)
    comp = _zstd_with_content_size(inner, usize)
    assert zstandard.get_frame_parameters(comp).content_size == usize
    rb = RecordBuilder()
    Header(profile="", library="crafted").write(rb)
    for _ in range(20):
        Chunk(compression="zstd", data=comp, message_start_time=0, message_end_time=0,
              uncompressed_crc=zlib.crc32(inner), uncompressed_size=usize).write(rb)
    p = tmp_path / "crafted2.mcap"
    p.write_bytes(b"\x89MCAP0\r\n" + rb.end())
    tracemalloc.start()
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            info = read_recording_info(p)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert peak < 64 * 2**20, f"peak {peak / 2**20:.0f} MiB"
    assert len(info.damage) >= 20 and all("crafted2.mcap" in d["message"] for d in info.damage)


def test_recordings_joined_end_to_end_are_reported_not_read_as_the_first_only(tmp_path):
    """Two recordings joined with cat: the first is read, and a warning names the byte where the second
    starts (that tail is the second file, byte for byte); the file is not 'complete'."""
    a, b, joined = tmp_path / "a.mcap", tmp_path / "b.mcap", tmp_path / "joined.mcap"
    first = _recording(a, n_chunks=2, seed=1)
    _recording(b, n_chunks=3, seed=2)
    joined.write_bytes(a.read_bytes() + b.read_bytes())
    got, rep, caught = _read(joined)
    assert len(got["can0"]) == len(first)
    assert not rep.complete and [d["kind"] for d in rep.damage] == ["appended"]
    at = rep.damage[0]["offset"]
    assert at == a.stat().st_size and str(at) in caught[0] and str(joined) in caught[0]
    assert joined.read_bytes()[at:] == b.read_bytes()
    _, rep_a, caught_a = _read(a)  # a single recording: no such warning
    assert rep_a.complete and not caught_a
    with pytest.raises(Exception, match="second MCAP recording"):
        read_frames(joined, recover=False)


def test_recover_with_no_frame_left_fails_and_writes_nothing(tmp_path):
    """A recording cut inside its first records: recover says no frame could be read and writes no
    output (before: 'recovered 0 frames', exit 0, an empty recording)."""
    from wheelsoil.daq.convert import recover_recording

    src = tmp_path / "run.mcap"
    _recording(src, n_chunks=2)
    cut = tmp_path / "cut.mcap"
    cut.write_bytes(src.read_bytes()[:100])
    with pytest.raises(ValueError, match="no CAN frame could be read"):
        recover_recording(cut, tmp_path / "out.mcap")
    assert not (tmp_path / "out.mcap").exists()
