"""The command cycle: when the commands due go out, and on which output.

A new command set kicks a cycle at once (no sooner than ``min_gap_s`` after the last one);
while anything is due the cycles repeat at ``output_rate_hz`` on one timer, and with nothing
due (every robot idle) there is no timer at all. What is due is the command table's
(commands.py): a robot's command while it is fresh, then **the stale stop** (zero velocity
once a command is older than ``command_timeout_s``, for ``hold_time_s``), then nothing.
``output_cycle`` sends only zeros while the e-stop is latched or the relay is disarmed
(safety.py). ``_send_commands`` encodes by the configured output protocol: sim_protocol.py,
grsim.py, robot_box.py.
"""

from __future__ import annotations

import asyncio
import logging
import math
import socket
import time

from larcmacs_relay.codecs import Command
from larcmacs_relay.part import Planned, RelayPart

log = logging.getLogger("larcmacs_relay")



class CommandCycle(RelayPart):
    """The output schedule, the cycle and the send of what is due."""

    #: the output schedule (see _kick_output): the last cycle, the next one due (inf: every
    #: robot idle, nothing to send, no wake-up), and the one timer armed for it
    _last_cycle: float
    _next_cycle: float
    _period: float
    _timer: asyncio.TimerHandle | None
    #: the sim output of the table's version ``_plan_version`` (every team's datagram,
    #: its address and robots): while the table is unchanged a cycle only sends it
    _plan: list[Planned]
    _plan_version: int

    def _setup_cycle(self) -> None:
        self._last_cycle = -math.inf
        self._next_cycle = math.inf
        self._period = 1.0 / self.config.output_rate_hz
        self._timer = None
        self._plan = []
        self._plan_version = -1
        self._udp_out = None
        self._sim_host = self.config.sim_host

    def _open_output(self, udp: list[socket.socket]) -> None:
        """The one UDP socket every command leaves from."""
        cfg = self.config
        # Resolve output hosts once: sendto() with a name would resolve on every datagram.
        self._sim_host = socket.gethostbyname(cfg.sim_host)
        self._box_host = socket.gethostbyname(cfg.robot_box_host)
        out = socket.socket(socket.AF_INET, socket.SOCK_DGRAM, socket.IPPROTO_UDP)
        out.setblocking(False)
        udp.append(out)
        self._udp_out = out

    def _close_cycle(self) -> None:
        if self._timer is not None:
            self._timer.cancel()
            self._timer = None

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
            self._send_robot_box(due)
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
