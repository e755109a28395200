"""The command SUB: the backend's command sets, and the other topics it sends the relay
(estop, arming, sim, referee-out, tracker-out), each to the part that owns it.

**Where a robot command gets its team and id checked**: ``_handle_native`` below. Every
``RobotCommand`` goes through ``codecs.command_from_proto`` (team blue or yellow, id 0..15,
every value finite, kick speed >= 0; a bad one is counted and skipped, the rest of the set
is used), then, on the robot-box output, the one team the box may drive. A set is dropped
whole while the e-stop is latched (every robot zeroed instead) or the relay is disarmed
(the latch and the arming themselves: safety.py).
"""

from __future__ import annotations

import asyncio
import logging
import time
from typing import cast

import zmq
from google.protobuf.message import DecodeError

from larcmacs_relay import codecs
from larcmacs_relay.codecs import Command, CommandError
from larcmacs_relay.part import MAX_BATCH, NOBLOCK, RelayPart
from sslnet import streams
from sslpb import touchline_pb2

log = logging.getLogger("larcmacs_relay")

#: at most this many robot commands kept by their bytes (_handle_native); then started afresh
MAX_PARSED = 512
_EVENTS = int(zmq.EVENTS)
_POLLIN = int(zmq.POLLIN)
#: the topics the relay's SUB takes (the commands' first: the others come a few times a
#: second at most)
TOPICS = (b"commands", b"sim", b"referee-out", b"tracker-out", b"estop", b"arming")


class CommandInput(RelayPart):
    """Command sets into the command table; the other topics to their parts."""

    #: valid robot commands by their serialized RobotCommand: a command set repeats most
    #: robots' commands byte for byte, and the same bytes are the same command (the same
    #: object, so the table and the output see at once that nothing changed)
    _parsed: dict[bytes, Command]

    def _setup_command_input(self) -> None:
        self._parsed = {}
        self._commands_changed = False
        self._pending_latency_ns = []

    def _open_command_input(self, sub: zmq.Socket[bytes]) -> int:
        """Subscribes and binds the command SUB, read from the loop's reader on its FD (a
        plain socket: zmq.asyncio would cost a future and a poller round per command set);
        returns the FD."""
        for topic in TOPICS:
            sub.setsockopt(zmq.SUBSCRIBE, topic)
        sub.bind(self.config.sub_endpoint)
        fd = sub.getsockopt(zmq.FD)
        assert isinstance(fd, int)
        return fd

    def _drain_commands(self, sub: zmq.Socket[bytes]) -> None:
        """Every message waiting on the command SUB, then one output decision for all of them
        (a burst of command sets is one cycle, not one each). The socket's FD is edge-
        triggered: it is drained until ZMQ_EVENTS has no POLLIN (or a receive finds nothing),
        and after MAX_BATCH the rest is left for a call_soon (its FD would not signal
        again). A message's parts are recv_multipart's bytes, but each part's ``more`` is read
        from the part itself: recv_multipart asks the socket for ZMQ_RCVMORE after each part,
        a ``get`` that looks the option up in an enum (two a command set)."""
        self._commands_changed = False
        recv, get = sub.recv, sub.get
        try:
            for _ in range(MAX_BATCH):
                try:
                    part = recv(NOBLOCK, copy=False)
                except zmq.Again:
                    break
                frames = [part.bytes]
                while part.more:  # a message's parts come together: they are all there
                    part = recv(NOBLOCK, copy=False)
                    frames.append(part.bytes)
                try:
                    self._handle_native(frames)
                except Exception as exc:  # never fatal: a bad message is an error, not a crash
                    self.streams["commands"].error("internal error", str(exc))
                    log.exception("command handling failed")
                # ZMQ_EVENTS says whether another message waits: a receive that fails costs
                # pyzmq an exception (twice the time of this question), once per wake-up
                if not cast(int, get(_EVENTS)) & _POLLIN:
                    break
            else:
                asyncio.get_running_loop().call_soon(self._drain_commands, sub)
        except zmq.ZMQError as exc:  # the socket closed under us (shutdown)
            self._ratelog.warning("commands-recv", "command receive failed: %s", exc)
        if self._commands_changed:
            self._kick_output()

    def _handle_native(self, frames: list[bytes]) -> None:
        now = time.monotonic()
        if len(frames) != 2:
            self._command_error("commands", f"expected [topic, message], got {len(frames)} frames",
                                "bad frames")
            return
        topic, body = frames
        if topic != b"commands":  # the others come a few times a second at most (tracked
            self._handle_other(topic, body, now)  # vision: once a world tick)
            return
        counter = self.streams["commands"]
        if self.estop_latched:
            # latched: whatever arrives, every robot gets zero until an explicit release
            counter.packet(len(body), now)
            self.table.stop_all(now)
            return
        if not self.armed:
            # disarmed: nothing from a command set reaches a robot (the robots commanded
            # before were zeroed when it was disarmed: zeros for the hold time, then silence)
            self._command_error("commands", "relay disarmed: command set dropped (arm it from "
                                "the station first)", "disarmed")
            return
        cset = touchline_pb2.RobotCommandSet()
        try:  # not self._parse: a call more per command set, on the hot path
            cset.ParseFromString(body)
        except DecodeError as exc:
            self._command_error("commands", f"RobotCommandSet does not parse: {exc}",
                                streams.wire_problem(body))
            return
        counter.packet(len(body), now)
        accepted: list[Command] = []
        parsed = self._parsed
        for pc in cset.commands:
            key = pc.SerializeToString()
            c = parsed.get(key)
            if c is None:
                try:
                    c = codecs.command_from_proto(pc)
                except CommandError as exc:  # not kept: counted every time it comes
                    self._command_error("commands", str(exc), "bad command")
                    continue
                if len(parsed) >= MAX_PARSED:
                    parsed.clear()
                parsed[key] = c
            if self._box_team is not None and c.team != self._box_team:
                # a robot-box datagram has no team: their robot 3 would be our robot 3
                self._command_error(
                    "commands", f"{codecs.team_name(c.team)} {c.id} dropped: robot-box "
                    f"datagrams have no team field, only {self.config.our_team} is driven",
                    "other team")
                continue
            accepted.append(c)
        if cset.stop_all:
            for c in accepted:
                self.table.update(c.zero(), now)
            self.table.stop_all(now)
            self._commands_changed = True
            log.warning("stop_all received: every known robot zeroed")
            return
        self.table.update_all(accepted, now)
        if accepted:
            self._commands_changed = True
        if cset.source_receive_time_ns > 0 and accepted:
            self._pending_latency_ns.append(cset.source_receive_time_ns)

    def _handle_other(self, topic: bytes, body: bytes, now: float) -> None:
        """A message on the command SUB other than a command set."""
        if topic == b"tracker-out":
            self._handle_tracker_out(body)
        elif topic == b"sim":
            self._handle_sim_command(body)
        elif topic == b"referee-out":
            self._handle_referee_out(body)
        elif topic == b"estop":
            self._handle_estop(body, now)
        elif topic == b"arming":
            self._handle_arming(body, now)
        else:
            self._command_error("commands", f"unknown topic {topic[:32]!r}", "unknown topic")
