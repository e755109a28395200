"""What robots and simulators answer, per robot (pure: no sockets, no clock; times are
arguments).

``decode(env)`` turns one ``RobotFeedbackEnvelope`` from the relay (a ``RobotControlResponse``
of the SSL simulation protocol, or a grSim ``Robots_Status``) into one ``Answer`` per robot,
or the reason it is refused (``sslnet.streams`` reasons); ``Decoder`` does the same but parses
a payload only when it differs from the last one of its stream (the relay forwards a
simulator's repeated answers coalesced: larcmacs_relay/feedback.py). ``FeedbackTracker`` keeps
per robot: ball contact (``dribbler_ball_contact`` or grSim's infrared), the last kick
(grSim's flat / chip flags) and when, the time of the last answer, and for the transport that
answers every command (the simulation protocol) the round trip (the relay's last send -> the
answer's arrival at the relay, one sample per envelope) and the losses (commands sent vs
answers over the last ``LOSS_WINDOW_S``; an envelope stands for as many answers, all with its
bytes, as its ``sequence`` advanced since the previous envelope of its stream). A robot the
station commands that has not answered for ``NO_ANSWER_S`` is marked ``no_answer``. Battery
and kicker voltages are a hook for real robots: they stay None until a transport fills them.
"""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass, field
from typing import Literal

from sslnet import streams
from sslpb import grsim_robot_status_pb2 as grsim_status_pb
from sslpb import ssl_simulation_robot_feedback_pb2 as fb_pb
from sslpb import touchline_pb2 as tl

from .state import Team

Transport = Literal["sim", "grsim"]
KickKind = Literal["flat", "chip"]

#: a commanded robot without an answer for longer than this is marked no_answer
NO_ANSWER_S = 0.5
#: the window of the losses (commands sent vs answers)
LOSS_WINDOW_S = 2.0
#: round trips averaged
RTT_SAMPLES = 20


@dataclass(frozen=True, slots=True)
class Answer:
    """One robot in one answer datagram."""

    id: int
    ball_contact: bool | None = None  # None: the answer does not say
    kick: KickKind | None = None  # a kick reported in this answer
    battery_v: float | None = None  # hooks for real robots' telemetry
    kicker_v: float | None = None


@dataclass(frozen=True, slots=True)
class Decoded:
    team: Team
    transport: Transport
    answers: tuple[Answer, ...]


def _team(value: int) -> Team | None:
    return "blue" if value == tl.TEAM_BLUE else "yellow" if value == tl.TEAM_YELLOW else None


def decode(env: tl.RobotFeedbackEnvelope) -> Decoded | tuple[str, str]:
    """The robots in ``env``'s payload, or (reason, detail) when it is refused."""
    team = _team(env.team)
    if team is None:
        return streams.OTHER, f"feedback for team {env.team}"
    if env.kind == tl.FEEDBACK_SIM_RESPONSE:
        resp = fb_pb.RobotControlResponse()
        why = streams.parse_message(resp, env.payload)
        if why is not None:
            return why
        return Decoded(team, "sim", tuple(
            Answer(f.id, f.dribbler_ball_contact if f.HasField("dribbler_ball_contact")
                   else None)
            for f in resp.feedback))
    if env.kind == tl.FEEDBACK_GRSIM_STATUS:
        status = grsim_status_pb.Robots_Status()
        why = streams.parse_message(status, env.payload)
        if why is not None:
            return why
        answers: list[Answer] = []
        for s in status.robots_status:
            if s.robot_id < 0:
                return streams.OTHER, f"robot id {s.robot_id}"
            kick: KickKind | None = "chip" if s.chip_kick else "flat" if s.flat_kick else None
            answers.append(Answer(s.robot_id, s.infrared, kick))
        return Decoded(team, "grsim", tuple(answers))
    return streams.OTHER, f"feedback of kind {env.kind}"


class Decoder:
    """``decode`` with a memory per answer stream (kind, team): a payload with the same bytes
    as the last one decoded is not parsed again (its ``Decoded`` is immutable: the same
    one is returned)."""

    def __init__(self) -> None:
        self._last: dict[tuple[int, int], tuple[bytes, Decoded]] = {}

    def clear(self) -> None:
        self._last.clear()

    def __call__(self, env: tl.RobotFeedbackEnvelope) -> Decoded | tuple[str, str]:
        key = (env.kind, env.team)
        payload = env.payload
        last = self._last.get(key)
        if last is not None and last[0] == payload:
            return last[1]
        dec = decode(env)
        if not isinstance(dec, tuple):
            self._last[key] = (payload, dec)
        return dec


@dataclass
class RobotFeedbackState:
    """One robot's feedback; times are the tracker's clock (monotonic s)."""

    team: Team
    id: int
    transport: Transport
    ball_contact: bool = False
    #: whether its answers carry ball contact at all (robot-box answers may not)
    reports_contact: bool = False
    last_answer: float | None = None
    last_kick: KickKind | None = None
    last_kick_time: float | None = None
    round_trips_ms: deque[float] = field(default_factory=lambda: deque(maxlen=RTT_SAMPLES))
    #: (time, commands sent so far, answers so far), for the losses over the window
    counts: deque[tuple[float, int, int]] = field(default_factory=deque)
    sent_total: int = 0
    answers_total: int = 0
    battery_v: float | None = None
    kicker_v: float | None = None


@dataclass(frozen=True, slots=True)
class RobotFeedbackView:
    """What the page and the strategy read of one robot's feedback."""

    transport: Transport
    ball_contact: bool
    age_s: float | None  # since the last answer
    no_answer: bool
    last_kick: KickKind | None
    last_kick_age_s: float | None
    round_trip_ms: float | None
    commands_sent: int | None  # over the last LOSS_WINDOW_S (transports answering each one)
    answers: int | None
    loss: float | None  # 1 - answers / commands sent
    battery_v: float | None
    kicker_v: float | None
    #: its answers carry ball contact (else ``ball_contact`` False means "not said")
    reports_contact: bool = False

    def contact(self, max_age_s: float) -> bool | None:
        """Ball contact as the robot reports it now; None when it does not say (no contact
        in its answers, no answer lately): the strategy then judges from the positions."""
        if not self.reports_contact or self.no_answer or self.age_s is None \
                or self.age_s > max_age_s:
            return None
        return self.ball_contact


class FeedbackTracker:
    """Per robot feedback from decoded answers; ``view`` says what it means now."""

    def __init__(self) -> None:
        self.robots: dict[tuple[Team, int], RobotFeedbackState] = {}
        #: teams whose transport answers every command (simulation protocol)
        self.answering: set[Team] = set()
        #: the station's last command per robot (tracker clock)
        self.commanded: dict[tuple[Team, int], float] = {}
        #: the last envelope's sequence per answer stream (kind, team)
        self.sequences: dict[tuple[int, int], int] = {}

    def clear(self) -> None:
        self.robots.clear()
        self.answering.clear()
        self.commanded.clear()
        self.sequences.clear()

    def _answers_in(self, env: tl.RobotFeedbackEnvelope) -> int:
        """How many answers ``env`` stands for: the relay forwards a run of answers with the
        same bytes as one envelope, and its ``sequence`` counts every answer of the stream;
        1 without a previous sequence, or when it did not advance (a restarted relay)."""
        key = (env.kind, env.team)
        seq = env.sequence
        last = self.sequences.get(key)
        self.sequences[key] = seq
        return seq - last if last is not None and seq > last else 1

    def command(self, team: Team, rid: int, now: float) -> None:
        """The station commanded this robot at ``now``."""
        self.commanded[(team, rid)] = now

    def _state(self, team: Team, rid: int, transport: Transport) -> RobotFeedbackState:
        st = self.robots.get((team, rid))
        if st is None or st.transport != transport:
            st = RobotFeedbackState(team, rid, transport)
            self.robots[(team, rid)] = st
        return st

    def update(self, env: tl.RobotFeedbackEnvelope, dec: Decoded, now: float) -> None:
        """One decoded answer (``dec`` from ``decode(env)``) that arrived at ``now``."""
        team = dec.team
        answered: set[int] = set()
        for a in dec.answers:
            st = self._state(team, a.id, dec.transport)
            answered.add(a.id)
            st.last_answer = now
            if a.ball_contact is not None:
                st.ball_contact = a.ball_contact
                st.reports_contact = True
            if a.kick is not None:
                st.last_kick, st.last_kick_time = a.kick, now
            if a.battery_v is not None:
                st.battery_v = a.battery_v
            if a.kicker_v is not None:
                st.kicker_v = a.kicker_v
        if dec.transport != "sim":
            return
        self.answering.add(team)
        n = self._answers_in(env)
        # every robot sent to, in every answer (several hundred a second): each protobuf
        # field read once, the window's start computed once
        robots = self.robots
        received = env.receive_time_ns
        window_start = now - LOSS_WINDOW_S
        for s in env.sent:
            rid = s.id
            got = robots.get((team, rid))
            st = got if got is not None and got.transport == "sim" else \
                self._state(team, rid, "sim")
            st.sent_total = s.commands_sent
            if rid in answered:
                st.answers_total += n
                last_sent = s.last_sent_time_ns
                if last_sent > 0 and received >= last_sent:
                    st.round_trips_ms.append((received - last_sent) / 1e6)
            counts = st.counts
            counts.append((now, st.sent_total, st.answers_total))
            while len(counts) > 1 and counts[1][0] <= window_start:
                counts.popleft()

    def view(self, team: Team, rid: int, now: float) -> RobotFeedbackView | None:
        st = self.robots.get((team, rid))
        if st is None:
            return None
        age = None if st.last_answer is None else now - st.last_answer
        cmd = self.commanded.get((team, rid))
        commanded = cmd is not None and now - cmd <= NO_ANSWER_S
        no_answer = (st.transport == "sim" and team in self.answering and commanded
                     and (age is None or age > NO_ANSWER_S))
        sent = answers = None
        loss = None
        if st.transport == "sim" and len(st.counts) >= 2:
            _, s0, a0 = st.counts[0]
            _, s1, a1 = st.counts[-1]
            sent, answers = s1 - s0, a1 - a0
            loss = min(1.0, max(0.0, 1.0 - answers / sent)) if sent > 0 else None
        rtt = (sum(st.round_trips_ms) / len(st.round_trips_ms)) if st.round_trips_ms else None
        return RobotFeedbackView(
            transport=st.transport,
            ball_contact=st.ball_contact and not no_answer,
            age_s=age,
            no_answer=no_answer,
            last_kick=st.last_kick,
            last_kick_age_s=None if st.last_kick_time is None else now - st.last_kick_time,
            round_trip_ms=rtt,
            commands_sent=sent,
            answers=answers,
            loss=loss,
            battery_v=st.battery_v,
            kicker_v=st.kicker_v,
            reports_contact=st.reports_contact,
        )

    def views(self, now: float) -> dict[tuple[Team, int], RobotFeedbackView]:
        out: dict[tuple[Team, int], RobotFeedbackView] = {}
        for key in self.robots:
            v = self.view(key[0], key[1], now)
            if v is not None:
                out[key] = v
        return out
