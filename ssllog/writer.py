"""Writer: header, records, and on finish() the type-6 index record."""

from __future__ import annotations

import struct
import time
from typing import BinaryIO

from ssllog.format import (
    INDEX_TRAILER,
    RECORD_HEADER,
    RECORD_HEADER_SIZE,
    TYPE_INDEX_2021,
    file_header,
)


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
        self._offsets: list[int] = []
        self._flush_interval_ns = flush_interval_ns
        self._last_flush = time.monotonic_ns()

    def write(self, time_ns: int, rtype: int, payload: bytes) -> None:
        self._f.write(RECORD_HEADER.pack(time_ns, rtype, len(payload)))
        self._f.write(payload)
        self._offsets.append(self._offset)
        self._offset += RECORD_HEADER_SIZE + len(payload)
        now = time.monotonic_ns()
        if now - self._last_flush >= self._flush_interval_ns:
            self.flush()

    def flush(self) -> None:
        self._f.flush()
        self._last_flush = time.monotonic_ns()

    def finish(self) -> None:
        """Writes the index record and closes the file."""
        body = struct.pack(f">{len(self._offsets)}q", *self._offsets)
        size = len(body) + 8 + len(INDEX_TRAILER)
        # distance from the end of the file back to the start of the index record
        back = RECORD_HEADER_SIZE + size
        self._f.write(RECORD_HEADER.pack(0, TYPE_INDEX_2021, size))
        self._f.write(body + struct.pack(">q", back) + INDEX_TRAILER)
        self._f.close()

    def close_unfinished(self) -> None:
        """Closes the file without an index (after a write error: the file is read up to its
        last complete record)."""
        self._f.close()
