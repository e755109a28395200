"""The relay's I/O: multicast in, ZeroMQ out; ZeroMQ commands in, UDP to simulator/robots out.

Use ``Relay(config)`` and ``await relay.run()`` (``relay.stop()`` ends it), or
``await run_relay(config, stop_event)``. Nothing is opened before ``run()``.
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
import math
import socket
import sys
import time
from collections import deque
from collections.abc import Callable
from typing import cast

import zmq
import zmq.asyncio
from google.protobuf.message import DecodeError

from larcmacs_relay import codecs
from larcmacs_relay.codecs import Command, CommandError
from larcmacs_relay.commands import CommandTable, RobotState
from larcmacs_relay.compat import RefereeMapper, decode_command_matrix
from larcmacs_relay.config import RelayConfig
from larcmacs_relay.feedback import FeedbackGate, HeldAnswer, SentLog, sent_items
from sslnet import proc, streams
from sslnet.kerneltime import enable_kernel_timestamps, kernel_time_ns
from sslnet.multicast import open_multicast_receiver, open_multicast_sender, open_udp_server
from sslnet.rate import RateCounter
from sslnet.ratelog import RateLimitedLog
from sslnet.streams import StreamCounter
from sslpb import ssl_simulation_control_pb2, touchline_pb2

log = logging.getLogger("larcmacs_relay")

MAX_DATAGRAM = 65536
MAX_BATCH = 512
#: at most this many robot commands kept by their bytes (_handle_native); then started afresh
MAX_PARSED = 512
# ZeroMQ flags as plain ints: pyzmq's IntFlag arithmetic costs more than the send it flags
_NOBLOCK = int(zmq.NOBLOCK)
_SNDMORE_NOBLOCK = int(zmq.SNDMORE | zmq.NOBLOCK)
_EVENTS = int(zmq.EVENTS)
_POLLIN = int(zmq.POLLIN)
#: a frame sent by libzmq's binding itself: pyzmq's Socket.send is a Python layer over it (for
#: routing ids and groups, which a PUB has not), a call and keywords more per frame
_SEND_FRAME = zmq.backend.Socket.send
_TOPICS = {"vision": b"vision", "referee": b"referee", "tracker": b"tracker"}
#: the stock event loops' clock: time.monotonic itself (uvloop's is not)
_MONOTONIC_LOOP_TIME = asyncio.BaseEventLoop.time
#: one team's datagram of an output cycle: team, bytes, address, its robots' ids
_Planned = tuple[int, bytes, tuple[str, int], tuple[int, ...]]
_STREAM_IDS = {
    "vision": touchline_pb2.STREAM_VISION,
    "referee": touchline_pb2.STREAM_REFEREE,
    "tracker": touchline_pb2.STREAM_TRACKER,
}


def stream_proto(c: StreamCounter, now: float) -> touchline_pb2.StreamStats:
    """One stream's counters as published in RelayStats."""
    return touchline_pb2.StreamStats(
        name=c.name,
        packets=c.packets,
        errors=c.errors,
        bytes=c.bytes,
        rate_hz=c.rate.rate_hz(now),
        last_age_s=c.rate.age_s(now),
        last_error=c.last_error,
        errors_by_reason=c.by_reason,
    )


class Relay:
    """One relay instance. Attributes ``streams``, ``table`` and the bound endpoints
    (``pub_address``, ``sub_address``, ``compat_vision_address``, ``compat_referee_address``)
    are valid once ``ready`` is set."""

    def __init__(self, config: RelayConfig) -> None:
        config.validate()
        self.config = config
        self.table = CommandTable(config.command_timeout_s, config.hold_time_s)
        names = ["vision", "referee", "tracker", "commands", "output", "sim_responses"]
        names += ["sim_commands", "referee_out", "tracker_out"]
        if config.output == "grsim":
            names.append("grsim_status")
        if config.compat:
            names.append("compat_commands")
        self.streams = {n: StreamCounter(n) for n in names}
        self._output = self.streams["output"]
        self.cycles = RateCounter()
        self.ready = asyncio.Event()
        self.pub_address = ""
        self.sub_address = ""
        self.compat_vision_address = ""
        self.compat_referee_address = ""
        self._stop = asyncio.Event()
        self._ratelog = RateLimitedLog(log, config.log_interval_s)
        self._sequences = {"vision": 0, "referee": 0, "tracker": 0}
        #: the feedback forwarding rule per (kind, team) (feedback.py) and each one's timer
        #: for a held answer
        self._gates: dict[tuple[int, int], FeedbackGate] = {}
        #: the simulator's answer streams by the port they come from (blue's port first: the
        #: same port for both is blue's, as it was), each one's gate once it has answered
        self._sim_teams = {config.sim_yellow_port: codecs.TEAM_YELLOW,
                           config.sim_blue_port: codecs.TEAM_BLUE}
        self._sim_gates: dict[int, FeedbackGate] = {}
        self._gate_timers: dict[FeedbackGate, asyncio.TimerHandle] = {}
        #: per team: commands sent to each robot and the wall clock (ns) of the last one,
        #: forwarded with every answer (the backend's round trip and losses)
        self._sent: dict[int, SentLog] = {t: SentLog() for t in codecs.TEAMS}
        #: per team, the robots' commands of the last sim datagram, its bytes, the robots'
        #: ids and each one's encoded part: a cycle with the same command objects sends the
        #: same bytes, and a robot's part is kept while its command is the same object
        self._sim_out: dict[int, tuple[tuple[Command, ...], bytes, tuple[int, ...],
                                       list[bytes]]] = {}
        #: the sim output of the table's version ``_plan_version`` (every team's datagram,
        #: its address and robots): while the table is unchanged a cycle only sends it
        self._plan: list[_Planned] = []
        self._plan_version = -1
        #: valid robot commands by their serialized RobotCommand: a command set repeats most
        #: robots' commands byte for byte, and the same bytes are the same command (the same
        #: object, so the table and the output see at once that nothing changed)
        self._parsed: dict[bytes, Command] = {}
        #: grsim output: the bound Robots_Status ports {"blue": port, "yellow": port}
        self.grsim_status_ports: dict[str, int] = {}
        self._referee_mapper = RefereeMapper(config.our_team)
        self._pending_latency_ns: list[int] = []
        self._latencies: deque[tuple[float, float]] = deque()
        self._ctx: zmq.asyncio.Context | None = None
        self._pub: zmq.Socket[bytes] | None = None
        self._compat_vision: zmq.Socket[bytes] | None = None
        self._compat_referee: zmq.Socket[bytes] | None = None
        self._udp_out: socket.socket | None = None
        #: the simulator's answers arrive on ``_udp_out``; True while the loop watches it (the
        #: output idle), False while the output cycles read it (see _watch_responses)
        self._responses_watched = False
        self._stamped = False  # the kernel stamps the answers' arrival
        self._referee_out: socket.socket | None = None
        self._tracker_out: socket.socket | None = None
        #: uuids of the tracked vision this relay sent: its own frames heard back on the
        #: tracker input (same group and port, loopback) are not taken as another tracker's
        self._own_tracker_uuids: set[str] = set()
        #: own tracked frames heard back on the tracker input (not forwarded, not errors)
        self.own_tracker_echoes = 0
        #: the output schedule (see _kick_output): the last cycle, the next one due (inf: every
        #: robot idle, nothing to send, no wake-up), and the one timer armed for it
        self._last_cycle = -math.inf
        self._next_cycle = math.inf
        self._period = 1.0 / config.output_rate_hz
        #: the running loop once it is known to keep time.monotonic (the stock loops)
        self._monotonic_loop: asyncio.AbstractEventLoop | None = None
        self._timer: asyncio.TimerHandle | None = None
        self._commands_changed = False
        #: "host:port" of each datagram source seen (bounded): one string, not one per datagram
        self._sources: dict[tuple[str, int], str] = {}
        self._sim_host = config.sim_host
        self._box_host = config.robot_box_host
        #: the emergency stop, latched until an explicit release (EmergencyStop on "estop")
        self.estop_latched = False
        self.estop_by = ""
        #: --require-arming: disarmed until an Arming message arms it (a restart disarms)
        self.arming_required = config.require_arming
        self.armed = not config.require_arming
        self.armed_by = ""
        self.cpu = proc.CpuMeter()
        #: robot-box output: the only team it may drive (its datagrams cannot say which)
        self._box_team: int | None = (
            (codecs.TEAM_BLUE if config.our_team == "blue" else codecs.TEAM_YELLOW)
            if config.output == "robot-box" else None)

    # ------------------------------------------------------------------ lifecycle

    def stop(self) -> None:
        self._stop.set()

    async def run(self) -> None:
        loop = asyncio.get_running_loop()
        cfg = self.config
        ctx = zmq.asyncio.Context()
        self._ctx = ctx
        sync_ctx: zmq.Context[zmq.Socket[bytes]] = zmq.Context.shadow(ctx.underlying)
        zsockets: list[zmq.Socket[bytes] | zmq.asyncio.Socket] = []
        udp: list[socket.socket] = []
        tasks: list[asyncio.Task[None]] = []
        sub_fd: int | None = None

        def zsock(c: zmq.Context[zmq.Socket[bytes]], kind: int) -> zmq.Socket[bytes]:
            s = c.socket(kind)
            s.setsockopt(zmq.LINGER, 0)
            zsockets.append(s)
            return s

        def asock(kind: int) -> zmq.asyncio.Socket:
            s = ctx.socket(kind)
            s.setsockopt(zmq.LINGER, 0)
            zsockets.append(s)
            return s

        try:
            pub = zsock(sync_ctx, zmq.PUB)
            pub.setsockopt(zmq.SNDHWM, 10000)
            pub.bind(cfg.pub_endpoint)
            self.pub_address = _endpoint(pub)
            self._pub = pub
            # a plain socket drained from the loop's reader on its FD: zmq.asyncio would cost
            # a future and a poller round per command set
            sub = zsock(sync_ctx, zmq.SUB)
            sub.setsockopt(zmq.SUBSCRIBE, b"commands")
            sub.setsockopt(zmq.SUBSCRIBE, b"sim")
            sub.setsockopt(zmq.SUBSCRIBE, b"referee-out")
            sub.setsockopt(zmq.SUBSCRIBE, b"tracker-out")
            sub.setsockopt(zmq.SUBSCRIBE, b"estop")
            sub.setsockopt(zmq.SUBSCRIBE, b"arming")
            sub.bind(cfg.sub_endpoint)
            self.sub_address = _endpoint(sub)
            compat_sub: zmq.asyncio.Socket | None = None
            if cfg.compat:
                cv = zsock(sync_ctx, zmq.PUB)
                cv.bind(cfg.compat_vision_pub)
                self.compat_vision_address = _endpoint(cv)
                self._compat_vision = cv
                cr = zsock(sync_ctx, zmq.PUB)
                cr.bind(cfg.compat_referee_pub)
                self.compat_referee_address = _endpoint(cr)
                self._compat_referee = cr
                compat_sub = asock(zmq.SUB)
                compat_sub.setsockopt(zmq.SUBSCRIBE, b"")
                compat_sub.connect(cfg.compat_commands)

            inputs: list[tuple[str, str, int, Callable[[bytes], str | None]]] = [
                ("vision", cfg.vision_group, cfg.vision_port, codecs.check_forwarded),
                ("referee", cfg.referee_group, cfg.referee_port, codecs.check_forwarded),
            ]
            if cfg.tracker_enabled:
                inputs.append(
                    ("tracker", cfg.tracker_group, cfg.tracker_port, codecs.validate_tracker)
                )
            for name, group, port, validate in inputs:
                rx = open_multicast_receiver(group, port, cfg.interface)
                udp.append(rx)
                loop.add_reader(rx.fileno(), self._drain_input, rx, name, validate)
                log.info("listening for %s on %s:%d via %s", name, group, port, cfg.interface)

            # Resolve output hosts once: sendto() with a name would resolve on every datagram.
            self._sim_host = socket.gethostbyname(cfg.sim_host)
            self._box_host = socket.gethostbyname(cfg.robot_box_host)
            out = socket.socket(socket.AF_INET, socket.SOCK_DGRAM, socket.IPPROTO_UDP)
            out.setblocking(False)
            udp.append(out)
            self._udp_out = out
            if cfg.output == "sim":
                self._stamped = _stamp_arrivals(out)
                self._watch_responses(True)
            elif cfg.output == "grsim":
                for label, team, port in (
                        ("blue", codecs.TEAM_BLUE, cfg.grsim_status_blue_port),
                        ("yellow", codecs.TEAM_YELLOW, cfg.grsim_status_yellow_port)):
                    st = open_udp_server(cfg.grsim_status_host, port)
                    udp.append(st)
                    self.grsim_status_ports[label] = st.getsockname()[1]
                    loop.add_reader(st.fileno(), self._drain_grsim_status, st, team)
                    log.info("listening for grSim %s robot status on %s:%d", label,
                             cfg.grsim_status_host, self.grsim_status_ports[label])
            if cfg.referee_out_enabled:
                rout = open_multicast_sender(cfg.interface, ttl=cfg.referee_out_ttl)
                udp.append(rout)
                self._referee_out = rout
            if cfg.tracker_out:
                # loopback: TTL 0, it cannot leave this host whatever the routes say
                tout = open_multicast_sender(
                    cfg.tracker_out_interface,
                    ttl=0 if cfg.tracker_out_on_loopback else cfg.tracker_out_ttl)
                udp.append(tout)
                self._tracker_out = tout
                log.info("tracked vision out to %s:%d via %s%s", cfg.tracker_out_group,
                         cfg.tracker_out_port, cfg.tracker_out_interface,
                         " (loopback only: --tracker-out to publish on --interface)"
                         if cfg.tracker_out_on_loopback else " (the venue network)")

            fd = sub.getsockopt(zmq.FD)
            assert isinstance(fd, int)
            sub_fd = fd
            loop.add_reader(fd, self._drain_commands, sub)
            if compat_sub is not None:
                tasks.append(asyncio.create_task(self._compat_loop(compat_sub)))
            tasks.append(asyncio.create_task(self._stats_loop()))
            log.info(
                "relay up: pub %s, sub %s, output %s at %.0f Hz",
                self.pub_address,
                self.sub_address,
                cfg.output,
                cfg.output_rate_hz,
            )
            self.ready.set()
            stop_wait = asyncio.create_task(self._stop.wait())
            done, _ = await asyncio.wait([stop_wait, *tasks], return_when=asyncio.FIRST_COMPLETED)
            stop_wait.cancel()
            for t in done:
                if t is not stop_wait and not t.cancelled() and t.exception() is not None:
                    raise t.exception()  # type: ignore[misc]
        finally:
            if self._timer is not None:
                self._timer.cancel()
                self._timer = None
            for timer in self._gate_timers.values():
                timer.cancel()
            self._gate_timers.clear()
            if sub_fd is not None:
                with contextlib.suppress(Exception):
                    loop.remove_reader(sub_fd)
            for t in tasks:
                t.cancel()
            for t in tasks:
                with contextlib.suppress(asyncio.CancelledError, Exception):
                    await t
            try:
                self.last_word()
            except Exception:  # the sockets are closed all the same
                log.exception("last word failed")
            for s in udp:
                with contextlib.suppress(Exception):
                    loop.remove_reader(s.fileno())
                s.close()
            self._pub = self._compat_vision = self._compat_referee = None
            self._udp_out = None
            self._referee_out = None
            self._tracker_out = None
            for z in zsockets:
                z.close(linger=0)
            ctx.term()
            self._ctx = None
            log.info("relay stopped")

    # ------------------------------------------------------------------ inputs

    def _drain_input(
        self, sock: socket.socket, name: str, validate: Callable[[bytes], str | None]
    ) -> None:
        """Read every datagram waiting on ``sock`` (never just one per wakeup); after
        MAX_BATCH in a row it yields to the loop (the reader is level-triggered and comes back
        at once), so a flood cannot starve the command output. Vision and referee are not
        decoded here (the backend decodes them once): per datagram only the size and
        emptiness checks, its receive time, one Envelope and one ZeroMQ message; the stream's
        packets are counted once per wake-up (one clock read, not one per datagram)."""
        counter = self.streams[name]
        topic = _TOPICS[name]
        stream = _STREAM_IDS[name]
        pub = self._pub
        max_bytes = self.config.max_datagram_bytes
        sources = self._sources
        seq = self._sequences[name]
        tracker = name == "tracker"
        # vision and referee: only an empty datagram is refused (check_forwarded), tested here
        forwarded = validate is codecs.check_forwarded
        compat_vision = self._compat_vision if name == "vision" else None
        compat_referee = name == "referee" and self._compat_referee is not None
        recvfrom = sock.recvfrom
        time_ns = time.time_ns
        envelope = touchline_pb2.Envelope
        send = _SEND_FRAME
        n = nbytes = 0
        try:
            for _ in range(MAX_BATCH):
                try:
                    data, addr = recvfrom(MAX_DATAGRAM)
                except (BlockingIOError, InterruptedError):
                    return
                except OSError as exc:
                    counter.error("receive failed", str(exc))
                    self._ratelog.warning(f"{name}-recv", "%s receive failed: %s", name, exc)
                    return
                receive_ns = time_ns()
                size = len(data)
                if forwarded and data and size <= max_bytes:
                    pass  # the common case: nothing more to check
                elif not self._input_ok(data, addr, name, validate, counter, tracker):
                    continue
                n += 1
                nbytes += size
                seq += 1
                source = sources.get(addr)
                if source is None:
                    source = self._source(addr)
                if pub is not None:
                    body = envelope(stream=stream, receive_time_ns=receive_ns, sequence=seq,
                                    source=source, payload=data).SerializeToString()
                    try:  # a PUB queues a multipart message whole or not at all
                        send(pub, topic, _SNDMORE_NOBLOCK)
                        send(pub, body, _NOBLOCK)
                    except zmq.Again:
                        self._ratelog.warning("pub-full", "ZeroMQ PUB queue full, message "
                                              "dropped")
                if compat_vision is not None:
                    self._publish(compat_vision, [data])
                elif compat_referee:
                    self._compat_referee_out(data, addr)
        finally:
            self._sequences[name] = seq
            if n:
                counter.packets_at(n, nbytes, time.monotonic())

    def _input_ok(self, data: bytes, addr: tuple[str, int], name: str,
                  validate: Callable[[bytes], str | None], counter: StreamCounter,
                  tracker: bool) -> bool:
        """The checks of an input datagram beyond the common case (a tracker's, an own tracked
        frame heard back, an empty or oversized one): False when it is not forwarded (an echo
        is counted apart, a bad one as an error by reason, and logged)."""
        if tracker and self._own_tracker_uuids and self._own_echo(data):
            self.own_tracker_echoes += 1
            return False
        max_bytes = self.config.max_datagram_bytes
        if len(data) > max_bytes:
            reason: str | None = f"{len(data)} bytes, more than {max_bytes}"
            kind = streams.OVERSIZED
        else:
            try:
                reason = validate(data)
            except Exception as exc:  # a decoder surprise must not kill the reader
                reason = f"validation failed: {exc!r}"
            kind = codecs.classify(reason, data) if reason is not None else ""
        if reason is None:
            return True
        counter.error(kind, reason)
        self._ratelog.warning(
            f"{name}-bad",
            "dropped malformed %s datagram from %s:%d: %s",
            name,
            addr[0],
            addr[1],
            reason,
        )
        return False

    def _compat_referee_out(self, data: bytes, addr: tuple[str, int]) -> None:
        ref, why = codecs.parse_referee(data)
        if ref is not None:
            self._publish(self._compat_referee, [self._referee_mapper.encode(ref)])
        else:
            self._ratelog.warning("compat-referee", "Referee from %s:%d not re-encoded "
                                  "for the compat output: %s", addr[0], addr[1], why)

    def _own_echo(self, data: bytes) -> bool:
        """True if ``data`` is tracked vision this relay sent (heard back on loopback)."""
        pkt, _ = codecs.parse_tracked_out(data)
        return pkt is not None and pkt.uuid in self._own_tracker_uuids

    def _publish(self, sock: zmq.Socket[bytes] | None, frames: list[bytes]) -> None:
        if sock is None:
            return
        try:
            sock.send_multipart(frames, flags=_NOBLOCK)
        except zmq.Again:
            self._ratelog.warning("pub-full", "ZeroMQ PUB queue full, message dropped")

    # ------------------------------------------------------------------ commands

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
                    part = recv(_NOBLOCK, copy=False)
                except zmq.Again:
                    break
                frames = [part.bytes]
                while part.more:  # a message's parts come together: they are all there
                    part = recv(_NOBLOCK, copy=False)
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
        try:
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

    def _handle_estop(self, body: bytes, now: float) -> None:
        msg = touchline_pb2.EmergencyStop()
        try:
            msg.ParseFromString(body)
        except DecodeError as exc:
            self._command_error("commands", f"EmergencyStop does not parse: {exc}",
                                streams.wire_problem(body))
            return
        if msg.action == touchline_pb2.EmergencyStop.PRESS:
            if not self.estop_latched:
                log.warning("emergency stop latched (by %s): zeros to every robot until an "
                            "explicit release", msg.by or "?")
            self.estop_latched, self.estop_by = True, msg.by
            if self.arming_required and self.armed:
                log.warning("disarmed by the emergency stop")
            self.armed = not self.arming_required  # the e-stop disarms
            self.table.stop_all(now)
            self._commands_changed = True
        elif msg.action == touchline_pb2.EmergencyStop.RELEASE:
            if self.estop_latched:
                log.warning("emergency stop released (by %s)", msg.by or "?")
            self.estop_latched, self.estop_by = False, ""
        else:
            self._command_error("commands", f"EmergencyStop with action {msg.action}",
                                "bad command")

    def _handle_arming(self, body: bytes, now: float) -> None:
        msg = touchline_pb2.Arming()
        try:
            msg.ParseFromString(body)
        except DecodeError as exc:
            self._command_error("commands", f"Arming does not parse: {exc}",
                                streams.wire_problem(body))
            return
        if not self.arming_required:
            return  # always armed: nothing to do
        if msg.armed:
            if self.estop_latched:
                self._command_error("commands", "arming refused: the emergency stop is latched",
                                    "arming refused")
                return
            was = self.armed
            if not was:
                log.warning("ARMED (by %s): commands go to the robots", msg.by or "?")
            self.armed, self.armed_by = True, msg.by
            if not was:
                self._acknowledge()
            return
        if not self.armed:
            return  # repeated every 0.5 s: zeros for the hold time, then silence
        log.warning("disarmed (by %s): only stops go to the robots", msg.by or "?")
        self.armed, self.armed_by = False, msg.by
        self.table.stop_all(now)
        self._commands_changed = True
        self._acknowledge()

    def _acknowledge(self) -> None:
        """The statistics at once after an arming change (not a second later on the stats
        timer): the backend waits for them to tell the operator what the relay did."""
        self._publish(self._pub, [b"stats", self.stats().SerializeToString()])

    def _command_error(self, stream: str, reason: str, kind: str = "rejected") -> None:
        self.streams[stream].error(kind, reason)
        kind = " ".join(reason.split()[:3])  # bounded set of log keys, one per kind of error
        self._ratelog.warning(f"{stream}-bad:{kind}", "rejected %s: %s", stream, reason)

    def _handle_sim_command(self, body: bytes) -> None:
        cfg = self.config
        counter = self.streams["sim_commands"]
        cmd = ssl_simulation_control_pb2.SimulatorCommand()
        try:
            cmd.ParseFromString(body)
        except DecodeError as exc:
            self._command_error("sim_commands", f"SimulatorCommand does not parse: {exc}",
                                streams.wire_problem(body))
            return
        if not cmd.IsInitialized():
            self._command_error("sim_commands", "SimulatorCommand misses required fields",
                                streams.MISSING_FIELD)
            return
        counter.packet(len(body))
        if cfg.output == "sim":
            self._send(body, (self._sim_host, cfg.sim_control_port))
        elif cfg.output == "grsim":
            pkt = codecs.sim_command_to_grsim(cmd)
            if pkt is not None:
                self._send(pkt, (self._sim_host, cfg.grsim_port))
        else:
            self._command_error("sim_commands", "simulator commands unsupported in robot-box mode")

    def _handle_referee_out(self, body: bytes) -> None:
        """The internal referee's messages go out as real Referee multicast."""
        cfg = self.config
        if self._referee_out is None:
            self._command_error("referee_out", "referee output is off (interface is not "
                                "loopback; start with --referee-out to allow it)")
            return
        ref, reason = codecs.parse_referee(body)
        if ref is None:
            self._command_error("referee_out", f"Referee rejected: {reason}")
            return
        try:
            self._referee_out.sendto(body, (cfg.referee_group, cfg.referee_port))
        except OSError as exc:
            self._command_error("referee_out", f"send failed: {exc}")
            return
        self.streams["referee_out"].packet(len(body))

    def _handle_tracker_out(self, body: bytes) -> None:
        """The station's world estimate goes out as the league's tracked vision, checked
        first (a bad one is counted by reason and never sent)."""
        cfg = self.config
        if self._tracker_out is None:
            self._command_error("tracker_out", "tracked vision output is off (--no-tracker-out)",
                                "output off")
            return
        pkt, reason = codecs.parse_tracked_out(body)
        if pkt is None:
            assert reason is not None
            self._command_error("tracker_out", reason, codecs.classify(reason, body))
            return
        if len(body) > cfg.max_datagram_bytes:
            self._command_error("tracker_out", f"{len(body)} bytes, more than "
                                f"{cfg.max_datagram_bytes}", streams.OVERSIZED)
            return
        if pkt.uuid not in self._own_tracker_uuids and len(self._own_tracker_uuids) < 64:
            self._own_tracker_uuids.add(pkt.uuid)
        try:
            self._tracker_out.sendto(body, (cfg.tracker_out_group, cfg.tracker_out_port))
        except OSError as exc:
            self._command_error("tracker_out", f"send failed: {exc}", "send failed")
            return
        self.streams["tracker_out"].packet(len(body))

    async def _compat_loop(self, sub: zmq.asyncio.Socket) -> None:
        cfg = self.config
        counter = self.streams["compat_commands"]
        while True:
            frames = await sub.recv_multipart()
            now = time.monotonic()
            body = frames[-1]
            try:
                result = decode_command_matrix(
                    body,
                    kick_mps_per_volt=cfg.kick_mps_per_volt,
                    max_kick_mps=cfg.max_kick_mps,
                    dribbler_rpm_per_unit=cfg.dribbler_rpm_per_unit,
                )
            except ValueError as exc:
                self._command_error("compat_commands", str(exc))
                continue
            counter.packet(len(body), now)
            for err in result.errors:
                self._command_error("compat_commands", err)
            if self.estop_latched:  # the latch holds for the seed's commands too
                self.table.stop_all(now)
                continue
            if not self.armed:
                if result.commands:
                    self._command_error("compat_commands", "relay disarmed: commands dropped",
                                        "disarmed")
                continue
            for c in result.commands:
                self.table.update(c, now)
            if result.commands:
                self._kick_output()

    # ------------------------------------------------------------------ output

    def _kick_output(self) -> None:
        """New commands (or a stop): a cycle at once, unless the last one was less than
        ``min_output_gap_s`` ago; then one as soon as that gap has passed. Either way the
        repeat schedule is re-phased from that cycle."""
        now = time.monotonic()
        earliest = self._last_cycle + self.config.min_gap_s
        if now >= earliest:
            self._run_cycle(now)
        elif earliest < self._next_cycle:
            self._arm(earliest)

    def _arm(self, t: float) -> None:
        """The next cycle is due at monotonic ``t``. One timer at most, moved to ``t`` unless
        it is due within the cycle tolerance (0.5 ms) of it: a command set re-phases the
        schedule a period later, and the timer left where it was would wake the loop for
        nothing (a cycle ran since) several times per period at one set per camera frame."""
        self._next_cycle = t
        timer = self._timer
        loop = asyncio.get_running_loop()
        when = t if loop is self._monotonic_loop else self._loop_time(t)
        if timer is not None:
            if abs(timer.when() - when) <= 0.0005:
                return
            timer.cancel()
        self._timer = loop.call_at(when, self._on_timer)

    def _loop_time(self, t: float) -> float:
        """Monotonic ``t`` on the loop's clock (asyncio's is time.monotonic, uvloop's not)."""
        loop = asyncio.get_running_loop()
        if loop is self._monotonic_loop:
            return t
        if type(loop).time is _MONOTONIC_LOOP_TIME:  # the stock loops: t itself, from now on
            self._monotonic_loop = loop
            return t
        return loop.time() + (t - time.monotonic())

    def _on_timer(self) -> None:
        self._timer = None
        now = time.monotonic()
        if now + 0.0005 < self._next_cycle:  # a cycle ran since: not due yet
            self._arm(self._next_cycle)
            return
        self._run_cycle(now)

    def _run_cycle(self, now: float) -> None:
        """One cycle and the next one's time: a period later, on the old schedule while it
        keeps up (no drift), and no wake-up at all when nothing was due (every robot idle:
        the next command kicks the output again)."""
        out = self._udp_out
        if self._stamped and out is not None:  # the answers that came since, before a send
            self._drain_responses(out)  # (an answer's 'sent' is what went before it)
        try:
            sent = self.output_cycle(now)
        except Exception as exc:  # the schedule must survive a bad cycle: stops depend on it
            sent = True
            self.streams["output"].error("internal error", str(exc))
            log.exception("output cycle failed")
        self._last_cycle = now
        if self._stamped:  # the cycles read the answers while they run, the loop once idle
            self._watch_responses(not sent)
        if not sent:
            self._next_cycle = math.inf
            if self._timer is not None:
                self._timer.cancel()
                self._timer = None
            return
        period = self._period
        due_at = self._next_cycle
        on_schedule = now + 0.0005 >= due_at and now - due_at < period
        self._arm(due_at + period if on_schedule else now + period)

    def _watch_responses(self, watched: bool) -> None:
        """The simulator answers every datagram of a cycle (about 330 a second at full
        scale), and a loop wake-up per answer cost more than the answer: while the output
        cycles run (at least ``output_rate_hz``), each cycle reads what came since, before it
        sends, and the loop does not watch the socket; once the output is idle it watches it
        again. The kernel's arrival stamps keep every answer's receive time exact; an answer
        goes on at most one period later (the backend's feedback is held up to 20 ms anyway).
        Without the stamps (not Linux) the loop always watches, as before."""
        out = self._udp_out
        if out is None or watched == self._responses_watched:
            return
        loop = asyncio.get_running_loop()
        if watched:
            loop.add_reader(out.fileno(), self._drain_responses, out)
        else:
            loop.remove_reader(out.fileno())
        self._responses_watched = watched

    def output_cycle(self, now: float) -> bool:
        """One output cycle: send every due command (public for tests and benchmarks).
        False when nothing was due (every robot idle or none known)."""
        due = self.table.due(now)
        if not due:
            return False
        self.cycles.add(now)
        if self.estop_latched or not self.armed:
            # the latch and the arming are enforced here, where every command path meets:
            # only zeros leave (the stops of robots commanded before, for the hold time)
            self._send_commands([c.zero() for c in due])
        else:
            self._send_commands(due, self.table.version)
        if self._pending_latency_ns:
            sent_ns = time.time_ns()
            for src in self._pending_latency_ns:
                self._latencies.append((now, (sent_ns - src) / 1e6))
            self._pending_latency_ns.clear()
        return True

    def _send_commands(self, due: list[Command], version: int | None = None) -> None:
        """Encode and send ``due`` on the configured output. ``version``: the command table's
        version ``due`` is of (its commands are the same objects while it stays the same),
        None for commands made for this call (stops)."""
        cfg = self.config
        if cfg.output == "robot-box":
            for c in due:
                self._send(
                    codecs.encode_robot_box(
                        c,
                        kick_mps_per_volt=cfg.kick_mps_per_volt,
                        dribbler_rpm_per_unit=cfg.dribbler_rpm_per_unit,
                        charge=cfg.robot_box_charge,
                    ),
                    (self._box_host, cfg.robot_box_port),
                )
            return
        if cfg.output == "sim":
            if version is None or version != self._plan_version:
                self._plan = self._sim_plan(due)
                self._plan_version = -1 if version is None else version
            plan = self._plan
        else:
            plan = self._grsim_plan(due)
        out = self._udp_out
        if out is None:
            return
        n = nbytes = 0
        for team, data, addr, ids in plan:
            try:
                out.sendto(data, addr)
            except OSError as exc:
                self._send_failed(addr, exc)
                continue
            self._sent[team].sent(ids, time.time_ns())
            n += 1
            nbytes += len(data)
        if n:  # one count a cycle (the output stream's clock: the cycle's, not one each)
            self._output.packets_at(n, nbytes, time.monotonic())

    def _grsim_plan(self, due: list[Command]) -> list[_Planned]:
        """Each team's grSim_Packet of ``due`` (a timestamp in each: nothing reused)."""
        cfg = self.config
        plan: list[_Planned] = []
        for team in codecs.TEAMS:
            cmds = [c for c in due if c.team == team]
            if cmds:
                data = codecs.encode_grsim_commands(
                    cmds, team == codecs.TEAM_YELLOW, time.time(), cfg.chip_angle_deg)
                plan.append((team, data, (self._sim_host, cfg.grsim_port),
                             tuple(c.id for c in cmds)))
        return plan

    def _sim_plan(self, due: list[Command]) -> list[_Planned]:
        """Each team's RobotControl datagram of ``due`` (sorted by team, id), its address and
        its robots' ids; a team's bytes are reused while its commands are the same objects."""
        cfg = self.config
        encode = codecs.encode_sim_robot_command
        angle = cfg.chip_angle_deg
        plan: list[_Planned] = []
        blue = [c for c in due if c.team == codecs.TEAM_BLUE]
        yellow = [c for c in due if c.team != codecs.TEAM_BLUE] if len(blue) < len(due) else []
        for team, cmds, port in ((codecs.TEAM_BLUE, blue, cfg.sim_blue_port),
                                 (codecs.TEAM_YELLOW, yellow, cfg.sim_yellow_port)):
            if not cmds:
                continue
            robots = tuple(cmds)
            last = self._sim_out.get(team)
            if last is not None and last[0] == robots:  # the same objects (or equal ones)
                data, ids = last[1], last[2]
            else:
                if last is not None and len(last[0]) == len(robots):
                    parts = [p if c is o else encode(c, angle)
                             for c, o, p in zip(robots, last[0], last[3], strict=True)]
                else:
                    parts = [encode(c, angle) for c in robots]
                data = b"".join(parts)
                ids = tuple([c.id for c in robots])
                if last is not None and last[2] == ids:
                    ids = last[2]  # the same robots: the sent log sees it by identity
                self._sim_out[team] = (robots, data, ids, parts)
            plan.append((team, data, (self._sim_host, port), ids))
        return plan

    def last_word(self) -> None:
        """On every shutdown the relay can see (SIGTERM, SIGINT, an exception): zero velocity,
        no kick, dribbler off to every robot it ever commanded, ``last_word_repeats`` times
        (UDP can drop one), so the robots' last datagram from it is a stop. Only a SIGKILL
        (or a power cut) leaves the stop to the robots' own command timeout."""
        zeros = self.table.all_zero()
        if not zeros or self._udp_out is None:
            return
        for k in range(self.config.last_word_repeats):
            if k:
                time.sleep(0.005)
            self._send_commands(zeros)
        log.warning("last word: stop sent to %d robots (%d times)", len(zeros),
                    self.config.last_word_repeats)

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

    def _drain_responses(self, sock: socket.socket) -> None:
        """The simulator's answers waiting on ``sock``: each one checked (a repeat of the last
        valid bytes is not parsed again) and forwarded (feedback.py); the stream's packets
        counted once per call."""
        counter = self.streams["sim_responses"]
        stamped = self._stamped
        gates = self._sim_gates
        packets = nbytes = 0
        try:
            while True:
                try:
                    if stamped:
                        data, anc, _flags, addr = sock.recvmsg(MAX_DATAGRAM, 64)
                    else:
                        data, addr = sock.recvfrom(MAX_DATAGRAM)
                except (BlockingIOError, InterruptedError):
                    return
                except OSError as exc:  # e.g. ICMP port unreachable reported on the socket
                    counter.error("socket error", str(exc))
                    self._ratelog.warning("sim-resp-os", "simulator socket error: %s", exc)
                    continue
                receive_ns = (kernel_time_ns(anc) if stamped else None) or time.time_ns()
                packets += 1
                nbytes += len(data)
                gate = gates.get(addr[1])  # the team's answers (a gate made at the first)
                if gate is None and addr[1] in self._sim_teams:
                    gate = gates[addr[1]] = self._gate(touchline_pb2.FEEDBACK_SIM_RESPONSE,
                                                       self._sim_teams[addr[1]])
                if gate is None:  # the control port's SimulatorResponse: errors only
                    n, reason = codecs.count_response_errors(data)
                    kind = None if n == 0 or reason.startswith("simulator error") else \
                        codecs.classify(reason, data)
                else:
                    checked = gate.checked
                    if checked is not None and checked[0] == data:  # a repeat: said the same
                        n, reason, kind = checked[1], checked[2], None
                    else:
                        n, reason, kind = codecs.check_robot_control_response(data)
                        if kind is None:
                            gate.checked = (data, n, reason)
                if kind is not None:
                    counter.error(kind, reason)
                    self._ratelog.warning("sim-resp-bad", "bad answer from the simulator at "
                                          "%s:%d: %s", addr[0], addr[1], reason)
                    continue
                if n:
                    counter.error("simulator error", reason, n)
                    self._ratelog.warning(
                        "sim-resp", "simulator at %s:%d reports: %s", addr[0], addr[1], reason
                    )
                if gate is not None:
                    self._forward_feedback(gate, data, addr, receive_ns)
        finally:
            if packets:
                counter.packets_at(packets, nbytes, time.monotonic())

    def _drain_grsim_status(self, sock: socket.socket, team: int) -> None:
        """grSim's Robots_Status datagrams of one team, validated and forwarded unchanged."""
        counter = self.streams["grsim_status"]
        for _ in range(MAX_BATCH):
            try:
                data, addr = sock.recvfrom(MAX_DATAGRAM)
            except (BlockingIOError, InterruptedError):
                return
            except OSError as exc:
                counter.error("socket error", str(exc))
                self._ratelog.warning("grsim-status-os", "grSim status socket error: %s", exc)
                return
            receive_ns = time.time_ns()
            if len(data) > self.config.max_datagram_bytes:
                counter.error(streams.OVERSIZED, f"{len(data)} bytes")
                continue
            reason = codecs.check_grsim_status(data)
            if reason is not None:
                counter.error(codecs.classify(reason, data), reason)
                self._ratelog.warning("grsim-status-bad", "dropped grSim status from %s:%d: "
                                      "%s", addr[0], addr[1], reason)
                continue
            counter.packet(len(data))
            self._forward_feedback(self._gate(touchline_pb2.FEEDBACK_GRSIM_STATUS, team), data,
                                   addr, receive_ns)

    def _gate(self, kind: int, team: int) -> FeedbackGate:
        """The forwarding rule of one answer stream: simulator answers are coalesced
        (feedback.py), grSim's robot status (only sent on a change) never is."""
        gate = self._gates.get((kind, team))
        if gate is None:
            interval = self.config.feedback_interval_s \
                if kind == touchline_pb2.FEEDBACK_SIM_RESPONSE else 0.0
            gate = self._gates[(kind, team)] = FeedbackGate(kind, team, interval)
        return gate

    def _forward_feedback(self, gate: FeedbackGate, data: bytes, addr: tuple[str, int],
                          receive_ns: int) -> None:
        """One valid answer: onto the PUB now, or held (feedback.py) and sent by a timer
        unless a newer one goes first."""
        now = time.monotonic()
        sent = self._sent[gate.team].snapshot()
        if gate.arrive(data, now):
            held = gate.held
            if held is not None:
                if held.data != data:  # the answers before a change first
                    self._publish_feedback(gate, held)
                timer = self._gate_timers.pop(gate, None)
                if timer is not None:  # nothing held any more: no wake-up for it
                    timer.cancel()
            self._publish_feedback(gate, HeldAnswer(data, addr, receive_ns, gate.answers, sent))
            gate.forwarded(data, now)
            return
        gate.hold(HeldAnswer(data, addr, receive_ns, gate.answers, sent))
        if gate not in self._gate_timers:  # (a gate is its stream: its timer by identity)
            loop = asyncio.get_running_loop()
            self._gate_timers[gate] = loop.call_at(self._loop_time(gate.flush_at),
                                                  self._flush_feedback, gate)

    def _flush_feedback(self, gate: FeedbackGate) -> None:
        """A held answer is due (no newer one came to take its place): it goes on."""
        self._gate_timers.pop(gate, None)
        held = gate.held
        if held is None:
            return
        self._publish_feedback(gate, held)
        gate.forwarded(held.data, time.monotonic())

    def _publish_feedback(self, gate: FeedbackGate, a: HeldAnswer) -> None:
        """One answer onto the PUB ("feedback"), with what had been sent to the team's robots
        when it arrived and its stream's count of answers then (``sequence``)."""
        env = touchline_pb2.RobotFeedbackEnvelope(
            kind=gate.kind,  # type: ignore[arg-type]
            team=gate.team,  # type: ignore[arg-type]
            receive_time_ns=a.receive_ns,
            sequence=a.sequence,
            source=self._source(a.addr),
            payload=a.data,
            sent=[touchline_pb2.RobotSent(id=rid, commands_sent=n, last_sent_time_ns=t)
                  for rid, (n, t) in sorted(sent_items(a.sent).items())],
        )
        self._publish(self._pub, [b"feedback", env.SerializeToString()])

    def _source(self, addr: tuple[str, int]) -> str:
        """"ip:port" of a datagram's sender, made once per sender (at most 256 kept)."""
        source = self._sources.get(addr)
        if source is None:
            source = f"{addr[0]}:{addr[1]}"
            if len(self._sources) < 256:  # a spoofing flood cannot grow it
                self._sources[addr] = source
        return source

    # ------------------------------------------------------------------ stats

    def stats(self, now: float | None = None) -> touchline_pb2.RelayStats:
        t = time.monotonic() if now is None else now
        while self._latencies and self._latencies[0][0] < t - 1.0:
            self._latencies.popleft()
        lat = sorted(v for _, v in self._latencies)
        latency = sum(lat) / len(lat) if lat else -1.0
        p50 = lat[len(lat) // 2] if lat else -1.0
        p99 = lat[min(len(lat) - 1, int(0.99 * len(lat)))] if lat else -1.0
        return touchline_pb2.RelayStats(
            time_ns=time.time_ns(),
            streams=[stream_proto(s, t) for s in self.streams.values()],
            output_mode=self.config.output,
            active_robots=self.table.count(RobotState.ACTIVE),
            stale_robots=self.table.count(RobotState.STALE) + self.table.count(RobotState.STOPPED),
            output_rate_hz=self.cycles.rate_hz(t),
            command_latency_ms=latency,
            stale_stops=self.table.stale_stops,
            estop_latched=self.estop_latched,
            estop_by=self.estop_by,
            command_latency_p50_ms=p50,
            command_latency_p99_ms=p99,
            cpu_percent=self.cpu.read(),
            rss_mb=proc.rss_mb(),
            armed=self.armed,
            arming_required=self.arming_required,
        )

    async def _stats_loop(self) -> None:
        while True:
            await asyncio.sleep(self.config.stats_interval_s)
            self._publish(self._pub, [b"stats", self.stats().SerializeToString()])


def _stamp_arrivals(sock: socket.socket) -> bool:
    """Asks the kernel to stamp every datagram ``sock`` receives with its arrival time (Linux;
    False where that is not to be had)."""
    if not sys.platform.startswith("linux"):
        return False
    try:
        enable_kernel_timestamps(sock)
    except OSError:
        return False
    return True


def _endpoint(sock: zmq.Socket[bytes] | zmq.asyncio.Socket) -> str:
    value = sock.getsockopt(zmq.LAST_ENDPOINT)
    return value.decode() if isinstance(value, bytes) else str(value)


async def run_relay(config: RelayConfig, stop: asyncio.Event | None = None) -> None:
    """Run a relay until ``stop`` is set (or forever); all sockets are closed on return."""
    relay = Relay(config)
    if stop is None:
        await relay.run()
        return
    task = asyncio.create_task(relay.run())
    waiter = asyncio.create_task(stop.wait())
    await asyncio.wait([task, waiter], return_when=asyncio.FIRST_COMPLETED)
    relay.stop()
    waiter.cancel()
    await task
