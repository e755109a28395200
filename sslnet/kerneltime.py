"""Kernel receive timestamps of UDP datagrams (Linux SO_TIMESTAMPNS): when a datagram reached
the socket, not when Python got round to reading it. Used to measure latencies honestly."""

from __future__ import annotations

import socket
import struct
from typing import Any

SO_TIMESTAMPNS: int = getattr(socket, "SO_TIMESTAMPNS", 35)  # Linux value, not always exported


def enable_kernel_timestamps(sock: socket.socket) -> None:
    """Ask the kernel to stamp every datagram (read them with ``recvmsg(n, 64)``)."""
    sock.setsockopt(socket.SOL_SOCKET, SO_TIMESTAMPNS, 1)


def kernel_time(ancdata: list[tuple[int, int, Any]]) -> float | None:
    """The arrival time (s, Unix) in ``recvmsg``'s ancillary data, or None without a stamp."""
    for level, kind, payload in ancdata:
        if level == socket.SOL_SOCKET and kind == SO_TIMESTAMPNS:
            sec, nsec = struct.unpack("qq", payload[:16])
            return float(sec + nsec * 1e-9)
    return None
