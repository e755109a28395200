from pathlib import Path

from ssllog.seek import read_index, seek
from ssllog.writer import LogWriter


def test_seek_in_indexed_file(tmp_path: Path) -> None:
    p = tmp_path / "s.log"
    w = LogWriter(str(p))
    for i in range(10):
        w.write(100 * i, 4, b"x" * i)
    w.finish()
    offs = read_index(str(p))
    assert offs is not None and len(offs) == 10 and offs[0] == 16
    assert seek(str(p), offs, 0) == 16
    assert seek(str(p), offs, 250) == offs[3]
    assert seek(str(p), offs, 300) == offs[3]
    assert seek(str(p), offs, 10_000) is None
