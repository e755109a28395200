"""Kernel receive timestamps of UDP datagrams (Linux SO_TIMESTAMPNS): when a datagram reached
the socket, not when Python got round to reading it. Used to measure latencies honestly."""

from __future__ import annotations

import socket
import struct
from typing import Any

SO_TIMESTAMPNS: int = getattr(socket, "SO_TIMESTAMPNS", 35)  # Linux value, not always exported
_TIMESPEC = struct.Struct("qq")


def enable_kernel_timestamps(sock: socket.socket) -> None:
    """Ask the kernel to stamp every datagram (read them with ``recvmsg(n, 64)``)."""
    sock.setsockopt(socket.SOL_SOCKET, SO_TIMESTAMPNS, 1)


def _stamp(ancdata: list[tuple[int, int, Any]]) -> tuple[int, int] | None:
    for level, kind, payload in ancdata:
        if level == socket.SOL_SOCKET and kind == SO_TIMESTAMPNS and len(payload) >= 16:
            sec, nsec = _TIMESPEC.unpack_from(payload)
            return int(sec), int(nsec)
    return None


def kernel_time(ancdata: list[tuple[int, int, Any]]) -> float | None:
    """The arrival time (s, Unix) in ``recvmsg``'s ancillary data, or None without a stamp."""
    stamp = _stamp(ancdata)
    return None if stamp is None else float(stamp[0] + stamp[1] * 1e-9)


def kernel_time_ns(ancdata: list[tuple[int, int, Any]]) -> int | None:
    """The arrival time (ns since the Unix epoch, as ``time.time_ns()``), or None."""
    stamp = _stamp(ancdata)
    return None if stamp is None else stamp[0] * 1_000_000_000 + stamp[1]
