"""Seeking by time in an indexed plain log: binary search over record headers."""

from __future__ import annotations

import os
import struct

from ssllog.format import INDEX_TRAILER, RECORD_HEADER, RECORD_HEADER_SIZE


def read_index(path: str) -> list[int] | None:
    """The record offsets of the type-6 index at the end of the file, or None."""
    size = os.path.getsize(path)
    if size < 16 + RECORD_HEADER_SIZE + 15:
        return None
    with open(path, "rb") as f:
        f.seek(size - 15)
        tail = f.read(15)
        if tail[8:] != INDEX_TRAILER:
            return None
        (back,) = struct.unpack(">q", tail[:8])
        start = size - back
        if back < RECORD_HEADER_SIZE + 15 or start < 16:
            return None
        f.seek(start + RECORD_HEADER_SIZE)
        n = (back - RECORD_HEADER_SIZE - 15) // 8
        return list(struct.unpack(f">{n}q", f.read(n * 8)))


def seek(path: str, offsets: list[int], time_ns: int) -> int | None:
    """Offset of the first record at or after time_ns (receive times non-decreasing)."""
    with open(path, "rb") as f:
        lo, hi = 0, len(offsets)
        while lo < hi:
            mid = (lo + hi) // 2
            f.seek(offsets[mid])
            t, _, _ = RECORD_HEADER.unpack(f.read(RECORD_HEADER_SIZE))
            if t < time_ns:
                lo = mid + 1
            else:
                hi = mid
    return offsets[lo] if lo < len(offsets) else None
