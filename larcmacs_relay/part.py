"""What the relay's parts share: the state more than one of them reads or writes (each with
the module that owns it), the few helpers they all use, and the calls one part makes into
another (declared here, made in the part named beside each).

The parts are the classes ``Relay`` (relay.py) is made of, one module each; they are one
object at run time, so a datagram's path through them costs what it cost in one class (no
call from one object to another on the hot path). Read this file as the table of contents of
what crosses from one part to another; every other name a part uses is its own.
"""

from __future__ import annotations

import asyncio
import socket
import time
from collections import deque

import zmq
import zmq.asyncio
from google.protobuf.message import DecodeError, Message

from larcmacs_relay.codecs import Command
from larcmacs_relay.commands import CommandTable
from larcmacs_relay.config import RelayConfig
from larcmacs_relay.feedback import SentLog
from sslnet import streams
from sslnet.rate import RateCounter
from sslnet.ratelog import RateLimitedLog
from sslnet.streams import StreamCounter
from sslpb import ssl_simulation_control_pb2, touchline_pb2

MAX_DATAGRAM = 65536
MAX_BATCH = 512
# ZeroMQ flags as plain ints: pyzmq's IntFlag arithmetic costs more than the send it flags
NOBLOCK = int(zmq.NOBLOCK)
#: the stock event loops' clock: time.monotonic itself (uvloop's is not)
_MONOTONIC_LOOP_TIME = asyncio.BaseEventLoop.time
#: one team's datagram of an output cycle: team, bytes, address, its robots' ids
Planned = tuple[int, bytes, tuple[str, int], tuple[int, ...]]


class Opened:
    """The sockets a run opens (relay.py closes them): ZeroMQ ones with LINGER 0, the UDP
    ones with their readers removed."""

    def __init__(self, ctx: zmq.asyncio.Context) -> None:
        self.ctx = ctx
        self.sync_ctx: zmq.Context[zmq.Socket[bytes]] = zmq.Context.shadow(ctx.underlying)
        self.zmq: list[zmq.Socket[bytes] | zmq.asyncio.Socket] = []
        self.udp: list[socket.socket] = []

    def zsock(self, kind: int) -> zmq.Socket[bytes]:
        """A plain (not asyncio) ZeroMQ socket."""
        s = self.sync_ctx.socket(kind)
        s.setsockopt(zmq.LINGER, 0)
        self.zmq.append(s)
        return s

    def asock(self, kind: int) -> zmq.asyncio.Socket:
        s = self.ctx.socket(kind)
        s.setsockopt(zmq.LINGER, 0)
        self.zmq.append(s)
        return s


def endpoint(sock: zmq.Socket[bytes] | zmq.asyncio.Socket) -> str:
    """The address a socket bound (a wildcard port resolved)."""
    value = sock.getsockopt(zmq.LAST_ENDPOINT)
    return value.decode() if isinstance(value, bytes) else str(value)


class RelayPart:
    """The shared state (set up by relay.py and the owners named) and the shared helpers."""

    config: RelayConfig
    #: every stream's counters by name (relay.py makes them; each part counts its own)
    streams: dict[str, StreamCounter]
    #: streams["output"]: every datagram a command or a simulator command is in
    _output: StreamCounter
    #: the latest command per robot (commands.py): command_input.py and compat_io.py write
    #: it, cycle.py reads what is due, safety.py zeroes it
    table: CommandTable
    _ratelog: RateLimitedLog
    #: the native PUB (relay.py binds it): envelopes, feedback, stats
    _pub: zmq.Socket[bytes] | None
    #: the one UDP socket every command leaves from (cycle.py opens it); the simulator's
    #: answers come back on it (answers.py)
    _udp_out: socket.socket | None
    #: the kernel stamps the simulator's answers' arrival (answers.py): then the output
    #: cycles read them (cycle.py), not the loop
    _stamped: bool
    #: "host:port" of each datagram source seen (bounded): one string, not one per datagram
    _sources: dict[tuple[str, int], str]
    #: the running loop once it is known to keep time.monotonic (the stock loops)
    _monotonic_loop: asyncio.AbstractEventLoop | None
    #: a message on the command SUB changed what is due: one output cycle after the batch
    _commands_changed: bool
    #: output cycles (cycle.py counts them, stats.py reports their rate)
    cycles: RateCounter
    #: the output hosts, resolved once when the output opens (cycle.py)
    _sim_host: str
    _box_host: str
    #: per team: commands sent to each robot and the wall clock (ns) of the last one
    #: (cycle.py writes it, answers.py forwards it with every answer)
    _sent: dict[int, SentLog]
    #: the e-stop latch and the arming (safety.py sets them; command_input.py, compat_io.py
    #: and cycle.py obey them; stats.py reports them)
    estop_latched: bool
    estop_by: str
    arming_required: bool
    armed: bool
    armed_by: str
    #: the seed's compat PUBs (compat_io.py), written by inputs.py
    _compat_vision: zmq.Socket[bytes] | None
    _compat_referee: zmq.Socket[bytes] | None
    #: uuids of the tracked vision sent (tracker_out.py), its echoes dropped by inputs.py
    _own_tracker_uuids: set[str]
    #: robot-box output: the only team it may drive (robot_box.py), checked by
    #: command_input.py
    _box_team: int | None
    #: command latencies: the sets' source times waiting for their cycle (command_input.py),
    #: then (time, ms) of the last second (cycle.py adds them, stats.py reports them)
    _pending_latency_ns: list[int]
    _latencies: deque[tuple[float, float]]

    # ------------------------------------------------------------------ shared helpers

    def _publish(self, sock: zmq.Socket[bytes] | None, frames: list[bytes]) -> None:
        if sock is None:
            return
        try:
            sock.send_multipart(frames, flags=NOBLOCK)
        except zmq.Again:
            self._ratelog.warning("pub-full", "ZeroMQ PUB queue full, message dropped")

    def _command_error(self, stream: str, reason: str, kind: str = "rejected") -> None:
        self.streams[stream].error(kind, reason)
        kind = " ".join(reason.split()[:3])  # bounded set of log keys, one per kind of error
        self._ratelog.warning(f"{stream}-bad:{kind}", "rejected %s: %s", stream, reason)

    def _parse(self, stream: str, msg: Message, body: bytes) -> bool:
        """``body`` into ``msg``; False, counted as an error of ``stream`` by its wire
        problem, when it does not parse."""
        try:
            msg.ParseFromString(body)
        except DecodeError as exc:
            self._command_error(stream, f"{msg.DESCRIPTOR.name} does not parse: {exc}",
                                streams.wire_problem(body))
            return False
        return True

    def _multicast(self, stream: str, sock: socket.socket, body: bytes,
                   group: tuple[str, int], failed: str = "rejected") -> None:
        """``body``, checked, to a multicast ``group``: counted in ``stream``, or its failure
        as an error of kind ``failed``."""
        try:
            sock.sendto(body, group)
        except OSError as exc:
            self._command_error(stream, f"send failed: {exc}", failed)
            return
        self.streams[stream].packet(len(body))

    def _send(self, data: bytes, addr: tuple[str, int]) -> bool:
        if self._udp_out is None:
            return False
        try:
            self._udp_out.sendto(data, addr)
        except OSError as exc:
            self._send_failed(addr, exc)
            return False
        self._output.packet(len(data))
        return True

    def _send_failed(self, addr: tuple[str, int], exc: OSError) -> None:
        self._output.error("send failed", f"to {addr[0]}:{addr[1]}: {exc}")
        self._ratelog.warning("output-send", "send to %s:%d failed: %s", *addr, exc)

    def _source(self, addr: tuple[str, int]) -> str:
        """"ip:port" of a datagram's sender, made once per sender (at most 256 kept)."""
        source = self._sources.get(addr)
        if source is None:
            source = f"{addr[0]}:{addr[1]}"
            if len(self._sources) < 256:  # a spoofing flood cannot grow it
                self._sources[addr] = source
        return source

    def _loop_time(self, t: float) -> float:
        """Monotonic ``t`` on the loop's clock (asyncio's is time.monotonic, uvloop's not)."""
        loop = asyncio.get_running_loop()
        if loop is self._monotonic_loop:
            return t
        if type(loop).time is _MONOTONIC_LOOP_TIME:  # the stock loops: t itself, from now on
            self._monotonic_loop = loop
            return t
        return loop.time() + (t - time.monotonic())

    # ------------------------------------------------------------------ calls between parts

    def _kick_output(self) -> None:
        """cycle.py: new commands (or a stop): a cycle now or at the least gap."""
        raise NotImplementedError

    def _send_commands(self, due: list[Command], version: int | None = None) -> None:
        """cycle.py: ``due`` encoded and sent on the configured output."""
        raise NotImplementedError

    def _sim_plan(self, due: list[Command]) -> list[Planned]:
        """sim_protocol.py: each team's RobotControl datagram of ``due``."""
        raise NotImplementedError

    def _grsim_plan(self, due: list[Command]) -> list[Planned]:
        """grsim.py: each team's grSim_Packet of ``due``."""
        raise NotImplementedError

    def _send_robot_box(self, due: list[Command]) -> None:
        """robot_box.py: each robot's datagram of ``due`` to the robot box."""
        raise NotImplementedError

    def _send_grsim_replacement(self, cmd: ssl_simulation_control_pb2.SimulatorCommand) -> None:
        """grsim.py: a SimulatorCommand's teleports as a grSim replacement."""
        raise NotImplementedError

    def stats(self, now: float | None = None) -> touchline_pb2.RelayStats:
        """stats.py: the statistics as published."""
        raise NotImplementedError

    def _drain_responses(self, sock: socket.socket) -> None:
        """answers.py: the simulator's answers waiting on ``sock``, read and forwarded."""
        raise NotImplementedError

    def _watch_responses(self, watched: bool) -> None:
        """answers.py: whether the loop (True) or the output cycles read the answers."""
        raise NotImplementedError

    def _handle_estop(self, body: bytes, now: float) -> None:
        """safety.py: an EmergencyStop (press latches, release unlatches)."""
        raise NotImplementedError

    def _handle_arming(self, body: bytes, now: float) -> None:
        """safety.py: an Arming (arm, disarm)."""
        raise NotImplementedError

    def _handle_sim_command(self, body: bytes) -> None:
        """sim_protocol.py: a SimulatorCommand to the simulator."""
        raise NotImplementedError

    def _handle_referee_out(self, body: bytes) -> None:
        """referee_out.py: the internal referee's message to the referee multicast."""
        raise NotImplementedError

    def _handle_tracker_out(self, body: bytes) -> None:
        """tracker_out.py: the station's tracked vision to the tracker multicast."""
        raise NotImplementedError

    def _compat_referee_out(self, data: bytes, addr: tuple[str, int]) -> None:
        """compat_io.py: a Referee re-encoded for the seed."""
        raise NotImplementedError
