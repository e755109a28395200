"""LogFile on byte strings built by hand from the format description."""

import gzip
import struct
from pathlib import Path

import pytest

from ssllog import logfile
from ssllog.logfile import LogFile
from ssllog.reader import LogFormatError
from ssllog.writer import LogWriter
from sslpb import ssl_gc_referee_message_pb2, ssl_vision_wrapper_pb2

HEAD = b"SSL_LOG_FILE" + struct.pack(">i", 1)
S = 1_000_000_000
T0 = 1_700_000_000 * S

Referee = ssl_gc_referee_message_pb2.Referee


def rec(t: int, typ: int, payload: bytes) -> bytes:
    return struct.pack(">qii", t, typ, len(payload)) + payload


def wrapper(camera: int, frame: int) -> bytes:
    w = ssl_vision_wrapper_pb2.SSL_WrapperPacket()
    d = w.detection
    d.frame_number = frame
    d.t_capture = frame / 60
    d.t_sent = frame / 60
    d.camera_id = camera
    b = d.balls.add()
    b.confidence, b.x, b.y, b.pixel_x, b.pixel_y = 0.9, 100.0, -50.0, 1.0, 2.0
    r = d.robots_blue.add()
    r.confidence, r.robot_id, r.x, r.y, r.orientation = 0.8, 3, 1000.0, 500.0, 1.5
    r.pixel_x, r.pixel_y = 1.0, 2.0
    return w.SerializeToString()


def referee(
    counter: int,
    command: int,
    stage: int = Referee.NORMAL_FIRST_HALF,
    yellow: tuple[int, int, int] = (0, 0, 0),
    blue: tuple[int, int, int] = (0, 0, 0),
) -> bytes:
    r = Referee()
    r.packet_timestamp = 1
    r.stage_time_left = 300_000_000  # a real GC always sends it (ssl-log-stats needs it)
    r.stage = stage
    r.command = command
    r.command_counter = counter
    r.command_timestamp = 1
    for info, (score, yc, rc), name in ((r.yellow, yellow, "Yel"), (r.blue, blue, "Blu")):
        info.name = name
        info.score, info.yellow_cards, info.red_cards = score, yc, rc
        info.timeouts = info.timeout_time = info.goalkeeper = 0
    return r.SerializeToString()


def vision_log(n: int, cams: int = 2) -> bytes:
    """n records alternating cameras, 1/120 s apart."""
    return HEAD + b"".join(
        rec(T0 + i * S // 120, 4, wrapper(i % cams, i // cams)) for i in range(n)
    )


def test_index_seek_and_stream(tmp_path: Path) -> None:
    p = tmp_path / "a.log"
    p.write_bytes(vision_log(1000))
    calls: list[float] = []
    with LogFile.open(str(p), tmp_path / "cache", calls.append) as lf:
        assert calls and calls[-1] == 1.0
        assert lf.data_path == str(p)
        assert lf.counts == {4: 1000}
        assert lf.cameras == {0: 500, 1: 500}
        assert lf.t_first_ns == T0 and lf.t_last_ns == T0 + 999 * S // 120
        assert lf.duration_s == pytest.approx(999 / 120, abs=1e-6)
        assert lf.gaps == [] and lf.warning is None
        all_recs = list(lf.records())
        assert len(all_recs) == 1000 and all_recs[0].offset == 16
        for i in (0, 1, 63, 64, 65, 500, 999):
            t = all_recs[i].time_ns
            assert lf.offset_at(t) == all_recs[i].offset
            assert lf.offset_at(t - 1) == all_recs[i].offset
        assert lf.offset_at(T0 - S) == 16
        assert lf.offset_at(T0 + 100 * S) == lf.data_end == p.stat().st_size
        assert [r.offset for r in lf.records(all_recs[700].offset)][:2] == [
            all_recs[700].offset, all_recs[701].offset]
        # one frame back, across an index entry
        assert lf.prev_record_offset(all_recs[129].offset, 4) == all_recs[128].offset
        assert lf.prev_record_offset(all_recs[128].offset, 4) == all_recs[127].offset
        assert lf.prev_record_offset(16, 4) is None
        assert lf.read_at(all_recs[5].offset) == all_recs[5]


def test_prev_record_of_a_type_far_back(tmp_path: Path) -> None:
    p = tmp_path / "a.log"
    p.write_bytes(HEAD + rec(T0, 3, referee(1, Referee.HALT)) + vision_log(500)[16:])
    with LogFile.open(str(p), tmp_path / "c") as lf:
        last = list(lf.records())[-1]
        assert lf.prev_record_offset(last.offset, 3) == 16


def test_index_cache_is_reused_and_redone_when_file_changes(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    p = tmp_path / "a.log"
    p.write_bytes(vision_log(100))
    scans = 0
    real = logfile.build_index

    def counting(*a, **k):  # type: ignore[no-untyped-def]
        nonlocal scans
        scans += 1
        return real(*a, **k)

    monkeypatch.setattr(logfile, "build_index", counting)
    LogFile.open(str(p), tmp_path / "c").close()
    calls: list[float] = []
    with LogFile.open(str(p), tmp_path / "c", calls.append) as lf:
        assert lf.counts == {4: 100}
    assert scans == 1 and calls == []
    p.write_bytes(vision_log(120))
    with LogFile.open(str(p), tmp_path / "c") as lf:
        assert lf.counts == {4: 120}
    assert scans == 2


def test_gzip_copy_made_once_in_cache_dir(tmp_path: Path) -> None:
    src = tmp_path / "in"
    src.mkdir()
    gz = src / "m.log.gz"
    gz.write_bytes(gzip.compress(vision_log(300)))
    cache = tmp_path / "cache"
    calls: list[float] = []
    with LogFile.open(str(gz), cache, calls.append) as lf:
        assert lf.path == str(gz)
        assert Path(lf.data_path).parent == cache
        assert Path(lf.data_path).read_bytes() == vision_log(300)
        assert lf.counts == {4: 300}
        first_copy = Path(lf.data_path).stat().st_mtime_ns
    assert calls and calls[-1] == 1.0 and calls == sorted(calls)  # one bar, never backwards
    assert any(0 < c <= 0.7 for c in calls)  # the copy reports too
    assert sorted(x.name for x in src.iterdir()) == ["m.log.gz"]  # nothing beside the user's file
    calls.clear()
    with LogFile.open(str(gz), cache, calls.append) as lf:
        assert Path(lf.data_path).stat().st_mtime_ns == first_copy
        assert len(list(lf.records())) == 300
    assert calls == []  # neither decompressed nor rescanned
    assert not [x for x in cache.iterdir() if ".tmp" in x.name]


def test_gzip_cut_short_is_playable_with_warning(tmp_path: Path) -> None:
    import os

    whole = gzip.compress(HEAD + b"".join(rec(T0 + i, 4, os.urandom(200)) for i in range(50)))
    gz = tmp_path / "k.log.gz"
    gz.write_bytes(whole[: len(whole) * 3 // 4])
    with LogFile.open(str(gz), tmp_path / "c") as lf:
        n = len(list(lf.records()))
        assert 0 < n < 50 and lf.warning is not None


def test_truncated_tail_keeps_valid_part(tmp_path: Path) -> None:
    p = tmp_path / "a.log"
    good = HEAD + rec(T0, 4, wrapper(0, 0)) + rec(T0 + 1, 4, wrapper(1, 0))
    p.write_bytes(good + rec(T0 + 2, 4, wrapper(0, 1))[:-3])
    with LogFile.open(str(p), tmp_path / "c") as lf:
        assert lf.warning is not None and f"byte {len(good)}" in lf.warning
        assert len(list(lf.records())) == 2
        assert lf.data_end == len(good) and lf.t_last_ns == T0 + 1
        assert lf.offset_at(T0 + 2) == len(good)
    p.write_bytes(good + b"\x00" * 7)  # a cut record header
    with LogFile.open(str(p), tmp_path / "c") as lf:
        assert lf.warning is not None and "header" in lf.warning
        assert lf.counts == {4: 2}


@pytest.mark.parametrize("size", [-1, 64 * 1024 * 1024 + 1])
def test_corrupt_record_names_offset(tmp_path: Path, size: int) -> None:
    p = tmp_path / "a.log"
    p.write_bytes(HEAD + rec(T0, 4, b"abc") + struct.pack(">qii", T0, 4, size) + b"x" * 40)
    with pytest.raises(LogFormatError) as e:
        LogFile.open(str(p), tmp_path / "c")
    assert e.value.offset == 35 and "35" in str(e.value)


@pytest.mark.parametrize("data", [b"", b"SSL_LOG", b"NOT_A_LOG_FI" + b"\0\0\0\1",
                                  b"SSL_LOG_FILE" + b"\0\0\0\2"])
def test_bad_header(tmp_path: Path, data: bytes) -> None:
    p = tmp_path / "a.log"
    p.write_bytes(data)
    with pytest.raises(LogFormatError):
        LogFile.open(str(p), tmp_path / "c")


def test_garbage_never_crashes(tmp_path: Path) -> None:
    import random

    rng = random.Random(1)
    for i in range(40):
        body = bytearray(vision_log(20))
        for _ in range(5):
            body[rng.randrange(16, len(body))] = rng.randrange(256)
        p = tmp_path / f"g{i}.log"
        p.write_bytes(bytes(body))
        try:
            with LogFile.open(str(p), tmp_path / "c") as lf:
                list(lf.records())
        except LogFormatError:
            pass


def test_unknown_types_counted_and_index_record_skipped(tmp_path: Path) -> None:
    p = tmp_path / "a.log"
    w = LogWriter(str(p))
    w.write(T0, 4, wrapper(0, 0))
    w.write(T0 + 1, 1001, b"touchline")
    w.write(T0 + 2, 1001, b"touchline")
    w.write(T0 + 3, 77, b"")
    w.write(T0 + 4, 3, referee(1, Referee.HALT))
    w.finish()
    with LogFile.open(str(p), tmp_path / "c") as lf:
        assert lf.unknown_types == {1001: 2, 77: 1}
        assert lf.has_index_record
        assert [r.type for r in lf.records()] == [4, 3]
        assert [r.type for r in lf.records(include_unknown=True)] == [4, 1001, 1001, 77, 3]
        assert lf.t_last_ns == T0 + 4  # the index record's time 0 is not a receive time


def test_referee_events(tmp_path: Path) -> None:
    C = Referee
    msgs = [
        referee(1, C.HALT, C.NORMAL_FIRST_HALF_PRE),
        referee(1, C.HALT, C.NORMAL_FIRST_HALF_PRE),  # nothing new
        referee(2, C.STOP, C.NORMAL_FIRST_HALF_PRE),
        referee(3, C.PREPARE_KICKOFF_BLUE, C.NORMAL_FIRST_HALF),
        referee(4, C.NORMAL_START, C.NORMAL_FIRST_HALF),
        referee(5, C.STOP, C.NORMAL_FIRST_HALF, blue=(1, 0, 0)),
        referee(6, C.DIRECT_FREE_YELLOW, C.NORMAL_FIRST_HALF, blue=(1, 1, 0)),
        referee(6, C.DIRECT_FREE_YELLOW, C.NORMAL_FIRST_HALF, yellow=(0, 0, 1), blue=(1, 1, 0)),
    ]
    p = tmp_path / "r.log"
    p.write_bytes(HEAD + b"".join(rec(T0 + i * S, 3, m) for i, m in enumerate(msgs)))
    with LogFile.open(str(p), tmp_path / "c") as lf:
        got = [((e.time_ns - T0) // S, e.kind, e.label, e.team) for e in lf.events]
        assert lf.teams == {"yellow": "Yel", "blue": "Blu"}
    assert got == [
        (0, "stage", "NORMAL_FIRST_HALF_PRE", ""),
        (0, "command", "HALT", ""),
        (2, "command", "STOP", ""),
        (3, "stage", "NORMAL_FIRST_HALF", ""),
        (3, "command", "PREPARE_KICKOFF_BLUE", "blue"),
        (4, "command", "NORMAL_START", ""),
        (5, "command", "STOP", ""),
        (5, "goal", "Blu (0:1)", "blue"),
        (6, "command", "DIRECT_FREE_YELLOW", "yellow"),
        (6, "card", "yellow card Blu", "blue"),
        (7, "card", "red card Yel", "yellow"),
    ]


def test_cameras_and_gaps(tmp_path: Path) -> None:
    recs = [rec(T0 + i * S // 60, 4, wrapper(c, i)) for i in range(10) for c in (0, 1, 5)]
    recs.append(rec(T0 + 3 * S, 3, referee(1, Referee.HALT)))  # not vision: still a gap
    recs.append(rec(T0 + 5 * S, 4, wrapper(5, 99)))
    recs.append(rec(T0 + 5 * S + 1, 4, b"\x12\x00"))  # a wrapper without detection
    p = tmp_path / "v.log"
    p.write_bytes(HEAD + b"".join(recs))
    with LogFile.open(str(p), tmp_path / "c") as lf:
        assert lf.cameras == {0: 10, 1: 10, 5: 11}
        assert lf.gaps == [(T0 + 9 * S // 60, T0 + 5 * S)]


def test_camera_scanner_agrees_with_protobuf() -> None:
    for cam in (0, 1, 7, 200, 1000):
        b = wrapper(cam, 123456)
        assert logfile._camera_id(b, 0, len(b)) == cam
    assert logfile._camera_id(b"\xff\xff\xff", 0, 3) is None
    assert logfile._camera_id(b"", 0, 0) is None


def test_gzip_of_several_members(tmp_path: Path) -> None:
    data = vision_log(50)
    gz = tmp_path / "two.log.gz"
    gz.write_bytes(gzip.compress(data[:500]) + gzip.compress(data[500:]))
    with LogFile.open(str(gz), tmp_path / "c") as lf:
        assert lf.counts == {4: 50} and lf.warning is None


def test_broken_cache_files_are_redone(tmp_path: Path) -> None:
    gz = tmp_path / "m.log.gz"
    gz.write_bytes(gzip.compress(vision_log(30)))
    cache = tmp_path / "c"
    LogFile.open(str(gz), cache).close()
    for f in cache.iterdir():
        if f.suffix == ".json":
            f.write_text('{"half')
    calls: list[float] = []
    with LogFile.open(str(gz), cache, calls.append) as lf:
        assert lf.counts == {4: 30}
    assert calls  # done again rather than crashing


def test_a_file_written_by_ssl_log_recorder() -> None:
    """Recorded by ssl-go-tools' ssl-log-recorder (stopped with SIGINT) from multicast
    packets: 2 cameras at 60 Hz, referee at 10 Hz: HALT, STOP, FORCE_START, a blue goal,
    DIRECT_FREE_BLUE."""
    import tempfile

    src = Path(__file__).parent / "data" / "ssl-log-recorder.log.gz"
    with tempfile.TemporaryDirectory() as cache, LogFile.open(str(src), cache) as lf:
        assert lf.counts == {3: 35, 4: 422} and lf.warning is None
        assert lf.cameras == {0: 211, 1: 211}
        assert [e.label for e in lf.events if e.kind == "command"] == [
            "HALT", "STOP", "FORCE_START", "DIRECT_FREE_BLUE"]
        assert [e.label for e in lf.events if e.kind == "goal"] == ["Blu (0:1)"]
        assert 3.5 < lf.duration_s < 3.6
        mid = lf.offset_at(lf.t_first_ns + 2 * S)
        assert lf.read_at(mid).time_ns >= lf.t_first_ns + 2 * S


def test_gaps_at_the_start_and_end_and_without_vision(tmp_path: Path) -> None:
    ref = referee(1, Referee.HALT)
    p = tmp_path / "v.log"
    p.write_bytes(HEAD + rec(T0, 3, ref) + rec(T0 + 2 * S, 4, wrapper(0, 0))
                  + rec(T0 + 2 * S + 1, 4, wrapper(0, 1)) + rec(T0 + 4 * S, 3, ref))
    with LogFile.open(str(p), tmp_path / "c") as lf:
        assert lf.gaps == [(T0, T0 + 2 * S), (T0 + 2 * S + 1, T0 + 4 * S)]
    p.write_bytes(HEAD + rec(T0, 3, ref) + rec(T0 + 3 * S, 3, ref))
    with LogFile.open(str(p), tmp_path / "c") as lf:
        assert lf.gaps == [(T0, T0 + 3 * S)] and lf.cameras == {}


def test_operator_actions_are_timeline_events(tmp_path: Path) -> None:
    """Touchline's own type-1003 records (JSON) become "operator" events; a record that is
    not JSON is skipped, not fatal."""
    from ssllog.format import TYPE_TL_ACTION

    action = b'{"action": "referee", "by": "operator at 127.0.0.1", "command": "STOP"}'
    data = (HEAD + rec(T0, 4, wrapper(0, 1)) + rec(T0 + S, TYPE_TL_ACTION, action)
            + rec(T0 + S + 1, TYPE_TL_ACTION, b"\xff not json")
            + rec(T0 + 2 * S, 4, wrapper(0, 2)))
    path = tmp_path / "a.log"
    path.write_bytes(data)
    lf = LogFile.open(str(path), tmp_path / "cache")
    ops = [e for e in lf.events if e.kind == "operator"]
    assert [(e.time_ns, e.label) for e in ops] == [
        (T0 + S, "referee STOP (operator at 127.0.0.1)")]


def test_open_from_the_cache_only(tmp_path: Path) -> None:
    """build=False (the station, after its indexing process): the cache's index is used, a
    file without one (or changed since) is refused, never scanned."""
    import gzip as gz_

    p = tmp_path / "m.log"
    p.write_bytes(vision_log(100))
    with pytest.raises(logfile.NotCached):
        LogFile.open(str(p), tmp_path / "c", build=False)
    LogFile.open(str(p), tmp_path / "c").close()
    with LogFile.open(str(p), tmp_path / "c", build=False) as lf:
        assert lf.counts == {4: 100}
    p.write_bytes(vision_log(120))  # changed: its key differs
    with pytest.raises(logfile.NotCached):
        LogFile.open(str(p), tmp_path / "c", build=False)
    g = tmp_path / "m.log.gz"
    g.write_bytes(gz_.compress(vision_log(50)))
    with pytest.raises(logfile.NotCached, match="no decompressed copy"):
        LogFile.open(str(g), tmp_path / "c", build=False)
    assert not list((tmp_path / "c").glob("*.log"))  # nothing decompressed for it
