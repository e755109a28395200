import struct
from pathlib import Path

from ssllog.reader import LogReader
from ssllog.writer import LogWriter


def test_writer_bytes_match_the_format(tmp_path: Path) -> None:
    p = tmp_path / "w.log"
    w = LogWriter(str(p))
    w.write(5, 4, b"abc")
    w.write(7, 3, b"")
    w.finish()
    idx = struct.pack(">qqq", 16, 35, 16 + 8 * 3 + 7) + b"INDEXED"
    expected = (
        b"SSL_LOG_FILE" + struct.pack(">i", 1)
        + struct.pack(">qii", 5, 4, 3) + b"abc"
        + struct.pack(">qii", 7, 3, 0)
        + struct.pack(">qii", 0, 6, len(idx)) + idx
    )
    assert p.read_bytes() == expected
    r = LogReader(str(p))
    assert [x.time_ns for x in r] == [5, 7]
    assert r.index_offsets == [16, 35]


def test_unfinished_file_reads_up_to_last_flushed_record(tmp_path: Path) -> None:
    p = tmp_path / "w.log"
    w = LogWriter(str(p), flush_interval_ns=0)
    w.write(5, 4, b"abc")
    w.write(6, 4, b"defg")
    # no finish(): as if the station were killed now
    r = LogReader(str(p))
    assert [x.payload for x in r] == [b"abc", b"defg"]
    assert r.index_offsets is None and r.warning is None


def test_gzip_file_is_read(tmp_path: Path) -> None:
    import gzip

    p = tmp_path / "w.log"
    w = LogWriter(str(p))
    w.write(5, 4, b"abc")
    w.finish()
    gz = tmp_path / "w.log.gz"
    gz.write_bytes(gzip.compress(p.read_bytes()))
    r = LogReader(str(gz))
    assert [x.payload for x in r] == [b"abc"]
    assert r.index_offsets == [16]
