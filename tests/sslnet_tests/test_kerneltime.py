"""Kernel receive timestamps on a real loopback UDP socket."""

from __future__ import annotations

import select
import socket
import time

from sslnet.kerneltime import enable_kernel_timestamps, kernel_time


def test_a_stamped_datagram_carries_its_arrival_time_and_a_plain_one_none() -> None:
    rx = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    plain = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    tx = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    try:
        rx.bind(("127.0.0.1", 0))
        plain.bind(("127.0.0.1", 0))
        enable_kernel_timestamps(rx)
        before = time.time()
        tx.sendto(b"x", rx.getsockname())
        tx.sendto(b"y", plain.getsockname())
        assert select.select([rx], [], [], 2.0)[0], "nothing arrived"
        assert select.select([plain], [], [], 2.0)[0], "nothing arrived"
        data, anc, _, _ = rx.recvmsg(64, 64)
        after = time.time()
        stamp = kernel_time(anc)
        assert data == b"x" and stamp is not None
        assert before - 0.01 <= stamp <= after + 0.01
        _, anc2, _, _ = plain.recvmsg(64, 64)
        assert kernel_time(anc2) is None
    finally:
        for s in (rx, plain, tx):
            s.close()
