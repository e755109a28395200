"""The relay's ZeroMQ PUB onto the bus: datagram envelopes and the relay's statistics."""

from __future__ import annotations

import asyncio
import math
import struct
import time
from collections import deque
from collections.abc import Callable
from typing import Any

import zmq
import zmq.asyncio
from google.protobuf.message import DecodeError, Message

from ssllog.format import TYPE_REFEREE_2013, TYPE_VISION_2014
from sslnet import streams
from sslnet.streams import StreamCounter
from sslpb import touchline_pb2 as tl

from .. import topics
from ..bus import DataBus
from .common import SocketProcessor, badlog

_EVENTS, _POLLIN, _NOBLOCK = int(zmq.EVENTS), int(zmq.POLLIN), int(zmq.NOBLOCK)
_ROUNDS = 8  # ticks (each with its pass) in one callback of the descriptor at most
#: camera frames captured each within this of the one before (their own capture times, read
#: off the datagram) are one burst: cameras triggered together (grSim: one capture time for
#: its four cameras a step; fieldsim --camera-phases together). The relay's receive stamps,
#: user-space time after its recvfrom, spread them by its scheduling (grSim at load 3-5: 40 %
#: of a step's gaps over 0.3 ms, p90 1.8 ms); they are the rule only for a datagram whose
#: capture time cannot be read where every known sender writes it
BURST_GAP_NS = 300_000
#: the wait for the rest of a burst follows the relay's measured spread of one: the 95th
#: percentile of the gaps between its stamps of a burst's frames (the last BURST_GAPS of
#: them), never less than BURST_GAP_NS nor more than BURST_WAIT_MAX_NS
BURST_WAIT_MAX_NS = 2_000_000
BURST_GAPS = 64
#: a burst's expected size: the most common size of the last BURST_HISTORY whole bursts,
#: once seen twice (the smaller on a tie): a frame lost, or a burst split by a late one, does
#: not end the waiting as the smaller of the last two did
BURST_HISTORY = 8
#: the pass is never held longer than this after the first tick that held it (the runner's
#: cap, ``hold_max_s``): well within a camera period (13.3 ms at 75 Hz)
BURST_HOLD_MAX_NS = 3_000_000
_DOUBLE = struct.Struct("<d")


def capture_ns(payload: bytes) -> int | None:
    """A vision datagram's capture time (``t_capture``, ns) read off its first bytes, or None.
    Every known sender (ssl-vision, grSim, fieldsim: protobuf's own serializers) writes the
    wrapper's detection (field 1) first and in it ``frame_number`` (1) then ``t_capture`` (2):
    a dozen bytes read instead of a parse (the packet is parsed once, by VisionIngest). None
    for anything else (a geometry packet, another order): the relay's stamp stands in."""
    try:
        if payload[0] != 0x0A:  # field 1, length-delimited
            return None
        i = 1
        while payload[i] & 0x80:  # the detection's length
            i += 1
        if payload[i + 1] != 0x08:  # frame_number, varint
            return None
        i += 2
        while payload[i] & 0x80:
            i += 1
        if payload[i + 1] != 0x11:  # t_capture, 64-bit
            return None
        t: float = _DOUBLE.unpack_from(payload, i + 2)[0]
    except (IndexError, struct.error):
        return None
    return int(t * 1e9) if math.isfinite(t) and abs(t) < 1e11 else None


class RelayIngest(SocketProcessor):
    """Source: receives everything the relay publishes and puts it on the bus unchanged."""

    name = "relay-ingest"

    def __init__(self, bus: DataBus, sock: zmq.asyncio.Socket | None = None) -> None:
        super().__init__(None)
        if sock is not None:
            self.attach(sock)
        self.vision_packets = bus.of(topics.VISION_PACKETS)
        self.referee_packets = bus.of(topics.REFEREE_PACKETS)
        self.relay_stats = bus.of(topics.RELAY_STATS)
        self.feedback_packets = bus.of(topics.FEEDBACK_PACKETS)
        self._zmq = StreamCounter("zmq")
        self.counters = {"zmq": self._zmq}
        #: False while a log is replayed: live datagrams are then not fed to the pipeline
        #: (they are still recorded)
        self.live: Callable[[], bool] = lambda: True
        #: every live vision (type 4) and referee (type 3) datagram with its receive time
        self.record: Callable[[int, int, bytes], None] = lambda t, k, b: None
        self._fd = -1
        self._fd_loop: asyncio.AbstractEventLoop | None = None
        self._waiter: asyncio.Future[None] | None = None
        #: the runner's callback (``watch_input``): tick and pass when a message waits
        self._ready: Callable[[], None] | None = None
        #: one pass per burst: the clock of the relay's receive stamps (this machine's wall
        #: clock); the newest vision frame's stamp and its capture time (None: unread, the
        #: stamp groups it), the frames of its burst so far, the sizes of the last whole
        #: bursts and the size expected; the gaps between the stamps of a burst's frames and
        #: the wait they give; the times a tick held the pass for the rest of a burst
        self.clock_ns: Callable[[], int] = time.time_ns
        self._burst_last = 0
        self._burst_capture: int | None = None
        self._burst_n = 0
        self._burst_sizes: deque[int] = deque(maxlen=BURST_HISTORY)
        self.burst_expected = 0
        self._burst_gaps: list[int] = []
        self.burst_wait_ns = BURST_GAP_NS
        self.held = 0
        self.hold_max_s = BURST_HOLD_MAX_NS / 1e9
        #: messages put on the bus since the pass last ran (while the pass is held, the
        #: ticks' drains together stay within the smallest ingest topic); whether the pass
        #: is held; this tick's: a live camera frame, a referee packet (a HALT's way in: the
        #: pass at once; a robot's answer or the relay's statistics wait with the frames)
        self._unpassed = 0
        self._holding = False
        self._fed = False
        self._urgent = False

    async def wait_input(self) -> None:
        """Until a message waits. Through the socket's own file descriptor, watched by the
        loop once for the socket's life (``zmq.asyncio``'s poll added and removed a reader
        and built two futures per wake-up: 8 % of the station thread at 600 frames/s). The
        descriptor is edge-triggered: it signals only a change, so ``zmq.EVENTS`` is asked
        before waiting (a message that came while the last tick drained is there now)."""
        out = self._out
        if out is None:
            raise RuntimeError(f"{self.name}: no socket attached (the station attaches it "
                               "in start)")
        if out.get(_EVENTS) & _POLLIN:
            return
        loop = asyncio.get_running_loop()
        if self._fd_loop is not loop:
            self._watch_fd(loop)
        self._waiter = loop.create_future()
        try:
            await self._waiter
        finally:
            self._waiter = None

    def watch_input(self, ready: Callable[[], None]) -> bool:
        """The runner's callback instead of ``wait_input``: the loop calls ``_fd_ready`` when
        the descriptor signals, which calls ``ready`` (the tick and the pass, in that call)
        while a message waits. No future, no task, no second turn of the loop per frame."""
        if self._out is None:
            return False
        self._ready = ready
        loop = asyncio.get_running_loop()
        self._watch_fd(loop)
        loop.call_soon(self._fd_ready)  # what came before the watch (no signal for it)
        return True

    def _watch_fd(self, loop: asyncio.AbstractEventLoop) -> None:
        self._unwatch_fd()
        self._fd = self._out.get(zmq.FD)
        loop.add_reader(self._fd, self._fd_ready)
        self._fd_loop = loop

    def _unwatch_fd(self) -> None:
        if self._fd_loop is not None and not self._fd_loop.is_closed():
            self._fd_loop.remove_reader(self._fd)
        self._fd_loop = None

    def _fd_ready(self) -> None:
        # asking for the events also clears the descriptor (until the next change)
        try:
            ready = self._out.get(_EVENTS) & _POLLIN
        except zmq.ZMQError:  # closed under us (shutdown): wake the waiter, recv says why
            if self._ready is not None:
                return  # watched by the runner: nothing to tick, it stops
            ready = True
        if not ready:
            return
        if self._ready is not None:
            # the tick and its pass, then again while a message waits (one that came during
            # the pass): the descriptor is not to be trusted for it (a frame left there
            # until the next one came, seen at 4 cameras x 60 Hz), as wait_input asks too.
            # A few rounds, then the loop's next turn (timers, commands) before more
            for _ in range(_ROUNDS):
                self._ready()
                if not self._out.get(_EVENTS) & _POLLIN:
                    return
            if self._fd_loop is not None:
                self._fd_loop.call_soon(self._fd_ready)
            return
        w = self._waiter
        if w is not None and not w.done():
            w.set_result(None)

    async def teardown(self) -> None:
        self._ready = None
        self._unwatch_fd()

    def step(self) -> None:
        # drain what is there through the plain socket (no future per message), at most what
        # the smallest ingest topic holds less what is on it unread (the ticks since a held
        # pass): the pass after this tick takes the lot through the pipeline before the next
        # drain, so a burst is never overwritten on the bus unread.
        # Called when a message waits: ``zmq.EVENTS`` after each message (each asks libzmq
        # to take its commands: a system call), not before; not a recv until ``zmq.Again``
        # (the same system call and an exception). Either re-arms the edge-triggered
        # descriptor. Plain ints for the flags: an int & zmq.POLLIN builds an enum member.
        # A message's parts as recv_multipart's bytes, but each part's ``more`` read from the
        # part itself (recv_multipart asks the socket for ZMQ_RCVMORE after each part: a
        # ``get``, which looks the option up in an enum: ~0.8 us a message of two parts)
        out = self._out
        recv, get = out.recv, out.get
        if not self._holding:
            self._unpassed = 0
        self._fed = self._urgent = False
        limit = min(self.vision_packets.capacity, self.referee_packets.capacity,
                    self.feedback_packets.capacity) - self._unpassed
        handle = self._handle
        for _ in range(limit):
            try:
                part = recv(_NOBLOCK, copy=False)
            except zmq.Again:
                return
            frames = [part.bytes]
            while part.more:
                part = recv(_NOBLOCK, copy=False)
                frames.append(part.bytes)
            self._unpassed += 1
            handle(frames)
            if not get(_EVENTS) & _POLLIN:
                return
        if self._ready is not None and self._fd_loop is not None:
            # more than a topic holds: the rest after this pass, in the loop's next turn
            # (the descriptor will not signal what is already there)
            self._fd_loop.call_soon(self._fd_ready)

    def hold_pass(self) -> float | None:
        """Holds the pass for the rest of a burst under way (its cameras' frames came in
        bursts of more than this one has so far, most of the last times): seconds until
        ``burst_wait_ns`` after the newest frame's arrival at the relay, or half of it from
        now when this thread is that far behind the relay. The relay forwards a burst's
        frames one by one, tens of microseconds to milliseconds apart, and a pass takes
        longer than that: without the hold the first frame or two got a pass of their own,
        the rest a second one. The runner does not block on it (timers, the other
        processors, a stop run meanwhile); the pass runs once the burst is whole (this tick
        answers None), or at that time. None (the pass now): a burst of one (cameras with
        phases of their own never hold), a whole one, a referee packet in this tick, no
        camera frame in it and none held, or the smallest ingest topic full of unread
        messages."""
        if (self._urgent or not (self._fed or self._holding)
                or self._burst_n >= self.burst_expected
                or self._unpassed >= min(self.vision_packets.capacity,
                                         self.referee_packets.capacity,
                                         self.feedback_packets.capacity)):
            self._holding = False
            return None
        now = self.clock_ns()
        wait = self.burst_wait_ns
        # from the newest frame's arrival at the relay or, if that is longer ago (this thread
        # woke late: the relay has forwarded the burst's frames before the rest came here),
        # from now; never longer than the wait from now
        until = max(min(self._burst_last, now), now - wait // 2) + wait
        self._holding = True
        self.held += 1
        return (until - now) / 1e9

    def held_pass_ran(self) -> None:
        self._holding = False

    def _parse(self, msg: Message, body: bytes, what: str) -> str | None:
        """Parses ``body`` into ``msg``: None, or the parser's words, counted under the reason
        ``wire_problem`` names. (Not ``streams.parse_message``: these messages are proto3,
        with no required field to check, and every camera frame comes through here.)"""
        try:
            msg.ParseFromString(body)
        except DecodeError as exc:
            self._zmq.error(streams.wire_problem(body), f"{what}: {exc}")
            return str(exc)
        return None

    def _handle(self, frames: list[bytes]) -> None:
        c = self._zmq
        c.rate.add()
        if len(frames) != 2:
            c.error("bad frames", f"expected 2 frames, got {len(frames)}")
            badlog.warning("zmq-frames", "relay message with %d frames ignored", len(frames))
            return
        topic, body = frames
        if topic == b"stats":
            stats = tl.RelayStats()
            if self._parse(stats, body, "stats") is None:
                self.relay_stats.write(_relay_stats_dict(stats))
            return
        if topic == b"feedback":
            fb = tl.RobotFeedbackEnvelope()
            why = self._parse(fb, body, "feedback")
            if why is not None:
                badlog.warning("zmq-feedback", "undecodable feedback envelope: %s", why)
            elif self.live():  # in replay nothing is sent to robots: nothing answers for it
                self.feedback_packets.write(fb)
            return
        env = tl.Envelope()
        why = self._parse(env, body, "envelope")
        if why is not None:
            badlog.warning("zmq-envelope", "undecodable envelope on %r: %s", topic, why)
            return
        if topic == b"vision":
            t = env.receive_time_ns
            self.record(t, TYPE_VISION_2014, env.payload)
            if self.live():
                self.vision_packets.write(env)
                self._fed = True
                self._burst(t, capture_ns(env.payload))
        elif topic == b"referee":
            self._urgent = True
            self.record(env.receive_time_ns, TYPE_REFEREE_2013, env.payload)
            if self.live():
                self.referee_packets.write(env)

    def _burst(self, t: int, capture: int | None) -> None:
        """Counts a vision frame (relay stamp ``t``, capture time ``capture``) into its burst."""
        before = self._burst_capture
        if (abs(capture - before) <= BURST_GAP_NS if capture is not None and before is not None
                else capture is None and before is None and t - self._burst_last <= BURST_GAP_NS):
            self._burst_n += 1
            gaps = self._burst_gaps
            gaps.append(t - self._burst_last)
            if len(gaps) >= BURST_GAPS:
                gaps.sort()
                self.burst_wait_ns = min(max(gaps[len(gaps) * 95 // 100], BURST_GAP_NS),
                                         BURST_WAIT_MAX_NS)
                gaps.clear()
        else:  # a new burst: the one before is whole
            if self._burst_n:
                sizes = self._burst_sizes
                sizes.append(self._burst_n)
                best, times = 0, 1  # the most common size, seen twice, the smaller on a tie
                for size in set(sizes):
                    k = sizes.count(size)
                    if k > times or (k == times and size < best):
                        best, times = size, k
                self.burst_expected = best
            self._burst_n = 1
        self._burst_last, self._burst_capture = t, capture


def _relay_stats_dict(s: tl.RelayStats) -> dict[str, Any]:
    return {
        "time_ns": s.time_ns,
        "received_mono": time.monotonic(),
        "output_mode": s.output_mode,
        "active_robots": s.active_robots,
        "stale_robots": s.stale_robots,
        "output_rate_hz": s.output_rate_hz,
        "command_latency_ms": s.command_latency_ms,
        "command_latency_p50_ms": s.command_latency_p50_ms,
        "command_latency_p99_ms": s.command_latency_p99_ms,
        "stale_stops": s.stale_stops,
        "estop_latched": s.estop_latched,
        "estop_by": s.estop_by,
        "armed": s.armed,
        "arming_required": s.arming_required,
        "cpu_percent": s.cpu_percent,
        "rss_mb": s.rss_mb,
        "streams": {
            st.name: {
                "packets": st.packets,
                "errors": st.errors,
                "rate_hz": st.rate_hz,
                "last_age_s": st.last_age_s,
                "last_error": st.last_error,
                "errors_by_reason": dict(sorted(st.errors_by_reason.items())),
            }
            for st in s.streams
        },
    }
