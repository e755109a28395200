"""ZeroMQ sockets to the relay (connect side; the relay binds)."""

from __future__ import annotations

import zmq
import zmq.asyncio


def sub_socket(ctx: zmq.asyncio.Context, endpoint: str, topics: list[bytes]) -> zmq.asyncio.Socket:
    sock = ctx.socket(zmq.SUB)
    sock.setsockopt(zmq.LINGER, 0)
    sock.setsockopt(zmq.RCVHWM, 10000)
    for t in topics:
        sock.setsockopt(zmq.SUBSCRIBE, t)
    sock.connect(endpoint)
    return sock


def pub_socket(ctx: zmq.asyncio.Context, endpoint: str) -> zmq.asyncio.Socket:
    sock = ctx.socket(zmq.PUB)
    sock.setsockopt(zmq.LINGER, 0)
    sock.setsockopt(zmq.SNDHWM, 100)
    sock.connect(endpoint)
    return sock
