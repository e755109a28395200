"""The writer's index of a long recording: offsets spilled to a temporary file in chunks come
back in order in the type-6 index (memory stays flat while recording)."""

from __future__ import annotations

from pathlib import Path

import pytest

import ssllog.writer as writer_mod
from ssllog.reader import LogReader
from ssllog.writer import LogWriter


def test_spilled_offsets_make_the_same_index(tmp_path: Path,
                                             monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(writer_mod, "SPILL_CHUNK", 7)  # several spills and a partial chunk
    path = tmp_path / "a.log"
    w = LogWriter(str(path))
    for i in range(40):
        w.write(1_000_000 * i, 4, bytes([i % 256]) * (i % 5 + 1))
    assert w._spill is not None  # it did spill
    w.finish()
    r = LogReader(str(path))
    records = list(r)
    assert [rec.time_ns for rec in records] == [1_000_000 * i for i in range(40)]
    # the index lists every record's offset, in order, across the spilled chunks
    assert r.index_offsets == [rec.offset for rec in records]


def test_an_unfinished_file_drops_its_spill(tmp_path: Path,
                                             monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(writer_mod, "SPILL_CHUNK", 3)
    w = LogWriter(str(tmp_path / "b.log"))
    for i in range(10):
        w.write(i, 4, b"x")
    spill = w._spill
    assert spill is not None
    w.close_unfinished()
    assert spill.closed and w._spill is None
