"""The session recorder: order, index, rotation, crash safety, a full disk, a stuck disk."""

from __future__ import annotations

import io
import json
import threading
import time
from pathlib import Path
from typing import BinaryIO

import pytest

from backend.recorder import SessionRecorder
from ssllog.format import TYPE_TL_ACTION, TYPE_TL_SESSION
from ssllog.reader import LogReader, Record
from ssllog.seek import read_index
from tests.waiting import wait_until

DEADLINE_S = 5.0


def read(path: Path) -> tuple[list[Record], LogReader]:
    r = LogReader(str(path))
    return list(r), r


def logs(folder: Path) -> list[Path]:
    return sorted(folder.glob("*.log"), key=lambda p: p.stat().st_mtime_ns)


def payloads(records: list[Record]) -> list[tuple[int, int, bytes]]:
    """The records other than the session header."""
    return [(r.time_ns, r.type, r.payload) for r in records if r.type != TYPE_TL_SESSION]


def test_records_come_out_in_order_with_an_index(tmp_path: Path) -> None:
    rec = SessionRecorder(tmp_path / "logs", our_team="yellow")
    sent = [(1000 + i, (4, 3, 5, 1001, TYPE_TL_ACTION)[i % 5], bytes([i % 256]) * (i % 7))
            for i in range(500)]
    for t, typ, p in sent:
        rec.record(t, typ, p)
    rec.close()
    rec.close()  # idempotent
    [path] = logs(tmp_path / "logs")
    assert path.name.startswith("touchline-") and path.name.endswith(".log")
    records, r = read(path)
    assert records[0].type == TYPE_TL_SESSION
    session = json.loads(records[0].payload)
    assert session["touchline"] == 1 and session["our_team"] == "yellow"
    assert session["reason"] == "start" and session["started_unix"] > 0
    assert payloads(records) == sent
    assert r.warning is None and r.unknown_types == {}
    assert r.index_offsets == [x.offset for x in records]
    assert read_index(str(path)) == r.index_offsets
    st = rec.status()
    assert st["recording"] is False and st["records_total"] == 501 and st["dropped"] == 0


def test_size_rotation_gives_several_indexed_files(tmp_path: Path) -> None:
    rec = SessionRecorder(tmp_path, max_bytes=4000)
    sent = [(i, 4, b"x" * 100) for i in range(200)]  # 116 bytes each: ~34 a file
    for t, typ, p in sent:
        rec.record(t, typ, p)
    rec.close()
    files = logs(tmp_path)
    assert len(files) >= 5
    assert len({f.name for f in files}) == len(files)
    got: list[tuple[int, int, bytes]] = []
    for f in files:
        records, r = read(f)
        assert r.index_offsets == [x.offset for x in records] and r.warning is None
        assert json.loads(records[0].payload)["reason"] in ("start", "size")
        got += payloads(records)
        # the data (without the index) stays within one record of the limit
        assert r.index_offsets[-1] <= 4000
    assert got == sent


def test_stage_change_and_request_start_new_files(tmp_path: Path) -> None:
    rec = SessionRecorder(tmp_path)
    rec.stage("NORMAL_FIRST_HALF_PRE")
    rec.record(1, 4, b"a")
    rec.stage("NORMAL_FIRST_HALF_PRE")  # no change
    rec.record(2, 4, b"b")
    rec.stage("NORMAL_FIRST_HALF")
    rec.record(3, 4, b"c")
    rec.new_file("operator")
    rec.record(4, 4, b"d")
    rec.close()
    files = logs(tmp_path)
    contents = [read(f)[0] for f in files]
    assert [payloads(c) for c in contents] == [
        [(1, 4, b"a"), (2, 4, b"b")], [(3, 4, b"c")], [(4, 4, b"d")]]
    reasons = [json.loads(c[0].payload)["reason"] for c in contents]
    assert reasons == ["start", "stage NORMAL_FIRST_HALF", "operator"]
    assert all(read(f)[1].index_offsets is not None for f in files)


def test_a_flipping_stage_does_not_make_a_file_per_flip(tmp_path: Path) -> None:
    """A referee whose stage flips (spoofed, broken) starts one new file, not one per flip;
    a stage change 10 s after the last rotation starts the next."""
    now = [100.0]
    rec = SessionRecorder(tmp_path, clock=lambda: now[0])
    rec.stage("NORMAL_FIRST_HALF")
    for i in range(20):
        now[0] += 0.05
        rec.stage("NORMAL_HALF_TIME" if i % 2 == 0 else "NORMAL_FIRST_HALF")
        rec.record(i + 1, 4, b"x")
    now[0] += 10.0
    rec.stage("NORMAL_SECOND_HALF")
    rec.record(99, 4, b"y")
    rec.close()
    assert len(logs(tmp_path)) == 3  # the start, the first flip, the second half


def test_no_stage_rotation_when_off(tmp_path: Path) -> None:
    rec = SessionRecorder(tmp_path, rotate_on_stage=False)
    rec.stage("A")
    rec.record(1, 4, b"a")
    rec.stage("B")
    rec.record(2, 4, b"b")
    rec.close()
    assert len(logs(tmp_path)) == 1


def test_disable_finishes_enable_starts_a_new_file_folder_moves(tmp_path: Path) -> None:
    rec = SessionRecorder(tmp_path / "a")
    rec.record(1, 4, b"a")
    rec.set_enabled(False)
    rec.record(2, 4, b"lost")
    wait_until(lambda: rec.status()["files"] == 1 and not rec.status()["recording"],
               DEADLINE_S, 0.01, "the file to be finished")
    [first] = logs(tmp_path / "a")
    assert read(first)[1].index_offsets is not None  # finished while the recorder runs on
    rec.set_enabled(True)
    rec.record(3, 4, b"c")
    rec.set_folder(tmp_path / "b")
    rec.record(4, 4, b"d")
    rec.close()
    assert [payloads(read(f)[0]) for f in logs(tmp_path / "a")] == [[(1, 4, b"a")], [(3, 4, b"c")]]
    assert [payloads(read(f)[0]) for f in logs(tmp_path / "b")] == [[(4, 4, b"d")]]
    assert rec.status()["not_recorded"] == 1


def test_disabled_from_the_start_writes_nothing(tmp_path: Path) -> None:
    rec = SessionRecorder(tmp_path / "logs", enabled=False)
    rec.record(1, 4, b"a")
    rec.stage("A")
    rec.stage("B")
    rec.close()
    assert not (tmp_path / "logs").exists() or logs(tmp_path / "logs") == []
    assert rec.status()["enabled"] is False and rec.status()["not_recorded"] == 1


def test_flushed_within_a_second_and_readable_while_open(tmp_path: Path) -> None:
    rec = SessionRecorder(tmp_path)
    wait_until(lambda: rec.status()["recording"], DEADLINE_S, 0.01, "the first file")
    [path] = logs(tmp_path)
    empty = path.stat().st_size
    t0 = time.monotonic()
    for i in range(10):
        rec.record(i, 4, b"y" * 50)
    wait_until(lambda: path.stat().st_size >= empty + 10 * 66, DEADLINE_S, 0.01,
               "the records on disk")
    assert time.monotonic() - t0 < 1.0 + 0.5  # flush interval 0.5 s, with slack for a busy CI
    records, r = read(path)  # a second reader, while the recorder is still open
    assert [x.time_ns for x in records if x.type == 4] == list(range(10))
    assert r.index_offsets is None and r.warning is None
    st = rec.status()
    assert st["recording"] and st["file"] == path.name and st["records"] == 11
    assert st["size_bytes"] == path.stat().st_size and st["duration_s"] >= 0
    rec.close()


def test_disk_full_stops_recording_and_the_station_goes_on(
        tmp_path: Path, caplog: pytest.LogCaptureFixture) -> None:
    def full(_path: str) -> BinaryIO:
        return open("/dev/full", "wb", buffering=0)  # the kernel answers ENOSPC

    rec = SessionRecorder(tmp_path, opener=full)
    wait_until(lambda: rec.status()["error"] is not None, DEADLINE_S, 0.01, "the error")
    st = rec.status()
    assert st["error"].startswith("disk full:") and st["error"].endswith("recording stopped")
    assert st["recording"] is False
    for i in range(100):
        rec.record(i, 4, b"z")  # no exception
    assert rec.status()["not_recorded"] == 100
    rec.close()
    assert sum("disk full" in m for m in caplog.messages) == 1  # logged once


def test_disk_full_while_writing(tmp_path: Path) -> None:
    """A disk that fills after some records: what was written stays readable."""
    class Filling(io.FileIO):
        def __init__(self, path: str) -> None:
            super().__init__(path, "xb")
            self.left = 200

        def write(self, b: object) -> int:
            n = len(b)  # type: ignore[arg-type]
            if n > self.left:
                raise OSError(28, "No space left on device")
            self.left -= n
            return super().write(b)  # type: ignore[arg-type]

    rec = SessionRecorder(tmp_path, opener=lambda p: Filling(p))  # type: ignore[arg-type,return-value]
    for i in range(50):
        rec.record(i, 4, b"w" * 20)
    wait_until(lambda: rec.status()["error"] is not None, DEADLINE_S, 0.01, "the error")
    rec.close()
    [path] = logs(tmp_path)
    records, _ = read(path)  # what did get written is readable, without an index
    assert 0 < len(records) < 51


def test_queue_full_drops_and_counts(tmp_path: Path) -> None:
    gate = threading.Event()

    class Stuck(io.FileIO):
        def write(self, b: object) -> int:
            gate.wait(DEADLINE_S)
            return super().write(b)  # type: ignore[arg-type]

    rec = SessionRecorder(tmp_path, queue_size=100,
                          opener=lambda p: Stuck(p, "xb"))  # type: ignore[arg-type,return-value]
    t0 = time.monotonic()
    for i in range(300):
        rec.record(i, 4, b"q")
    assert time.monotonic() - t0 < 0.5  # the caller was not held up by the stuck disk
    st = rec.status()
    assert st["dropped"] >= 200 - 1 and st["queued"] <= 101
    gate.set()
    rec.close()
    [path] = logs(tmp_path)
    kept = [x.time_ns for x in read(path)[0] if x.type == 4]
    assert kept == list(range(len(kept))) and len(kept) + rec.dropped == 300


def test_times_never_go_back_and_bad_records_are_skipped(tmp_path: Path) -> None:
    rec = SessionRecorder(tmp_path, max_bytes=1)  # every record in its own file
    rec.record(10, 4, b"a")
    rec.record(11, 4, "not bytes")  # type: ignore[arg-type]
    rec.record(1 << 70, 4, b"x")
    rec.record(12, 1 << 40, b"x")
    rec.record(13, 3, b"b")
    rec.close()
    contents = [read(f)[0] for f in logs(tmp_path)]
    assert [[(x.time_ns, x.type) for x in c] for c in contents] == [
        [(10, TYPE_TL_SESSION), (10, 4)], [(13, TYPE_TL_SESSION), (13, 3)]]
    assert rec.status()["bad"] == 3


def test_an_empty_file_still_has_its_session_record(tmp_path: Path) -> None:
    rec = SessionRecorder(tmp_path)
    rec.close()
    [path] = logs(tmp_path)
    records, r = read(path)
    assert [x.type for x in records] == [TYPE_TL_SESSION] and r.index_offsets == [16]


def test_new_folder_while_disabled_opens_nothing(tmp_path: Path) -> None:
    rec = SessionRecorder(tmp_path / "a", enabled=False)
    rec.set_folder(tmp_path / "b")
    rec.new_file("operator")
    rec.set_enabled(True)
    rec.record(1, 4, b"a")
    rec.close()
    assert not (tmp_path / "a").exists()
    assert [payloads(read(f)[0]) for f in logs(tmp_path / "b")] == [[(1, 4, b"a")]]


def test_an_unexpected_error_stops_recording_not_the_thread(tmp_path: Path) -> None:
    def broken(_path: str) -> BinaryIO:
        raise RuntimeError("a bug")

    rec = SessionRecorder(tmp_path, opener=broken)
    wait_until(lambda: rec.status()["error"] is not None, DEADLINE_S, 0.01, "the error")
    assert "RuntimeError: a bug" in rec.status()["error"]
    rec.new_file("again")  # tries again, fails again, still answers
    rec.close()
    assert not rec._thread.is_alive()
