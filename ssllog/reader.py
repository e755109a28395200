"""Streaming reader: bounded memory, never writes into the file."""

from __future__ import annotations

import gzip
from collections import Counter
from collections.abc import Iterator
from dataclasses import dataclass
from typing import BinaryIO

from ssllog.format import (
    FILE_HEADER,
    HEADER_MAGIC,
    HEADER_SIZE,
    KNOWN_TYPES,
    MAX_PAYLOAD,
    RECORD_HEADER,
    RECORD_HEADER_SIZE,
    TOUCHLINE_TYPES,
    TYPE_INDEX_2021,
)


class LogFormatError(ValueError):
    """A corrupt file; `offset` is the byte offset of the bad header or record."""

    def __init__(self, offset: int, reason: str) -> None:
        super().__init__(f"corrupt SSL log at byte {offset}: {reason}")
        self.offset = offset


@dataclass(frozen=True, slots=True)
class Record:
    offset: int
    time_ns: int
    type: int
    payload: bytes


def open_log(path: str) -> BinaryIO:
    if path.endswith("gz"):
        return gzip.open(path, "rb")  # type: ignore[return-value]
    return open(path, "rb")


class LogReader:
    """Iterates the records of one log; `warning` tells of a truncated tail."""

    def __init__(self, path: str) -> None:
        self.path = path
        self.warning: str | None = None
        self.unknown_types: Counter[int] = Counter()
        self.index_offsets: list[int] | None = None

    def __iter__(self) -> Iterator[Record]:
        with open_log(self.path) as f:
            yield from self._records(f)

    def _read(self, f: BinaryIO, n: int) -> bytes:
        """``f.read(n)``; a gzip stream cut short (the league's recorder killed before it closed
        its file) ends the reading with a warning instead of an error."""
        try:
            return f.read(n)
        except EOFError:
            self.warning = "the compressed stream ends early (a recording that was killed?)"
            return b""

    def _records(self, f: BinaryIO) -> Iterator[Record]:
        head = self._read(f, HEADER_SIZE)
        if len(head) < HEADER_SIZE:
            raise LogFormatError(0, "file shorter than the 16-byte header")
        magic, version = FILE_HEADER.unpack(head)
        if magic != HEADER_MAGIC:
            raise LogFormatError(0, f"bad magic {magic!r}")
        if version != 1:
            raise LogFormatError(12, f"unsupported version {version}")
        offset = HEADER_SIZE
        while True:
            rh = self._read(f, RECORD_HEADER_SIZE)
            if not rh:
                return
            if len(rh) < RECORD_HEADER_SIZE:
                self.warning = self.warning or f"truncated record header at byte {offset}"
                return
            time_ns, rtype, size = RECORD_HEADER.unpack(rh)
            if size < 0 or size > MAX_PAYLOAD:
                raise LogFormatError(offset, f"payload size {size}")
            payload = self._read(f, size)
            if len(payload) < size:
                self.warning = self.warning or (
                    f"truncated record at byte {offset}: {len(payload)} of {size} bytes"
                )
                return
            if rtype == TYPE_INDEX_2021:
                self.index_offsets = _parse_index(payload, offset)
            elif rtype not in KNOWN_TYPES and rtype not in TOUCHLINE_TYPES:
                self.unknown_types[rtype] += 1
            else:
                yield Record(offset, time_ns, rtype, payload)
            offset += RECORD_HEADER_SIZE + size


def _parse_index(payload: bytes, offset: int) -> list[int]:
    if len(payload) < 15 or payload[-7:] != b"INDEXED" or (len(payload) - 15) % 8:
        raise LogFormatError(offset, "malformed index record")
    n = (len(payload) - 15) // 8
    import struct

    return list(struct.unpack(f">{n}q", payload[: n * 8]))
