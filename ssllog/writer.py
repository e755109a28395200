"""Writer: header, records, and on finish() the type-6 index record."""

from __future__ import annotations

import struct
import sys
import tempfile
import time
from array import array
from typing import BinaryIO

from ssllog.format import (
    INDEX_TRAILER,
    RECORD_HEADER,
    RECORD_HEADER_SIZE,
    TYPE_INDEX_2021,
    file_header,
)

#: offsets kept in memory before they go to the spill file (512 KiB)
SPILL_CHUNK = 65536


class LogWriter:
    """Appends records; flushes at least once per second of data (crash safety)."""

    def __init__(self, path: str, flush_interval_ns: int = 1_000_000_000,
                 *, file: BinaryIO | None = None) -> None:
        """``file``: an already open binary file to write into (tests use one that fails or
        blocks); without it ``path`` is created, never overwritten."""
        # kept open until finish(); "x" never overwrites
        self._f: BinaryIO = file if file is not None else open(path, "xb")  # noqa: SIM115
        self._f.write(file_header())
        self._offset = len(file_header())
        # every record's offset for the index at the end: 8 bytes each in an array, and
        # spilled to a temporary file a chunk at a time, so a long recording's memory stays
        # flat (a list of ints grew the backend by ~2 MB a minute at 8 cameras x 75 Hz)
        self._offsets = array("q")
        self._spill: BinaryIO | None = None
        self._flush_interval_ns = flush_interval_ns
        self._last_flush = time.monotonic_ns()

    def write(self, time_ns: int, rtype: int, payload: bytes) -> None:
        self._f.write(RECORD_HEADER.pack(time_ns, rtype, len(payload)))
        self._f.write(payload)
        self._offsets.append(self._offset)
        self._offset += RECORD_HEADER_SIZE + len(payload)
        if len(self._offsets) >= SPILL_CHUNK:
            self._spill_offsets()
        now = time.monotonic_ns()
        if now - self._last_flush >= self._flush_interval_ns:
            self.flush()

    def flush(self) -> None:
        self._f.flush()
        self._last_flush = time.monotonic_ns()

    def _spill_offsets(self) -> None:
        if self._spill is None:
            self._spill = tempfile.TemporaryFile(prefix="ssllog-index-")  # noqa: SIM115
        self._spill.write(self._offsets.tobytes())
        self._offsets = array("q")

    def _index_body(self) -> bytes:
        """Every record's offset, big-endian int64, in order."""
        offsets = array("q")
        if self._spill is not None:
            self._spill.seek(0)
            offsets.frombytes(self._spill.read())
            self._spill.close()
            self._spill = None
        offsets.extend(self._offsets)
        if sys.byteorder == "little":
            offsets.byteswap()
        return offsets.tobytes()

    def finish(self) -> None:
        """Writes the index record and closes the file."""
        body = self._index_body()
        size = len(body) + 8 + len(INDEX_TRAILER)
        # distance from the end of the file back to the start of the index record
        back = RECORD_HEADER_SIZE + size
        self._f.write(RECORD_HEADER.pack(0, TYPE_INDEX_2021, size))
        self._f.write(body + struct.pack(">q", back) + INDEX_TRAILER)
        self._f.close()

    def close_unfinished(self) -> None:
        """Closes the file without an index (after a write error: the file is read up to its
        last complete record)."""
        if self._spill is not None:
            self._spill.close()
            self._spill = None
        self._f.close()
