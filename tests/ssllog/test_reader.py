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
