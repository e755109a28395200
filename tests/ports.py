"""Ports for tests and benchmarks that open real sockets on loopback (the relay's tests,
bench/relay_digest.py, bench/relay_bench.py)."""

from __future__ import annotations

import random
import socket


def free_port(kind: int = socket.SOCK_DGRAM) -> int:
    """A port on 127.0.0.1 free right now (UDP; ``socket.SOCK_STREAM`` for TCP)."""
    s = socket.socket(socket.AF_INET, kind)
    s.bind(("127.0.0.1", 0))
    port: int = s.getsockname()[1]
    s.close()
    return port


def free_udp_port() -> int:
    return free_port(socket.SOCK_DGRAM)


def random_multicast_port() -> int:
    """A random port in 20000-40000 that is free for UDP on this host right now (a multicast
    group's port: bound on every address, so not one the kernel hands out for 127.0.0.1)."""
    for _ in range(50):
        port = random.randint(20000, 40000)
        s = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        try:
            s.bind(("0.0.0.0", port))
        except OSError:
            continue
        finally:
            s.close()
        return port
    raise RuntimeError("no free port found")
