"""asyncio I/O around the pure cores: command sockets, the real-time loop, vision multicast.

Use in-process::

    sim = FieldSim(SimConfig(vision_port=23456, control_port=0, blue_port=0, ...))
    await sim.start()          # sockets bound; sim.ports has the actual ports
    ...                        # sim.world is the live World (same event loop only)
    await sim.stop()

or from synchronous code / another thread: ``with FieldSimThread(config) as sim: ...``.
"""

from __future__ import annotations

import asyncio
import contextlib
import json
import logging
import socket
import time
from collections.abc import Callable
from typing import Any, TypeVar, cast

from anyio.from_thread import BlockingPortal, start_blocking_portal

from fieldsim.config import SimConfig
from fieldsim.protocol import CommandHandler
from fieldsim.vision import Vision
from fieldsim.world import Team, World
from sslnet.multicast import open_multicast_sender, open_udp_server
from sslnet.rate import RateCounter
from sslnet.ratelog import RateLimitedLog

log = logging.getLogger(__name__)

T = TypeVar("T")


class _Datagrams(asyncio.DatagramProtocol):
    """Calls ``handle(data) -> reply | None`` per datagram and sends the reply to the sender."""

    def __init__(
        self,
        name: str,
        handle: Callable[[bytes], bytes | None],
        sim: FieldSim,
        sock: socket.socket,
    ) -> None:
        self.name = name
        self.sock = sock
        self.last_addr: tuple[str, int] | None = None  # the sender of the datagram handled
        self.handle = handle
        self.sim = sim
        self.transport: asyncio.DatagramTransport | None = None

    def connection_made(self, transport: asyncio.BaseTransport) -> None:
        self.transport = cast(asyncio.DatagramTransport, transport)

    def datagram_received(self, data: bytes, addr: tuple[str | Any, int]) -> None:
        self.last_addr = (str(addr[0]), int(addr[1]))
        try:
            reply = self.handle(data)
        except Exception:  # a bug must not take the simulator down
            self.sim.internal_errors += 1
            log.exception("error handling a %s datagram", self.name)
            return
        if reply is not None and self.transport is not None and not self.transport.is_closing():
            # the raw socket, not transport.sendto: asyncio silently drops empty datagrams, and
            # an empty RobotControlResponse / SimulatorResponse (no errors) is a valid reply
            try:
                self.sock.sendto(reply, addr)
            except OSError as exc:
                self.sim.ratelog.warning(f"reply-{self.name}", "cannot reply on %s: %s",
                                         self.name, exc)

    def error_received(self, exc: Exception) -> None:
        self.sim.ratelog.warning(f"socket-{self.name}", "socket error on %s: %s", self.name, exc)


class FieldSim:
    """One simulator: world + vision + command servers, kept in real time by an asyncio task."""

    def __init__(
        self,
        config: SimConfig,
        *,
        clock: Callable[[], float] = time.monotonic,
        wallclock: Callable[[], float] = time.time,
    ) -> None:
        config.validate()
        self.config = config
        self.world = World(config)
        self.vision = Vision(config, self.world.geometry)
        self.ratelog = RateLimitedLog(log)
        self.handler = CommandHandler(self.world, self.ratelog)
        self.ports: dict[str, int] = {}
        self.frames_sent = [0] * len(self.vision.cameras)
        self.frame_rates = [RateCounter(window_s=2.0) for _ in self.vision.cameras]
        self.geometry_sent = 0
        self.truth_sent = 0
        self.send_errors = 0
        self.internal_errors = 0
        self.lag_resets = 0  # times the loop fell too far behind and skipped simulated time
        self._clock = clock
        self._wallclock = wallclock
        self._transports: list[asyncio.DatagramTransport] = []
        self._grsim_proto: _Datagrams | None = None
        #: like grSim: Robots_Status goes to the IP of the last grSim command's sender per team
        self.grsim_peers: dict[Team, str] = {}
        self.grsim_status_sent = 0
        self._sender: socket.socket | None = None
        self._task: asyncio.Task[None] | None = None
        self._zmq_ctx: Any = None
        self._truth_sock: Any = None
        self._started = False

    # -- lifecycle -----------------------------------------------------------------------------

    async def start(self) -> None:
        """Bind every socket and start the real-time loop. Raises OSError if a port is taken."""
        if self._started:
            return
        cfg = self.config
        loop = asyncio.get_running_loop()
        try:
            self._sender = open_multicast_sender(cfg.interface, ttl=cfg.vision_ttl, loop=True)
            servers: list[tuple[str, int, Callable[[bytes], bytes | None]]] = [
                ("control", cfg.control_port, self.handler.simulator_command),
                ("blue", cfg.blue_port, lambda d: self.handler.robot_control(Team.BLUE, d)),
                ("yellow", cfg.yellow_port, lambda d: self.handler.robot_control(Team.YELLOW, d)),
                ("grsim", cfg.grsim_port, self._grsim),
            ]
            for name, port, handle in servers:
                sock = open_udp_server(cfg.sim_host, port)
                self.ports[name] = sock.getsockname()[1]
                transport, proto = await loop.create_datagram_endpoint(
                    lambda n=name, h=handle, s=sock: _Datagrams(n, h, self, s),  # type: ignore[misc]
                    sock=sock,
                )
                self._transports.append(transport)
                if name == "grsim":
                    self._grsim_proto = proto
            if cfg.truth_pub:
                self._open_truth(cfg.truth_pub)
        except BaseException:
            await self._close()
            raise
        self._started = True
        self._task = asyncio.create_task(self._run(), name="fieldsim-loop")
        log.info(
            "fieldsim: vision -> %s:%d via %s (%d cameras at %.0f Hz, geometry %.1f Hz); "
            "commands on %s: control %d, blue %d, yellow %d, grSim %d; truth %s",
            cfg.vision_group, cfg.vision_port, cfg.interface, len(self.vision.cameras),
            cfg.camera_hz, cfg.geometry_hz, cfg.sim_host, self.ports["control"],
            self.ports["blue"], self.ports["yellow"], self.ports["grsim"],
            cfg.truth_pub or "off",
        )

    def _grsim(self, data: bytes) -> None:
        team = self.handler.grsim_packet(data)
        proto = self._grsim_proto
        if team is not None and proto is not None and proto.last_addr is not None:
            self.grsim_peers[team] = proto.last_addr[0]

    def _send_grsim_status(self) -> None:
        """grSim's Robots_Status of each team commanded through grSim_Packet, on a change."""
        cfg = self.config
        for team, host in self.grsim_peers.items():
            data = self.handler.grsim_status(team)
            if data is None or self._sender is None:
                continue
            port = (cfg.grsim_status_blue_port if team is Team.BLUE
                    else cfg.grsim_status_yellow_port)
            try:
                self._sender.sendto(data, (host, port))
                self.grsim_status_sent += 1
            except OSError as exc:
                self.send_errors += 1
                self.ratelog.warning("grsim-status", "grSim status to %s:%d failed: %s",
                                     host, port, exc)

    def _open_truth(self, endpoint: str) -> None:
        import zmq

        self._zmq_ctx = zmq.Context()
        sock = self._zmq_ctx.socket(zmq.PUB)
        sock.setsockopt(zmq.LINGER, 0)
        sock.setsockopt(zmq.SNDHWM, 100)
        sock.bind(endpoint)
        self._truth_sock = sock

    async def stop(self) -> None:
        """Stop the loop and close every socket (idempotent)."""
        task, self._task = self._task, None
        if task is not None:
            task.cancel()
            with contextlib.suppress(asyncio.CancelledError):
                await task
        await self._close()
        self._started = False

    async def _close(self) -> None:
        for transport in self._transports:
            transport.close()
        self._transports.clear()
        if self._sender is not None:
            self._sender.close()
            self._sender = None
        if self._truth_sock is not None:
            self._truth_sock.close(linger=0)
            self._truth_sock = None
        if self._zmq_ctx is not None:
            self._zmq_ctx.term()
            self._zmq_ctx = None
        await asyncio.sleep(0)  # let transports finish closing

    @property
    def running(self) -> bool:
        return self._task is not None and not self._task.done()

    async def wait(self) -> None:
        """Return when the loop task ends (only on stop() or an internal failure)."""
        if self._task is not None:
            with contextlib.suppress(asyncio.CancelledError):
                await self._task

    async def __aenter__(self) -> FieldSim:
        await self.start()
        return self

    async def __aexit__(self, *exc: object) -> None:
        await self.stop()

    # -- status --------------------------------------------------------------------------------

    def status(self) -> dict[str, Any]:
        s = self.handler.stats
        return {
            "sim_time": self.world.t,
            "frames_sent": list(self.frames_sent),
            "frame_rate_hz": [round(r.rate_hz(), 1) for r in self.frame_rates],
            "geometry_sent": self.geometry_sent,
            "truth_sent": self.truth_sent,
            "datagrams": dict(s.datagrams),
            "malformed": dict(s.malformed),
            "errors": dict(s.errors),
            "send_errors": self.send_errors,
            "internal_errors": self.internal_errors,
            "lag_resets": self.lag_resets,
        }

    # -- real-time loop ------------------------------------------------------------------------

    def _send(self, payload: bytes) -> bool:
        assert self._sender is not None
        try:
            self._sender.sendto(payload, (self.config.vision_group, self.config.vision_port))
            return True
        except OSError as exc:  # includes BlockingIOError on a full buffer
            self.send_errors += 1
            self.ratelog.warning("vision-send", "vision send failed: %s", exc)
            return False

    async def _run(self) -> None:
        cfg = self.config
        world, vision = self.world, self.vision
        dt = world.dt
        period = 1.0 / cfg.camera_hz
        geom_period = 1.0 / cfg.geometry_hz
        start_mono = self._clock() - world.t
        start_unix = self._wallclock() - world.t
        next_capture = [world.t + ph for ph in vision.phases]
        next_geom = world.t
        next_truth = world.t
        geometry_bytes = vision.geometry_packet().SerializeToString()  # never changes
        try:
            while True:
                now = self._clock() - start_mono
                steps = 0
                while world.t + dt <= now + 1e-9:
                    if steps >= cfg.max_catch_up_steps:
                        # too far behind (machine stalled): skip simulated time, keep pace
                        skipped = now - world.t
                        start_mono += skipped
                        start_unix += skipped
                        now = world.t
                        # (the captures stay where they are in simulated time, which
                        # goes on where it was: each camera keeps its phase, the frames
                        # it missed are dropped below; moved to the skip's instant, all
                        # cameras captured together from then on)
                        next_geom = min(next_geom, now)
                        next_truth = min(next_truth, now)
                        self.lag_resets += 1
                        self.ratelog.warning("lag", "fieldsim fell %.3f s behind real time",
                                             skipped)
                        break
                    world.step()
                    steps += 1
                if steps and self.grsim_peers:
                    self._send_grsim_status()
                # the frames due now are all encoded, then sent back to back: cameras
                # triggered together arrive as one burst (as grSim's), not one per encoding
                due: list[tuple[int, bytes]] = []
                for k in range(len(next_capture)):
                    while next_capture[k] <= now:
                        tc = next_capture[k]
                        next_capture[k] += period
                        if next_capture[k] <= now:
                            continue  # a late frame is dropped, like a camera would
                        t_sent = start_unix + (self._clock() - start_mono)
                        packet = vision.detect(k, world, start_unix + tc, t_sent, tc - world.t)
                        due.append((k, packet.SerializeToString()))
                for k, data in due:
                    if self._send(data):
                        self.frames_sent[k] += 1
                        self.frame_rates[k].add()
                if now >= next_geom:
                    next_geom += geom_period * max(1, int((now - next_geom) / geom_period) + 1)
                    if self._send(geometry_bytes):
                        self.geometry_sent += 1
                if self._truth_sock is not None and now >= next_truth:
                    next_truth += period * max(1, int((now - next_truth) / period) + 1)
                    self._publish_truth(start_unix + world.t)
                wake = min(world.t + dt, min(next_capture, default=world.t + dt), next_geom)
                delay = wake - (self._clock() - start_mono)
                await asyncio.sleep(max(0.0, delay))
        except asyncio.CancelledError:
            raise
        except Exception:
            self.internal_errors += 1
            log.exception("fieldsim loop failed")
            raise

    def _publish_truth(self, t_unix: float) -> None:
        """``[b"truth", JSON of World.truth() + "t_unix"]``: state, last touch, ball in goal,
        stats and the last events (goal / ball_out / collision, dedupe by ``seq``)."""
        import zmq

        truth = self.world.truth()
        truth["t_unix"] = t_unix
        try:
            self._truth_sock.send_multipart(
                [b"truth", json.dumps(truth).encode()], flags=zmq.NOBLOCK
            )
            self.truth_sent += 1
        except zmq.Again:
            pass


class FieldSimThread:
    """Runs a FieldSim on its own event loop in a daemon thread (for synchronous callers), via
    anyio's blocking portal (the loop-in-a-thread bridge).

    ``start()`` returns once every socket is bound (``ports`` filled) or raises what start
    raised; ``call(fn)`` runs ``fn(sim)`` on the simulator's loop and returns its result.
    """

    def __init__(self, config: SimConfig) -> None:
        self.config = config
        self.sim: FieldSim | None = None
        self._portal_cm: contextlib.AbstractContextManager[BlockingPortal] | None = None
        self._portal: BlockingPortal | None = None

    @property
    def ports(self) -> dict[str, int]:
        return dict(self.sim.ports) if self.sim is not None else {}

    def start(self, timeout: float = 10.0) -> None:
        self._portal_cm = start_blocking_portal("asyncio")
        self._portal = self._portal_cm.__enter__()
        sim = FieldSim(self.config)
        try:
            self._portal.start_task_soon(sim.start).result(timeout)
        except BaseException:
            self._close_portal()
            raise
        self.sim = sim

    def call(self, fn: Callable[[FieldSim], T], timeout: float = 5.0) -> T:
        assert self._portal is not None and self.sim is not None
        return self._portal.start_task_soon(fn, self.sim).result(timeout)

    def stop(self, timeout: float = 10.0) -> None:
        if self._portal is not None and self.sim is not None:
            with contextlib.suppress(Exception):  # stopping what may be half started
                self._portal.start_task_soon(self.sim.stop).result(timeout)
        self.sim = None
        self._close_portal()

    def _close_portal(self) -> None:
        cm, self._portal_cm, self._portal = self._portal_cm, None, None
        if cm is not None:
            cm.__exit__(None, None, None)

    def __enter__(self) -> FieldSimThread:
        self.start()
        return self

    def __exit__(self, *exc: object) -> None:
        self.stop()
