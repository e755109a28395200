import struct
from pathlib import Path

import pytest

from ssllog.reader import LogFormatError, LogReader

HEAD = b"SSL_LOG_FILE" + struct.pack(">i", 1)


def rec(t: int, typ: int, payload: bytes) -> bytes:
    return struct.pack(">qii", t, typ, len(payload)) + payload


def test_reads_hand_built_records(tmp_path: Path) -> None:
    p = tmp_path / "a.log"
    p.write_bytes(HEAD + rec(5, 4, b"abc") + rec(7, 3, b"") + rec(9, 42, b"zz"))
    r = LogReader(str(p))
    got = [(x.offset, x.time_ns, x.type, x.payload) for x in r]
    assert got == [(16, 5, 4, b"abc"), (35, 7, 3, b"")]
    assert r.unknown_types == {42: 1}
    assert r.warning is None


def test_truncated_tail_is_a_warning(tmp_path: Path) -> None:
    p = tmp_path / "a.log"
    p.write_bytes(HEAD + rec(5, 4, b"abc") + rec(6, 4, b"abcdef")[:-2])
    r = LogReader(str(p))
    assert [x.time_ns for x in r] == [5]
    assert r.warning is not None and "35" in r.warning


def test_corrupt_size_names_offset(tmp_path: Path) -> None:
    p = tmp_path / "a.log"
    p.write_bytes(HEAD + rec(5, 4, b"abc") + struct.pack(">qii", 6, 4, -1))
    with pytest.raises(LogFormatError) as e:
        list(LogReader(str(p)))
    assert e.value.offset == 35


def test_a_gzip_stream_cut_short_is_a_warning(tmp_path: Path) -> None:
    """The league's recorder killed with SIGTERM leaves a .log.gz without its end (seen with
    ssl-log-recorder: ssl-log-stats then fails with "unexpected EOF"): the records before the
    cut are read, the rest is a warning, not an error."""
    import gzip
    import os

    records = [rec(i, 4, os.urandom(200)) for i in range(50)]  # random: gzip cannot shrink it
    whole = gzip.compress(HEAD + b"".join(records))
    p = tmp_path / "killed.log.gz"
    p.write_bytes(whole[: len(whole) * 3 // 4])
    r = LogReader(str(p))
    got = [x.time_ns for x in r]
    assert 0 < len(got) < 50 and got == list(range(len(got)))
    assert r.warning is not None and "compressed stream ends early" in r.warning


def test_touchline_types_are_read(tmp_path: Path) -> None:
    p = tmp_path / "a.log"
    p.write_bytes(HEAD + rec(1, 1005, b"{}") + rec(2, 1001, b"\x0a\x00")
                  + rec(3, 1006, b'{"name": "p", "values": {}}') + rec(4, 1007, b""))
    r = LogReader(str(p))
    assert [(x.time_ns, x.type) for x in r] == [(1, 1005), (2, 1001), (3, 1006)]
    assert r.unknown_types == {1007: 1}
