"""ZeroMQ sockets to the relay (connect side; the relay binds)."""

from __future__ import annotations

import zmq
import zmq.asyncio

#: how soon a socket retries its connection to a relay that went away (ms). libzmq's default
#: is 100 ms plus up to 100 ms of random jitter, which was most of the time a restarted
#: relay took, once bound, to be back in the backend's data (bench/restart_bench.py). A
#: refused connection on loopback costs microseconds, so a fixed short interval (no
#: exponential backoff: RECONNECT_IVL_MAX 0) is the cheap way to be back at once.
RECONNECT_IVL_MS = 10


def _reconnect_soon(sock: zmq.asyncio.Socket) -> None:
    sock.setsockopt(zmq.RECONNECT_IVL, RECONNECT_IVL_MS)
    sock.setsockopt(zmq.RECONNECT_IVL_MAX, 0)


def sub_socket(ctx: zmq.asyncio.Context, endpoint: str, topics: list[bytes]) -> zmq.asyncio.Socket:
    sock = ctx.socket(zmq.SUB)
    sock.setsockopt(zmq.LINGER, 0)
    sock.setsockopt(zmq.RCVHWM, 10000)
    _reconnect_soon(sock)
    for t in topics:
        sock.setsockopt(zmq.SUBSCRIBE, t)
    sock.connect(endpoint)
    return sock


def pub_socket(ctx: zmq.asyncio.Context, endpoint: str) -> zmq.asyncio.Socket:
    sock = ctx.socket(zmq.PUB)
    sock.setsockopt(zmq.LINGER, 0)
    sock.setsockopt(zmq.SNDHWM, 100)
    _reconnect_soon(sock)
    sock.connect(endpoint)
    return sock
