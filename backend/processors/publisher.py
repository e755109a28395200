"""The command publisher: command sets, simulator commands and the e-stop to the relay."""

from __future__ import annotations

import time
from collections.abc import Callable, Mapping

import zmq
import zmq.asyncio

from ssllog.format import TYPE_TL_COMMANDS
from sslnet.rate import CountRate
from sslpb import touchline_pb2 as tl

from .. import topics
from ..bus import DataBus, Reader
from ..contract import FRAME_AGE_STAGE as FRAME_AGE_STAGE  # the stage of ``frame_age``
from ..messages import Command, CommandSet
from ..processor import OnTopic
from ..world.state import Team
from .common import LatencyStage, SocketProcessor

_CommandSet = tl.RobotCommandSet
_BLUE, _YELLOW = tl.TEAM_BLUE, tl.TEAM_YELLOW


def encode_command_set(cs: CommandSet, seq: int) -> tl.RobotCommandSet:
    """A command set as the relay gets it (and the recorder keeps it: TYPE_TL_COMMANDS)."""
    msg = _CommandSet(
        created_time_ns=cs.created_time_ns,
        source_receive_time_ns=cs.source_receive_time_ns,
        sequence=seq,
        stop_all=cs.stop_all,
    )
    add = msg.commands.add
    # each Command (and its LocalVelocity) unpacked as the tuple it is, in its fields'
    # order: one step instead of a read by name per field
    for team, rid, (fwd, left, ang), kick, chip, drib in cs.commands:
        m = add()  # fields set one by one: cheaper than add(**fields)
        m.team = _BLUE if team == "blue" else _YELLOW
        m.id = rid
        m.forward_mps = fwd
        m.left_mps = left
        m.angular_radps = ang
        m.kick_speed_mps = kick
        m.chip = chip
        m.dribbler_rpm = drib
    return msg


class CommandPublisher(SocketProcessor):
    """Sends each command set and simulator command to the relay."""

    name = "command-publisher"

    def __init__(self, bus: DataBus, sock: zmq.asyncio.Socket | None = None) -> None:
        cmds = bus.of(topics.ROBOT_COMMANDS)
        super().__init__(OnTopic(cmds, max_wait_s=0.05))
        if sock is not None:
            self.attach(sock)
        self.reader = Reader(cmds)
        self.sim_reader = Reader(bus.of(topics.SIM_COMMANDS))
        self.referee_out_reader = Reader(bus.of(topics.REFEREE_OUT))
        self.seq = 0
        self.latency = LatencyStage()  # relay arrival -> command set sent to the relay
        #: what each robot experiences: for every robot command of a set computed from vision,
        #: the age of the newest frame that saw that robot when the set is sent (``latency``
        #: takes the world's newest frame, one per set: a robot seen in an older frame, or
        #: commanded again for a new target, waited longer). Its frames' arrivals: the world
        #: processor's ``arrivals`` (the station shares them; empty: nothing measured)
        self.frame_age = LatencyStage(maxlen=2000)
        self.arrivals: Mapping[tuple[Team, int], int] = {}
        self.world = bus.of(topics.WORLD)
        self.sent = CountRate()  # command sets sent (a count; its rate when read)
        self.estop = bus.of(topics.ESTOP)
        self.relay_stats = bus.of(topics.RELAY_STATS)
        #: called when the relay reports a latch this backend does not have
        self.adopt_estop: Callable[[str], None] = lambda by: None
        self.estop_by: Callable[[], str] = lambda: ""
        self._estop_sent = (False, -1e9)  # (active, monotonic time) of the last latch message
        self._release_until = -1e9  # a release is being repeated until the relay confirms
        #: the station's arming (a relay with --require-arming obeys it; others ignore it)
        self.armed: Callable[[], bool] = lambda: False
        self.armed_by: Callable[[], str] = lambda: ""
        self._arming_sent = (False, -1e9)  # (armed, monotonic time) of the last Arming sent
        #: True while a log is replayed: nothing goes to robots or a simulator (the strategy
        #: and controllers may run on the replay; their commands are shown, never sent)
        self.muted: Callable[[], bool] = lambda: False
        #: every command set sent (the session recorder)
        self.record: Callable[[int, int, bytes], None] = lambda t, k, b: None
        self._was_muted = False
        #: called once, after the first command set for robots went to the relay (the
        #: station starts what the first command does not need)
        self.on_first_command: Callable[[], None] | None = None

    def step(self) -> None:
        if self.muted():
            self.reader.read_new()
            self.sim_reader.read_new()
            self.referee_out_reader.read_new()
            if not self._was_muted:  # into replay: every live robot stops now, not 0.1 s later
                self._was_muted = True
                stop = tl.RobotCommandSet(created_time_ns=time.time_ns(), stop_all=True)
                self.send([b"commands", stop.SerializeToString()])
            now = time.monotonic()
            self._estop_latch(now)
            self._arming(now)
            return
        self._was_muted = False
        for cs in self.reader.read_new():
            self.seq += 1
            raw = encode_command_set(cs, self.seq).SerializeToString()
            self.send([b"commands", raw])
            now_ns = time.time_ns()
            self.record(now_ns, TYPE_TL_COMMANDS, raw)
            self.sent.total += 1
            self.latency.add_at(now_ns, cs.source_receive_time_ns)
            if cs.source_receive_time_ns > 0 and self.arrivals:  # (not a stop's set)
                self._frame_ages(now_ns, cs.commands)
            if self.on_first_command is not None and (cs.commands or cs.stop_all):
                hook, self.on_first_command = self.on_first_command, None
                hook()
        for raw in self.sim_reader.read_new():
            self.send([b"sim", raw])
        for raw in self.referee_out_reader.read_new():
            self.send([b"referee-out", raw])
        now = time.monotonic()
        self._estop_latch(now)
        self._arming(now)

    def _frame_ages(self, now_ns: int, commands: tuple[Command, ...]) -> None:
        """Each seen robot's newest frame's age at ``now_ns`` (a robot not seen gets zero:
        no frame is behind its command)."""
        rec = self.world.latest()
        if rec is None:
            return
        robot, arrivals = rec.value.robot, self.arrivals
        add = self.frame_age.samples.append
        for c in commands:
            r = robot(c[0], c[1])
            if r is not None and r.visible:
                arrived = arrivals.get((c[0], c[1]))
                if arrived is not None:
                    add((now_ns - arrived) / 1e6)

    def _arming(self, now: float) -> None:
        """The arming state to the relay on every change and every 0.5 s (a restarted relay
        starts disarmed and is re-armed only if this backend is armed)."""
        armed = self.armed()
        was, when = self._arming_sent
        if armed != was or now - when >= 0.5:
            msg = tl.Arming(armed=armed, time_ns=time.time_ns(), by=self.armed_by())
            self.send([b"arming", msg.SerializeToString()])
            self._arming_sent = (armed, now)

    def _estop_latch(self, now: float) -> None:
        """Keeps the relay's latch in step: PRESS on a press and every 0.5 s while active
        (a relay that restarts, or a slow ZeroMQ join, gets it again); RELEASE only after an
        operator's release, repeated until the relay's stats say it is released (3 s at
        most). A latch the relay reports and this backend does not have is adopted."""
        active = bool(self.estop.latest_value())
        was, when = self._estop_sent
        if active and (not was or now - when >= 0.5):
            self._send_estop(tl.EmergencyStop.PRESS)
            self._estop_sent = (True, now)
            self._release_until = -1e9
            return
        if not active and was:  # the operator released it
            self._send_estop(tl.EmergencyStop.RELEASE)
            self._estop_sent = (False, now)
            self._release_until = now + 3.0
            return
        rs = self.relay_stats.latest_value()
        if active or rs is None or not rs.get("estop_latched"):
            return
        if now < self._release_until:  # not confirmed yet: say it again
            if now - when >= 0.1:
                self._send_estop(tl.EmergencyStop.RELEASE)
                self._estop_sent = (False, now)
        elif now - rs["received_mono"] < 1.5:  # fresh stats: the relay holds a latch we lack
            self.adopt_estop(str(rs.get("estop_by", "")))

    def _send_estop(self, action: int) -> None:
        msg = tl.EmergencyStop(action=action, time_ns=time.time_ns(),  # type: ignore[arg-type]
                               by=self.estop_by())
        self.send([b"estop", msg.SerializeToString()])

    def latency_summary(self) -> dict[str, float]:
        return self.latency.summary()
