"""Fixtures for the relay tests: a relay in-process on random ports, UDP stand-ins, helpers."""

from __future__ import annotations

import asyncio
import contextlib
import dataclasses
import math
import socket
import time
from collections.abc import AsyncIterator, Callable
from typing import Any

import zmq
import zmq.asyncio

from larcmacs_relay import Relay, RelayConfig
from larcmacs_relay.codecs import Command
from sslnet.kerneltime import enable_kernel_timestamps, kernel_time
from sslnet.multicast import open_multicast_sender
from tests.ports import free_udp_port, random_multicast_port

STARTUP_TIMEOUT_S = 5.0


def udp_server() -> socket.socket:
    """A UDP socket standing in for a simulator / robot box; the kernel stamps arrivals."""
    s = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    s.bind(("127.0.0.1", 0))
    enable_kernel_timestamps(s)
    s.setblocking(False)
    return s


async def recv_udp(sock: socket.socket, timeout: float = 2.0) -> tuple[bytes, float]:
    """One datagram and its arrival time (kernel timestamp, Unix seconds, ``time.time()``
    clock), so that a busy test event loop does not distort measured timing."""
    data, t, _ = await recv_udp_from(sock, timeout)
    return data, t


def _wake(fut: asyncio.Future[None]) -> None:
    if not fut.done():
        fut.set_result(None)


async def recv_udp_from(
    sock: socket.socket, timeout: float = 2.0
) -> tuple[bytes, float, tuple[str, int]]:
    loop = asyncio.get_running_loop()
    deadline = loop.time() + timeout
    while True:
        try:
            data, anc, _, addr = sock.recvmsg(65536, 64)
        except BlockingIOError:
            remaining = deadline - loop.time()
            if remaining <= 0:
                raise TimeoutError from None
            fut: asyncio.Future[None] = loop.create_future()
            loop.add_reader(sock.fileno(), _wake, fut)
            try:
                await asyncio.wait_for(fut, remaining)
            finally:
                loop.remove_reader(sock.fileno())
            continue
        stamp = kernel_time(anc)
        return data, time.time() if stamp is None else stamp, addr


def drain_udp(sock: socket.socket) -> int:
    n = 0
    while True:
        try:
            sock.recv(65536)
        except BlockingIOError:
            return n
        n += 1


@dataclasses.dataclass
class Harness:
    relay: Relay
    config: RelayConfig
    ctx: zmq.asyncio.Context
    sim_blue: socket.socket
    sim_yellow: socket.socket
    sim_control: socket.socket
    out_box: socket.socket
    sender: socket.socket

    def send_vision(self, data: bytes) -> None:
        self.sender.sendto(data, (self.config.vision_group, self.config.vision_port))

    def send_referee(self, data: bytes) -> None:
        self.sender.sendto(data, (self.config.referee_group, self.config.referee_port))

    def subscriber(self, *topics: bytes, endpoint: str | None = None) -> zmq.asyncio.Socket:
        s = self.ctx.socket(zmq.SUB)
        s.setsockopt(zmq.LINGER, 0)
        for t in topics or (b"",):
            s.setsockopt(zmq.SUBSCRIBE, t)
        s.connect(endpoint or self.relay.pub_address)
        return s

    def publisher(self) -> zmq.asyncio.Socket:
        s = self.ctx.socket(zmq.PUB)
        s.setsockopt(zmq.LINGER, 0)
        s.connect(self.relay.sub_address)
        return s


class CycleLog:
    """Every output cycle the relay runs, by its own clock: (the cycle's ``now``, the commands
    it sent). Checks of "nothing happened" or "only zeros went out until T" read this instead
    of sleeping and hoping the loop ran meanwhile."""

    def __init__(self, relay: Relay) -> None:
        self.cycles: list[tuple[float, list[Command]]] = []
        self._now = -math.inf
        cycle, send = relay.output_cycle, relay._send_commands

        def output_cycle(now: float) -> bool:
            self._now = now
            return cycle(now)

        def send_commands(due: list[Command], version: int | None = None) -> None:
            self.cycles.append((self._now, list(due)))
            send(due, version)

        relay.output_cycle = output_cycle  # type: ignore[method-assign]
        relay._send_commands = send_commands  # type: ignore[method-assign]

    def after(self, t: float) -> list[tuple[float, list[Command]]]:
        return [c for c in self.cycles if c[0] > t]


@contextlib.asynccontextmanager
async def running_relay(**overrides: Any) -> AsyncIterator[Harness]:
    sim_blue, sim_yellow, sim_control, out_box = (
        udp_server(),
        udp_server(),
        udp_server(),
        udp_server(),
    )
    port_of: Callable[[socket.socket], int] = lambda s: s.getsockname()[1]  # noqa: E731
    base = RelayConfig(
        vision_port=random_multicast_port(),
        referee_port=random_multicast_port(),
        tracker_out_port=random_multicast_port(),  # never the league's 10010 in a test
        pub_endpoint="tcp://127.0.0.1:*",
        sub_endpoint="tcp://127.0.0.1:*",
        sim_blue_port=port_of(sim_blue),
        sim_yellow_port=port_of(sim_yellow),
        sim_control_port=port_of(sim_control),
        grsim_port=port_of(sim_blue),
        grsim_status_host="127.0.0.1",
        grsim_status_blue_port=0,
        grsim_status_yellow_port=0,
        robot_box_port=port_of(out_box),
        compat_vision_pub="tcp://127.0.0.1:*",
        compat_referee_pub="tcp://127.0.0.1:*",
        compat_commands=f"tcp://127.0.0.1:{free_udp_port()}",
        stats_interval_s=0.2,
    )
    cfg = dataclasses.replace(base, **overrides)
    relay = Relay(cfg)
    task = asyncio.create_task(relay.run())
    ctx = zmq.asyncio.Context()
    sender = open_multicast_sender("127.0.0.1")
    try:
        await asyncio.wait_for(relay.ready.wait(), STARTUP_TIMEOUT_S)
        yield Harness(relay, cfg, ctx, sim_blue, sim_yellow, sim_control, out_box, sender)
    finally:
        relay.stop()
        await asyncio.wait_for(task, 5.0)
        ctx.destroy(linger=0)
        for s in (sim_blue, sim_yellow, sim_control, out_box, sender):
            s.close()


async def subscribed(
    sub: zmq.asyncio.Socket, probe: Callable[[], None], timeout: float = 3.0
) -> list[bytes]:
    """Work around the ZeroMQ slow-joiner: call ``probe`` until ``sub`` receives something.

    Returns the first message received."""
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        probe()
        if await sub.poll(50):
            return list(await sub.recv_multipart())
    raise AssertionError("subscriber never received anything")
