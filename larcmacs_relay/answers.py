"""What the simulator and the robots answer: the SSL simulation protocol's
RobotControlResponse (on the output socket) and grSim's Robots_Status (on its own ports),
each checked, counted and forwarded unchanged on the PUB's "feedback" topic with what had
been sent to that team's robots, a simulator's repeated answers coalesced (the rule:
feedback.py).

While the output cycles run, the cycles read the simulator's answers (``_watch_responses``):
a loop wake-up per answer cost more than the answer.
"""

from __future__ import annotations

import asyncio
import logging
import socket
import sys
import time

from larcmacs_relay import codecs
from larcmacs_relay.feedback import FeedbackGate, HeldAnswer, SentLog, sent_items
from larcmacs_relay.part import MAX_BATCH, MAX_DATAGRAM, RelayPart
from sslnet import streams
from sslnet.kerneltime import enable_kernel_timestamps, kernel_time_ns
from sslnet.multicast import open_udp_server
from sslpb import touchline_pb2

log = logging.getLogger("larcmacs_relay")


class Answers(RelayPart):
    """The simulator's answers and grSim's robot status, onto the PUB as feedback."""

    #: the feedback forwarding rule per (kind, team) (feedback.py) and each one's timer for
    #: a held answer
    _gates: dict[tuple[int, int], FeedbackGate]
    _gate_timers: dict[FeedbackGate, asyncio.TimerHandle]
    #: the simulator's answer streams by the port they come from (blue's port first: the
    #: same port for both is blue's, as it was), each one's gate once it has answered
    _sim_teams: dict[int, int]
    _sim_gates: dict[int, FeedbackGate]
    #: the simulator's answers arrive on ``_udp_out``; True while the loop watches it (the
    #: output idle), False while the output cycles read it (see _watch_responses)
    _responses_watched: bool
    #: grsim output: the bound Robots_Status ports {"blue": port, "yellow": port}
    grsim_status_ports: dict[str, int]

    def _setup_answers(self) -> None:
        cfg = self.config
        self._gates = {}
        self._gate_timers = {}
        self._sim_teams = {cfg.sim_yellow_port: codecs.TEAM_YELLOW,
                           cfg.sim_blue_port: codecs.TEAM_BLUE}
        self._sim_gates = {}
        self._responses_watched = False
        self._stamped = False
        self.grsim_status_ports = {}
        #: per team: commands sent to each robot and the wall clock (ns) of the last one,
        #: forwarded with every answer (the backend's round trip and losses)
        self._sent = {t: SentLog() for t in codecs.TEAMS}

    def _open_answers(self, loop: asyncio.AbstractEventLoop, udp: list[socket.socket]) -> None:
        """sim: the answers on the output socket, stamped by the kernel; grsim: the robot
        status ports."""
        cfg = self.config
        if cfg.output == "sim" and self._udp_out is not None:
            self._stamped = _stamp_arrivals(self._udp_out)
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

    def _close_answers(self) -> None:
        for timer in self._gate_timers.values():
            timer.cancel()
        self._gate_timers.clear()

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
