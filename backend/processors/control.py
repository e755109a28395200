"""The control processor: the speed controllers, the rules and every safety stop."""

from __future__ import annotations

import logging
import math
import time
from collections.abc import Callable, Mapping
from typing import Any

from domain.rules import kick_allowed
from sslnet.ratelog import RateLimitedLog

from .. import topics
from ..bus import DataBus
from ..control.follow import next_waypoint
from ..control.goto import LocalVelocity
from ..control.motion import PHASE_NAMES, MotionBank, RobotMotionState
from ..control.params import ALGORITHMS, ControlSettings
from ..control.referee_limits import capped, command_cap_mps
from ..messages import Command, CommandSet, TargetEntry
from ..params.model import StationParams
from ..processor import OnTopic, Processor
from ..world.referee import RefereeState
from ..world.silence import MIN_S as LOST_MIN_S
from ..world.silence import CameraSilence, Lost
from ..world.state import RobotState, Team, WorldState
from .common import log
from .internal_referee import InternalRefereeProcessor


class ControlProcessor(Processor):
    """Turns targets into robot commands on every world update with each robot's chosen
    controller (the paper's Algorithm 1 or 2, or the proportional baseline), then the safety
    rules: emergency stop and HALT zero every robot; every camera silent (``CameraSilence``:
    6 frame periods, at most 0.1 s, at >= 30 Hz) or a stale world zeroes every robot, a robot
    not seen gets zero; STOP and the other team's ball placement cap the speed.

    A command set carries the robots with something new (a camera saw the robot, its target
    or the referee command changed, or ``refresh_s`` passed): one camera of eight sees a few
    robots, and the relay keeps and repeats every robot's latest command. Every stop above
    still zeroes every robot in one set, and a robot not seen is zeroed in every tick."""

    name = "control"

    def __init__(self, bus: DataBus, max_wait_s: float, vision_stale_s: float,
                 settings: ControlSettings | None = None,
                 clock: Callable[[], float] = time.monotonic) -> None:
        world = bus.of(topics.WORLD)
        super().__init__(OnTopic(world, max_wait_s=max_wait_s))
        self.world = world
        self.targets = bus.of(topics.TARGETS)
        self.referee = bus.of(topics.REFEREE)
        self.estop = bus.of(topics.ESTOP)
        self.commands = bus.of(topics.ROBOT_COMMANDS)
        self.vision_stale_s = vision_stale_s
        self.strategy_stale_s = 0.5  # no targets for this long: the strategy is stuck, stop
        self.stop_speed_mps = 1.5
        self.our_team: Team = "blue"
        self.motion = MotionBank(settings or ControlSettings())
        self.last_commands: dict[tuple[Team, int], Command] = {}
        self._telemetry_cache: dict[str, dict[str, Any]] | None = {}
        #: a robot is stepped again when its world state (the world model reuses a robot's
        #: state object until a camera sees it again) or its target changed, when the
        #: referee command changed, or after ``refresh_s`` without a step; in between the
        #: relay repeats its last command. Per robot: the (state, target, monotonic time) of
        #: its last command while it is seen, and the monotonic time of its last step seen or
        #: not (its controller's dt)
        self.refresh_s = 0.02
        self._basis: dict[tuple[Team, int], tuple[RobotState, TargetEntry, float]] = {}
        self._step_t: dict[tuple[Team, int], float] = {}
        self._command: str | None = None
        self._keys: list[tuple[Team, int]] = []
        #: the robots to command, sorted, and what from (the targets' sequence number, our
        #: team, whether the other team may be driven)
        self._sorted_keys: list[tuple[Team, int]] = []
        self._keys_of: tuple[int, str, bool] | None = None
        self._indexed: WorldState | None = None
        self._index: Mapping[tuple[Team, int], int] = {}  # its robots' places by key
        self.internal: InternalRefereeProcessor | None = None
        #: whether commands for the other team may go out (the station says: a simulator
        #: output and the operator's safety.other_team_in_simulator); else they never do
        self.may_drive_other_team: Callable[[], bool] = lambda: False
        #: monotonic seconds (a virtual clock headless: evaluate/); the bus's records carry the
        #: same clock's times
        self.clock = clock
        self._last_tick = clock()
        self.halt_reason = ""
        #: why the robots are held now ("" while driving), for the log line of each change
        self._held = ""
        self._held_since = 0.0
        self._holdlog = RateLimitedLog(log, interval_s=10.0)
        #: in replay, the log's time at the playhead (Unix ns): vision is as old as the log
        #: says, whatever the speed and also while paused
        self.replay_clock: Callable[[], int] | None = None
        #: the receive clock live (the relay stamps arrivals with this machine's wall clock)
        self.clock_ns: Callable[[], int] = time.time_ns
        #: every camera's frames by the receive clock (the world processor's, fed with every
        #: detection frame; None: only the vision_stale_s rule)
        self.silence: CameraSilence | None = None
        #: every camera silent past its time (in the last tick), else None
        self.vision_lost: Lost | None = None

    def active_referee(self) -> RefereeState | None:
        """The referee the robots obey: the newest state, except the internal referee's own
        once the operator switched it off (then there is no referee until one is heard)."""
        ref = self.referee.latest_value()
        ir = self.internal
        if (ref is not None and ir is not None and not ir.enabled
                and ref.source_identifier == ir.referee.source_identifier):
            return None
        return ref

    def vision_age_s(self, now_mono: float) -> float:
        """How old the robots' view of the world is: since the world was last written, and
        since the relay received the newest frame merged into it (this machine's clock; a
        world written again and again from nothing new is as stale as one not written)."""
        rec = self.world.latest()
        if rec is None:
            return math.inf
        recv_ns = rec.value.receive_time_ns
        if self.replay_clock is not None:
            return (self.replay_clock() - recv_ns) / 1e9 if recv_ns > 0 else math.inf
        age = now_mono - rec.time_mono
        if recv_ns > 0:
            age = max(age, (self.clock_ns() - recv_ns) / 1e9)
        return age

    def receive_now_ns(self) -> int:
        """Now on the clock vision is judged by: the wall clock live, the log's time at the
        playhead in replay (a paused or stepped replay is not silence)."""
        return self.replay_clock() if self.replay_clock is not None else self.clock_ns()

    def _lost(self, vision_age: float) -> Lost | None:
        # (only once the world is LOST_MIN_S old: no camera is past its time sooner, and a
        # tick on every frame asks nothing)
        if self.silence is None or not vision_age >= LOST_MIN_S:
            return None
        return self.silence.lost(self.receive_now_ns())

    #: the runner asks ``wake_in_s`` again at least this often: a deadline that a frame set
    #: is never sooner than LOST_MIN_S after it (the nap never oversleeps it)
    wake_check_s = LOST_MIN_S

    def wake_in_s(self) -> float | None:
        """Seconds until every camera counts as silent, so the runner runs this tick then
        and not at its next max wait (up to 50 ms later); None when nothing is due (the rule
        does not hold, the vision is already lost, or a replay: nothing is sent)."""
        if self.replay_clock is not None or self.silence is None or self.vision_lost:
            return None
        d = self.silence.deadline_ns()
        if d is None:
            return None
        return max(0.0, (d - self.clock_ns()) / 1e9)

    def _hold_changed(self, held: str, now: float) -> None:
        """One log line when the robots are stopped for a new reason and when they are
        driven again (a vision PC that died and came back is in the log, not only on the
        page), rate-limited per reason (a flickering camera does not flood it); HALT is the
        referee's and goes in at INFO."""
        before, since = self._held, self._held_since
        self._held, self._held_since = held, now
        if held:
            level = logging.INFO if held == "HALT" else logging.WARNING
            self._holdlog.log(level, f"held-{held}", "robots stopped: %s", self.halt_reason)
        elif before:
            self._holdlog.log(logging.INFO if before == "HALT" else logging.WARNING,
                              f"driven-{before}",
                              "robots driven again after %.1f s stopped (%s)", now - since,
                              before)

    def apply_settings(self, settings: ControlSettings, our_team: Team) -> None:
        self.motion.apply_settings(settings)
        self.our_team = our_team
        self._basis.clear()  # every robot's command again under the new settings

    def configure(self, params: StationParams) -> None:
        self.apply_settings(params.control, params.team.our_team)
        safety = params.safety
        self.vision_stale_s = safety.vision_stale_s
        # a slow strategy rate must not look like a stall: at least 2.5 of its periods
        self.strategy_stale_s = max(safety.strategy_stale_s,
                                    2.5 / params.processors.strategy_hz)
        self.stop_speed_mps = safety.stop_speed_mps
        self._basis.clear()
        self.trigger = OnTopic(self.world, max_wait_s=params.processors.control_max_wait_s)

    def step(self) -> None:
        now = self.clock()
        tick_dt = min(0.1, now - self._last_tick)
        self._last_tick = now
        rec = self.world.latest()
        targets: dict[tuple[Team, int], TargetEntry] = self.targets.latest_value() or {}
        ref = self.active_referee()
        estop = bool(self.estop.latest_value())
        created = self.clock_ns()
        vision_age = self.vision_age_s(now)
        self.vision_lost = lost = self._lost(vision_age)
        if estop:
            self.halt_reason = "emergency stop"
            self._reset()
            self.commands.write(CommandSet(created, 0, (), stop_all=True))
            self.last_commands = {}
            return
        other_ok = self.may_drive_other_team()
        # the robots commanded change with the targets (20 Hz), not with every camera frame
        keys_of = (self.targets.seq, self.our_team, other_ok)
        if keys_of == self._keys_of:
            keys = self._sorted_keys
        else:
            keys = sorted(k for k in targets if k[0] == self.our_team or other_ok)
            self._keys_of, self._sorted_keys = keys_of, keys
        zero = _ZERO
        targets_age = self.targets.age_s(now)
        stalled = targets_age > self.strategy_stale_s
        blind = lost is not None or vision_age > self.vision_stale_s
        if rec is None or blind or (ref and ref.halted) or stalled:
            self.halt_reason = ("HALT" if ref and ref.halted else
                                "no vision" if vision_age == math.inf else
                                lost.reason() if lost is not None else
                                f"no vision for {vision_age:.1f} s" if blind
                                else f"strategy stalled ({targets_age:.1f} s)")
            held = ("HALT" if ref and ref.halted else "no vision" if rec is None or blind
                    else "strategy stalled")
            if held != self._held:
                self._hold_changed(held, now)
            self._reset()
            cmds = tuple(Command(t, i, zero) for t, i in keys)
            self.commands.write(CommandSet(created, 0, cmds))
            self.last_commands = {(c.team, c.id): c for c in cmds}
            return
        self.halt_reason = ""
        if self._held:
            self._hold_changed("", now)
        world = rec.value
        command = ref.command if ref is not None else None
        if command != self._command:  # speed caps and kicks change for every robot
            self._command = command
            self._basis.clear()
        if world is not self._indexed:
            self._indexed = world
            index = world.index  # the world model's (one dict for many worlds)
            self._index = (index if index is not None else
                           {(r.team, r.id): i for i, r in enumerate(world.robots)})
        index, world_robots = self._index, world.robots
        basis, step_t = self._basis, self._step_t
        motions = self.motion.robots
        kick_ok = kick_allowed(command)
        cmd_cap = command_cap_mps(command, self.our_team, self.stop_speed_mps)
        refresh_s = self.refresh_s
        out: list[Command] = []
        for key in keys:
            i = index.get(key)
            robot = None if i is None else world_robots[i]
            entry = targets[key]
            b = basis.get(key)  # (its time is the robot's step_t: both written in its step)
            if (b is not None and b[0] is robot and now - b[2] < refresh_s and robot.visible
                    and (b[1] is entry or b[1] == entry)):
                continue  # nothing new for this robot: the relay repeats its command
            last_t = step_t.get(key)
            dt = tick_dt if last_t is None else min(0.1, now - last_t)
            step_t[key] = now
            m = motions.get(key) or self.motion.get(key[0], key[1])
            if robot is None or not robot.visible:
                m.step(_UNSEEN, entry.target, dt)  # zero, and restart when seen again
                basis.pop(key, None)  # commanded zero again in every tick while not seen
                out.append(Command(key[0], key[1], zero))
                continue
            basis[key] = (robot, entry, now)
            x, y = robot.x, robot.y
            if entry.stop:  # a team play that failed: zero, never the last command
                m.reset()
                out.append(Command(key[0], key[1], zero))
                continue
            if entry.velocity is not None:  # a team play's velocity order, limited
                vel = m.step_velocity(robot.orientation, entry.velocity, dt)
            else:
                # (next_waypoint's own first test inline: most targets have no path)
                aim = entry.target if len(entry.path) <= 1 else next_waypoint(entry, x, y)
                vel = m.step_at(x, y, robot.orientation, aim, dt)
            # referee_limits: the command's cap (once per tick), then the robot's own
            cap = entry.max_speed_mps
            vel = capped(vel, cmd_cap if cap is None else min(cmd_cap, cap))
            out.append(_tuple_new(Command, (  # (the tuple itself: no __new__ call)
                key[0], key[1], vel, entry.kick_speed_mps if kick_ok else 0.0,
                entry.chip and kick_ok, entry.dribbler_rpm)))
        if keys != self._keys:  # robots no longer commanded leave the table
            self._keys = keys
            kept = set(keys)
            for key in [k for k in step_t if k not in kept]:
                del step_t[key]
                basis.pop(key, None)
            self.last_commands = {k: c for k, c in self.last_commands.items() if k in kept}
        if not out:
            return  # no robot has anything new: no command set
        last = dict(self.last_commands)  # a new dict: the views may hold the old one
        for c in out:
            last[(c.team, c.id)] = c
        self.last_commands = last
        self._telemetry_cache = None
        self.commands.write(_tuple_new(CommandSet, (created, world.receive_time_ns, tuple(out),
                                                    False)))

    def _reset(self) -> None:
        """Every controller back to its start (a stop): the next commands are computed afresh
        for every robot."""
        self.motion.reset_all()
        self._basis.clear()
        self._step_t.clear()

    @property
    def telemetry(self) -> dict[str, dict[str, Any]]:
        """Each robot's controller telemetry, built when read (the page reads it at its own
        rate, not once per camera frame)."""
        if self._telemetry_cache is None:
            self._telemetry_cache = self._telemetry()
        return self._telemetry_cache

    def _telemetry(self) -> dict[str, dict[str, Any]]:
        out: dict[str, dict[str, Any]] = {}
        for key, tel in self.motion.telemetry().items():
            entry: dict[str, Any] = dict(tel)
            entry["algorithm"] = ALGORITHMS[int(tel["algorithm"])]
            entry["phase"] = PHASE_NAMES[int(tel["phase"])]
            out[key] = entry
        return out


_UNSEEN = RobotMotionState(0.0, 0.0, 0.0, visible=False)
#: named tuples of the per-frame path made as the tuples they are (``Command(...)`` calls
#: the named tuple's ``__new__``, a Python function: about 0.2 us more)
_tuple_new = tuple.__new__
_ZERO = LocalVelocity.zero()  # (frozen: one for every zero command)
