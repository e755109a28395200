"""The match director: game controller and autoref of one simulated match (pure: no I/O).

Feed it ``tick(now, truth)`` with a monotonic clock (seconds) and, when one arrived, fieldsim's
truth dict; it returns the ball teleports it needs and keeps ``referee`` (a MatchReferee whose
``encode()`` is the Referee datagram) and the statistics up to date. ``revision`` changes
whenever the referee state changes, so the I/O shell can send at once.

The game runs as a queue of steps (hold a command for a while, prepare a kick-off or penalty
until the robots settled, wait for a set piece to be taken, wait for a ball placement); with
no step left the game is running, and the director judges goals, balls out, no progress, the
scripted interludes and the end of each half. Violations are judged on every truth frame.
"""

from __future__ import annotations

import math
import uuid
from collections import deque
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

from domain.field import division
from domain.rules import (
    BALL_RADIUS_MM,
    COLLISION_SPEED_MPS,
    PLACEMENT_TOLERANCE_MM,
    ROBOT_RADIUS_MM,
)
from match.referee import MatchReferee
from match.rules import (
    BALL_IN_PLAY_MM,
    COLLISION_DRAWN_MPS,
    DISTANCE_TOLERANCE_MM,
    HALT_SPEED_LIMIT_MMPS,
    NO_PROGRESS_MM,
    NO_PROGRESS_S,
    PENALTY_BEHIND_BALL_MM,
    PLACEMENT_STILL_MMPS,
    POSSESSION_DISTANCE_MM,
    STOP_SPEED_LIMIT_MMPS,
    TOO_CLOSE_MM,
    TOUCH_DISTANCE_MM,
    Grace,
    Timing,
    dist,
    dist_to_segment,
    placement_position,
)
from match.truth import TEAMS, RobotKey, RobotView, Snapshot, num, other, parse_truth, robot_key

# Violations judged continuously (counted once per episode, plus robot-seconds in violation)
EPISODE_KINDS = (
    "halt_moving", "stop_speed", "stop_distance", "set_piece_distance", "placement_distance",
    "defense_area",
)
# Violations judged at one instant (counted once per robot) or from events
SNAPSHOT_KINDS = ("kickoff_position", "penalty_position", "collision")
VIOLATION_KINDS = EPISODE_KINDS + SNAPSHOT_KINDS

# The scripted interludes: (name, half, fraction of the half's clock)
INTERLUDES: tuple[tuple[str, int, float], ...] = (
    ("halt", 1, 0.15), ("free_blue", 1, 0.3), ("placement_yellow", 1, 0.45),
    ("timeout_yellow", 1, 0.6), ("penalty_blue", 1, 0.75),
    ("stop", 2, 0.15), ("free_yellow", 2, 0.3), ("placement_blue", 2, 0.45),
    ("timeout_blue", 2, 0.6), ("penalty_yellow", 2, 0.75),
)
PLACEMENT_INTERLUDE_MM = 1000.0  # a scripted placement moves the ball this far
INTERLUDE_AFTER_RUNNING_S = 3.0  # an interlude waits for this much running play first

MAX_DT_S = 0.5  # a gap between frames longer than this counts as this much


@dataclass
class MatchConfig:
    half_s: float = 90.0
    division: str = "B"
    first_kickoff: str = "blue"
    blue_on_positive: bool = False
    goalkeepers: dict[str, int] = field(default_factory=lambda: {"blue": 0, "yellow": 0})
    plays: dict[str, str] = field(default_factory=lambda: {"blue": "match", "yellow": "simple"})
    interludes: bool = True
    timing: Timing = field(default_factory=Timing)
    grace: Grace = field(default_factory=Grace)


@dataclass(frozen=True)
class TeleportBall:
    """Put the ball at (x, y) mm, at rest."""

    x: float
    y: float


@dataclass
class Step:
    kind: str  # hold | prepare | kick | placement | force | half_time | end
    command: str
    duration: float = 0.0
    team: str | None = None  # kicking / placing / timeout team
    set_piece: str | None = None  # kick/prepare: kickoff | penalty | free
    pos: tuple[float, float] | None = None  # placement target, or where a hold teleports to
    teleport_at: float | None = None  # hold: teleport the ball to pos this long after entering
    interlude: str | None = None


@dataclass
class Violation:
    count: int = 0
    seconds: float = 0.0


@dataclass
class TeamStats:
    goals: int = 0
    possession_s: float = 0.0
    kicks: int = 0
    placements_ok: int = 0
    placements_failed: int = 0
    placement_times_s: list[float] = field(default_factory=list)
    violations: dict[str, Violation] = field(
        default_factory=lambda: {k: Violation() for k in VIOLATION_KINDS})


@dataclass
class _Interlude:
    name: str
    half: int
    at: float
    done: bool = False


class Director:
    def __init__(self, config: MatchConfig | None = None, *, wall_offset_s: float = 0.0) -> None:
        self.cfg = config if config is not None else MatchConfig()
        self.field = division(self.cfg.division)
        self.timing = self.cfg.timing
        self.grace = self.cfg.grace
        self.wall_offset_s = wall_offset_s
        self.referee = MatchReferee(source_identifier=f"touchline-match-{uuid.uuid4()}")
        self.referee.blue_team_on_positive_half = self.cfg.blue_on_positive
        self.referee.blue.goalkeeper = self.cfg.goalkeepers.get("blue", 0)
        self.referee.yellow.goalkeeper = self.cfg.goalkeepers.get("yellow", 0)
        self.referee.stage_time_left_us = int(self.cfg.half_s * 1e6)
        self.revision = 0
        self.stats = {t: TeamStats() for t in TEAMS}
        self.kicks_measured = False
        self.loose_ball_s = 0.0
        self.command_counts: dict[str, int] = {}
        self.command_seconds: dict[str, float] = {}
        self.stage_seconds: dict[str, float] = {}
        self.timeline: list[dict[str, Any]] = []
        self.event_counts: dict[str, int] = {}
        self.events_source: str | None = None  # "fieldsim" or "director" (self-detected)
        self.finished = False
        self.half = 1
        self.clock_left = self.cfg.half_s
        self.half_time_left = 0.0
        self.t0: float | None = None
        self.now = 0.0
        self._last_now: float | None = None
        self._last_truth_now: float | None = None
        self.snap: Snapshot | None = None
        self.queue: deque[Step] = deque()
        self.step: Step | None = None
        self.step_since = 0.0
        self._step_teleported: float | None = None
        self._step_failed_at: float | None = None
        self._step_anchor: tuple[float, float] | None = None
        self.command_since = 0.0
        self.running_since = 0.0
        self.in_interlude: str | None = None
        self.set_piece: tuple[str, str, float] | None = None  # team, kind, since
        self._progress_anchor: tuple[float, float] | None = None
        self._progress_since = 0.0
        self._last_seq = -1
        self._seen_unsequenced: set[tuple[Any, ...]] = set()
        self._kicks_seen: dict[RobotKey, int] = {}
        self.last_touch: RobotKey | None = None
        self._active: dict[str, set[RobotKey]] = {k: set() for k in EPISODE_KINDS}
        #: since when each robot of the non-placing team is inside the placement corridor
        self._in_corridor_since: dict[RobotKey, float] = {}
        self._halt_flagged: set[RobotKey] = set()
        self._actions: list[TeleportBall] = []
        self._issued = False  # the first HALT is issued even though the referee starts in HALT
        self._outside_since: float | None = None
        self._inside_in_running = False
        self.interludes = [
            _Interlude(n, h, a) for n, h, a in INTERLUDES] if self.cfg.interludes else []

    # -- public --------------------------------------------------------------------------------

    @property
    def started(self) -> bool:
        return self.t0 is not None

    @property
    def running(self) -> bool:
        """Running play: started, no step pending, not over."""
        return self.t0 is not None and self.step is None and not self.queue and not self.finished

    def side_of(self, team: str) -> int:
        """+1 if ``team`` defends the goal at positive x, else -1."""
        blue_pos = self.referee.blue_team_on_positive_half
        return 1 if (team == "blue") == blue_pos else -1

    def team_on_side(self, side: int) -> str:
        """The team defending the goal at x = side * half length."""
        return "blue" if (side > 0) == self.referee.blue_team_on_positive_half else "yellow"

    def encode(self, now_unix_us: int) -> bytes:
        return self.referee.encode(now_unix_us)

    def tick(self, now: float, truth: Mapping[str, Any] | None = None) -> list[TeleportBall]:
        """Advance to ``now`` (s, monotonic) with a new truth frame if one arrived."""
        self._actions = []
        if self.t0 is None:
            self.t0 = now
            self._last_now = now
            self.now = now
            self._begin()
        assert self._last_now is not None
        dt = max(0.0, now - self._last_now)
        self._last_now = now
        self.now = now
        if self.finished:
            return []
        self._account(min(dt, MAX_DT_S))
        snap = None
        if truth is not None:
            snap = parse_truth(truth)
            self.snap = snap
            self._observe(snap)
        self._advance()
        if snap is not None:
            self._events(snap)
        if self.running:
            self._running_checks()
        self._advance()
        if snap is not None:
            tdt = 0.0 if self._last_truth_now is None else min(now - self._last_truth_now,
                                                               MAX_DT_S)
            self._last_truth_now = now
            self._judge(snap, max(0.0, tdt))
        self._update_timers()
        return self._actions

    # -- bookkeeping ---------------------------------------------------------------------------

    def _log(self, kind: str, team: str | None = None, robot: int | None = None,
             detail: str = "") -> None:
        self.timeline.append({
            "t": round(self.now - (self.t0 or self.now), 3), "kind": kind, "team": team,
            "robot": robot, "command": self.referee.command, "stage": self.referee.stage,
            "detail": detail})

    def _give(self, command: str, pos: tuple[float, float] | None = None) -> None:
        ref = self.referee
        if self._issued and command == ref.command and pos == ref.designated_position:
            return
        self._issued = True
        stage = ref.stage
        ref.give(command, pos, now_us=int((self.now + self.wall_offset_s) * 1e6))
        if ref.stage != stage:
            self._log("stage", detail=ref.stage)
        self.command_counts[command] = self.command_counts.get(command, 0) + 1
        self.command_since = self.now
        if command == "HALT":
            self._halt_flagged = set()
        self.revision += 1
        detail = "" if pos is None else f"designated ({pos[0]:.0f}, {pos[1]:.0f})"
        self._log("command", detail=f"{command} {detail}".strip())

    def _set_stage(self, stage: str) -> None:
        self.referee.set_stage(stage)
        self.revision += 1
        self._log("stage", detail=stage)

    def _teleport(self, x: float, y: float) -> None:
        self._actions.append(TeleportBall(x, y))
        self._log("teleport", detail=f"ball to ({x:.0f}, {y:.0f})")

    def _account(self, dt: float) -> None:
        ref = self.referee
        self.command_seconds[ref.command] = self.command_seconds.get(ref.command, 0.0) + dt
        self.stage_seconds[ref.stage] = self.stage_seconds.get(ref.stage, 0.0) + dt
        if ref.command.startswith("TIMEOUT_"):
            ref.use_timeout_time(ref.command[len("TIMEOUT_"):].lower(), dt)
        if ref.stage in ("NORMAL_FIRST_HALF", "NORMAL_SECOND_HALF") \
                and ref.command != "HALT" and not ref.command.startswith("TIMEOUT_") \
                and self.in_interlude is None:
            self.clock_left -= dt
        if ref.stage == "NORMAL_HALF_TIME":
            self.half_time_left = max(0.0, self.half_time_left - dt)

    def _update_timers(self) -> None:
        ref = self.referee
        if ref.stage in ("NORMAL_FIRST_HALF", "NORMAL_SECOND_HALF"):
            ref.stage_time_left_us = int(self.clock_left * 1e6)
        elif ref.stage.endswith("_PRE"):
            ref.stage_time_left_us = int(self.cfg.half_s * 1e6)
        elif ref.stage == "NORMAL_HALF_TIME":
            ref.stage_time_left_us = int(self.half_time_left * 1e6)
        else:
            ref.stage_time_left_us = 0
        step, elapsed = self.step, self.now - self.step_since
        remaining: float | None = None
        if step is not None and step.kind == "placement" and self._step_failed_at is None:
            remaining = self.timing.placement_timeout - elapsed
        elif step is not None and step.kind == "kick":
            remaining = self.timing.kick_timeout - elapsed
        ref.action_time_remaining_us = None if remaining is None else int(max(0.0, remaining)
                                                                          * 1e6)
        nxt: str | None = None
        if step is not None and step.kind == "prepare":
            nxt = "NORMAL_START"
        elif self.queue:
            nxt = self.queue[0].command
        if nxt == ref.command:
            nxt = None
        if nxt != ref.next_command:
            ref.next_command = nxt
            self.revision += 1

    # -- observation ---------------------------------------------------------------------------

    def _observe(self, snap: Snapshot) -> None:
        # kicks: per-robot counters from fieldsim, counted from the first frame that has them
        for r in snap.robots:
            if r.kicks is None:
                continue
            self.kicks_measured = True
            prev = self._kicks_seen.get(r.key)
            if prev is not None and r.kicks != prev:
                self.stats[r.team].kicks += r.kicks - prev if r.kicks > prev else r.kicks
            self._kicks_seen[r.key] = r.kicks
        # last touch: fieldsim's, else the nearest robot touching the ball
        if snap.has_last_touch:
            self.last_touch = snap.last_touch
        elif snap.ball is not None:
            b = snap.ball
            near = [(dist(r.x, r.y, b.x, b.y), r.key) for r in snap.robots]
            near = [n for n in near if n[0] <= TOUCH_DISTANCE_MM]
            if near:
                self.last_touch = min(near)[1]

    def _settled(self) -> bool:
        s = self.snap
        return s is not None and all(r.speed < self.timing.settled_speed_mmps for r in s.robots)

    def _ball_at(self, pos: tuple[float, float], tol: float = PLACEMENT_TOLERANCE_MM) -> bool:
        s = self.snap
        return s is not None and s.ball is not None and \
            dist(s.ball.x, s.ball.y, pos[0], pos[1]) <= tol

    # -- the script ----------------------------------------------------------------------------

    def _begin(self) -> None:
        t = self.timing
        self._log("match", detail=f"start: {self.cfg.half_s:.0f} s halves, division "
                  f"{self.cfg.division}")
        self.queue.extend([
            Step("hold", "HALT", t.start_halt),
            Step("hold", "STOP", t.start_stop, pos=(0.0, 0.0), teleport_at=0.0),
            *self._kickoff_steps(self.cfg.first_kickoff),
        ])

    def _kickoff_steps(self, team: str) -> list[Step]:
        return [
            Step("prepare", f"PREPARE_KICKOFF_{team.upper()}", team=team, set_piece="kickoff",
                 pos=(0.0, 0.0)),
            Step("kick", "NORMAL_START", team=team, set_piece="kickoff"),
        ]

    def _advance(self) -> None:
        for _ in range(16):  # a bounded number of step changes per tick
            if self.finished:
                return
            if self.step is None:
                if not self.queue:
                    return
                self._enter(self.queue.popleft())
                continue
            if not self._step_done(self.step):
                return
            self.step = None
            if not self.queue:
                self._resume_running()

    def _resume_running(self) -> None:
        self.running_since = self.now
        self.set_piece = None
        self._progress_anchor = None
        self._progress_since = self.now
        self._outside_since = None
        self._inside_in_running = False
        if self.in_interlude is not None:
            self._log("interlude_end", detail=self.in_interlude)
        self.in_interlude = None

    def _enter(self, step: Step) -> None:
        self.step = step
        self.step_since = self.now
        self._step_teleported = None
        self._step_failed_at = None
        self._step_anchor = None
        if step.kind not in ("prepare", "kick"):
            self.set_piece = None
        if step.kind == "half_time":
            self._set_stage("NORMAL_HALF_TIME")
            self.half_time_left = step.duration
            self._give("HALT")
            self.referee.blue_team_on_positive_half = not self.referee.blue_team_on_positive_half
            self.revision += 1
            self._log("sides", detail="blue on positive half"
                      if self.referee.blue_team_on_positive_half else "blue on negative half")
            self._teleport(0.0, 0.0)
            return
        if step.kind == "end":
            self._give("HALT")
            self._set_stage("POST_GAME")
            self.finished = True
            self._log("match", detail="end")
            return
        if step.kind == "placement":
            self._give(step.command, step.pos)
            return
        if step.kind == "hold" and step.command.startswith("TIMEOUT_") and step.team:
            self.referee.start_timeout(step.team)
        self._give(step.command)
        if step.kind == "prepare" and step.team and step.set_piece:
            self.set_piece = (step.team, step.set_piece, self.now)
        if step.kind == "kick" and step.team and step.set_piece:
            if step.set_piece == "kickoff":
                self._judge_kickoff(step.team)
            elif step.set_piece == "penalty":
                self._judge_penalty(step.team)
            if self.set_piece is None or step.set_piece == "free":
                self.set_piece = (step.team, step.set_piece, self.now)
        if step.kind == "force":
            self._log("force_start")

    def _step_done(self, step: Step) -> bool:
        t = self.timing
        elapsed = self.now - self.step_since
        if step.kind == "hold":
            if step.pos is None or step.teleport_at is None:
                return elapsed >= step.duration
            if self._step_teleported is None:
                if elapsed >= step.teleport_at:
                    self._teleport(*step.pos)
                    self._step_teleported = self.now
                return False
            if elapsed < step.duration:
                return False
            return self._ball_at(step.pos) or \
                self.now - self._step_teleported >= t.teleport_confirm
        if step.kind == "prepare":
            return self._prepare_done(step, elapsed)
        if step.kind == "kick":
            return self._kick_done(elapsed)
        if step.kind == "placement":
            return self._placement_done(step, elapsed)
        if step.kind == "half_time":
            if elapsed < step.duration:
                return False
            self._set_stage("NORMAL_SECOND_HALF_PRE")
            self.half = 2
            self.clock_left = self.cfg.half_s
            second = other(self.cfg.first_kickoff)
            self.queue.extend([Step("hold", "STOP", t.start_stop, pos=(0.0, 0.0),
                                    teleport_at=0.0),
                               *self._kickoff_steps(second)])
            return True
        return True  # force, end

    def _prepare_done(self, step: Step, elapsed: float) -> bool:
        """Settled (or out of time), and the ball on its spot: a ball moved off the centre or
        the penalty mark during the preparation is put back before NORMAL_START."""
        t = self.timing
        if self._step_teleported is not None:
            assert step.pos is not None
            return self._ball_at(step.pos) or \
                self.now - self._step_teleported >= t.teleport_confirm
        longest = t.penalty_prepare_max if step.set_piece == "penalty" else t.prepare_max
        if elapsed < longest and (elapsed < t.prepare_min or not self._settled()):
            return False
        s = self.snap
        if step.pos is not None and s is not None and s.ball is not None \
                and not self._ball_at(step.pos):
            lt = self.last_touch
            self._log("ball_moved", team=lt[0] if lt else None, robot=lt[1] if lt else None,
                      detail=f"during {step.command}: ball at ({s.ball.x:.0f}, {s.ball.y:.0f}),"
                      f" put back to ({step.pos[0]:.0f}, {step.pos[1]:.0f})")
            self._count_event("ball_moved_in_preparation")
            self._teleport(*step.pos)
            self._step_teleported = self.now
            return False
        return True

    def _kick_done(self, elapsed: float) -> bool:
        s = self.snap
        if s is not None and s.ball is not None:
            if self._step_anchor is None:
                self._step_anchor = (s.ball.x, s.ball.y)
            elif dist(s.ball.x, s.ball.y, *self._step_anchor) > BALL_IN_PLAY_MM:
                self._log("ball_in_play", detail=f"after {elapsed:.1f} s")
                return True
        if elapsed >= self.timing.kick_timeout:
            self._log("kick_timeout", detail=f"ball not in play after {elapsed:.0f} s")
            self._give("FORCE_START")
            return True
        return False

    def _placement_done(self, step: Step, elapsed: float) -> bool:
        assert step.pos is not None and step.team is not None
        st = self.stats[step.team]
        if self._step_failed_at is None:
            s = self.snap
            if s is not None and s.ball is not None and self._ball_at(step.pos) \
                    and s.ball.speed < PLACEMENT_STILL_MMPS:
                st.placements_ok += 1
                st.placement_times_s.append(elapsed)
                self._log("placement_ok", team=step.team, detail=f"{elapsed:.1f} s")
                return True
            if elapsed < self.timing.placement_timeout:
                return False
            st.placements_failed += 1
            self._log("placement_failed", team=step.team,
                      detail=f"not placed after {elapsed:.0f} s")
            self._teleport(*step.pos)
            self._step_failed_at = self.now
            return False
        return self._ball_at(step.pos) or \
            self.now - self._step_failed_at >= self.timing.teleport_confirm

    # -- running play --------------------------------------------------------------------------

    def _running_checks(self) -> None:
        s = self.snap
        if s is not None and s.ball is not None and self._ball_outside(s):
            return
        if s is not None and s.ball is not None:
            b = s.ball
            if self._progress_anchor is None or \
                    dist(b.x, b.y, *self._progress_anchor) > NO_PROGRESS_MM:
                self._progress_anchor = (b.x, b.y)
                self._progress_since = self.now
        if self.now - self._progress_since >= NO_PROGRESS_S:
            self._count_event("no_progress")
            self._log("no_progress", detail=f"ball within {NO_PROGRESS_MM:.0f} mm for "
                      f"{NO_PROGRESS_S:.0f} s")
            self.queue.extend([Step("hold", "STOP", self.timing.no_progress_stop),
                               Step("force", "FORCE_START")])
            return
        if self.clock_left <= 0.0:
            # time is up: the interludes still due in this half run back to back, then it ends
            pending = [i for i in self.interludes if not i.done and i.half <= self.half]
            if pending:
                self._start_interlude(pending[0])
            else:
                self._end_half()
            return
        if self.now - self.running_since < INTERLUDE_AFTER_RUNNING_S:
            return
        elapsed_frac = 1.0 - self.clock_left / self.cfg.half_s if self.cfg.half_s > 0 else 1.0
        for il in self.interludes:
            if not il.done and (il.half < self.half or
                                (il.half == self.half and elapsed_frac >= il.at)):
                self._start_interlude(il)
                return

    def _end_half(self) -> None:
        self._log("half_end", detail=f"half {self.half}")
        if self.half == 1:
            self.queue.append(Step("half_time", "HALT", self.timing.half_time))
        else:
            self.queue.append(Step("end", "HALT"))

    def _start_interlude(self, il: _Interlude) -> None:
        il.done = True
        self.in_interlude = il.name
        t = self.timing
        self._log("interlude", detail=il.name)
        name = il.name
        steps: list[Step]
        if name == "halt":
            steps = [Step("hold", "HALT", t.interlude_halt),
                     Step("hold", "STOP", t.interlude_before), Step("force", "FORCE_START")]
        elif name == "stop":
            steps = [Step("hold", "STOP", t.interlude_stop), Step("force", "FORCE_START")]
        elif name.startswith("free_"):
            team = name[len("free_"):]
            hold = Step("hold", "STOP", t.interlude_before)
            s = self.snap
            if s is not None and s.ball is not None:
                # the ball stays where it is unless that is no place for a free kick
                pos = placement_position(self.field, s.ball.x, s.ball.y)
                if dist(pos[0], pos[1], s.ball.x, s.ball.y) > 1.0:
                    hold.pos, hold.teleport_at = pos, 0.5
            steps = [hold, Step("kick", f"DIRECT_FREE_{team.upper()}", team=team,
                                set_piece="free")]
        elif name.startswith("placement_"):
            team = name[len("placement_"):]
            pos = self._scripted_placement_target()
            steps = [Step("hold", "STOP", t.out_stop),
                     Step("placement", f"BALL_PLACEMENT_{team.upper()}", team=team, pos=pos),
                     Step("kick", f"DIRECT_FREE_{team.upper()}", team=team, set_piece="free")]
        elif name.startswith("timeout_"):
            team = name[len("timeout_"):]
            steps = [Step("hold", "STOP", 1.0),
                     Step("hold", f"TIMEOUT_{team.upper()}", t.timeout, team=team),
                     Step("hold", "STOP", t.interlude_before), Step("force", "FORCE_START")]
        elif name.startswith("penalty_"):
            team = name[len("penalty_"):]
            mark = self.field.penalty_mark(self.side_of(other(team)))
            steps = [Step("hold", "STOP", t.interlude_before, pos=mark, teleport_at=0.5),
                     Step("prepare", f"PREPARE_PENALTY_{team.upper()}", team=team,
                          set_piece="penalty", pos=mark),
                     Step("kick", "NORMAL_START", team=team, set_piece="penalty")]
        else:  # pragma: no cover - INTERLUDES names are fixed
            raise ValueError(name)
        for st in steps:
            st.interlude = name
        self.queue.extend(steps)

    def _scripted_placement_target(self) -> tuple[float, float]:
        """1 m from the ball towards the centre (across the field if it is near the centre)."""
        s = self.snap
        bx, by = (s.ball.x, s.ball.y) if s is not None and s.ball is not None else (0.0, 0.0)
        d = math.hypot(bx, by)
        if d > 2.0 * PLACEMENT_INTERLUDE_MM:
            tx, ty = bx - bx / d * PLACEMENT_INTERLUDE_MM, by - by / d * PLACEMENT_INTERLUDE_MM
        else:
            tx, ty = bx, by + (-PLACEMENT_INTERLUDE_MM if by > 0 else PLACEMENT_INTERLUDE_MM)
        return placement_position(self.field, tx, ty)

    # -- events --------------------------------------------------------------------------------

    def _count_event(self, kind: str) -> None:
        self.event_counts[kind] = self.event_counts.get(kind, 0) + 1

    def _events(self, snap: Snapshot) -> None:
        if snap.events is None:
            return  # goals and balls out are then seen in _running_checks
        self.events_source = "fieldsim"
        fresh: list[Mapping[str, Any]] = []
        for ev in snap.events:
            seq = ev.get("seq")
            if isinstance(seq, int) and not isinstance(seq, bool):
                if seq > self._last_seq:
                    fresh.append(ev)
            else:
                key = (ev.get("kind"), num(ev.get("t")), num(ev.get("x")), num(ev.get("y")))
                if key not in self._seen_unsequenced:
                    self._seen_unsequenced.add(key)
                    fresh.append(ev)
        fresh.sort(key=lambda e: e["seq"] if isinstance(e.get("seq"), int) else 0)
        for ev in fresh:
            seq = ev.get("seq")
            if isinstance(seq, int) and not isinstance(seq, bool):
                self._last_seq = max(self._last_seq, seq)
            self._handle_event(ev)

    def _handle_event(self, ev: Mapping[str, Any]) -> None:
        kind = ev.get("kind")
        s = self.snap
        bx = s.ball.x if s is not None and s.ball is not None else 0.0
        by = s.ball.y if s is not None and s.ball is not None else 0.0
        x, y = num(ev.get("x")), num(ev.get("y"))
        if kind == "collision":
            self._collision(ev)
            return
        if kind not in ("goal", "ball_out"):
            return
        self._count_event(str(kind))
        if not self.running:
            self._log(f"{kind}_ignored", detail="not in running play")
            return
        last = robot_key(ev.get("last_touch")) if "last_touch" in ev else self.last_touch
        if kind == "goal":
            side_txt = ev.get("side")
            if side_txt in ("positive", "negative"):
                side = 1 if side_txt == "positive" else -1
            elif x is not None and x != 0.0:
                side = 1 if x > 0 else -1
            else:
                self._log("goal_ignored", detail="event without side or x")
                return
            self._goal(side, last)
        else:
            x = bx if x is None else x
            y = by if y is None else y
            line = ev.get("line")
            if line not in ("touch", "goal"):
                line = "goal" if abs(x) >= self.field.half_length else "touch"
            self._ball_out(str(line), x, y, last)

    def _ball_outside(self, snap: Snapshot) -> bool:
        """Running play with the ball fully over a line: True (nothing else is judged then).

        With a fieldsim that reports no events, a ball that crosses a line in running play is a
        goal or a ball out at once. Otherwise this is the safety net for a ball that is outside
        while no event of fieldsim's stopped play (it left while play was stopped, so its event
        was ignored, and FORCE_START followed): after 1 s it is a ball out, never a goal."""
        b = snap.ball
        assert b is not None
        f = self.field
        if abs(b.x) <= f.half_length + BALL_RADIUS_MM and abs(b.y) <= f.half_width + BALL_RADIUS_MM:
            self._outside_since = None
            self._inside_in_running = True
            return False
        if self._outside_since is None:
            self._outside_since = self.now
        crossed = self._inside_in_running
        self._inside_in_running = False
        if snap.events is None and crossed:
            if self.events_source is None:
                self.events_source = "director"
            self._detect_lines(b.x, b.y, goal_possible=True)
        elif self.now - self._outside_since >= 1.0:
            self._detect_lines(b.x, b.y, goal_possible=False)
        return True

    def _detect_lines(self, bx: float, by: float, goal_possible: bool) -> None:
        """A goal or a ball out seen from the ball position (no event for it)."""
        self._outside_since = None
        f = self.field
        over_goal = abs(bx) > f.half_length + BALL_RADIUS_MM
        if goal_possible and over_goal and abs(by) < f.goal_width / 2.0:
            self._count_event("goal")
            self._goal(1 if bx > 0 else -1, self.last_touch)
            return
        self._count_event("ball_out")
        x = max(-f.half_length, min(f.half_length, bx))
        y = max(-f.half_width, min(f.half_width, by))
        self._ball_out("goal" if over_goal else "touch", x, y, self.last_touch)

    def _goal(self, side: int, last: RobotKey | None) -> None:
        defending = self.team_on_side(side)
        scorer = other(defending)
        self.stats[scorer].goals += 1
        (self.referee.blue if scorer == "blue" else self.referee.yellow).score += 1
        self.revision += 1
        by = f"last touch {last[0]} {last[1]}" if last else "last touch unknown"
        self._log("goal", team=scorer, detail=f"into the {'positive' if side > 0 else 'negative'}"
                  f" goal; {by}")
        self.queue.extend([
            Step("hold", "STOP", self.timing.goal_stop, pos=(0.0, 0.0),
                 teleport_at=self.timing.goal_teleport_after),
            *self._kickoff_steps(defending),
        ])

    def _ball_out(self, line: str, x: float, y: float, last: RobotKey | None) -> None:
        # the team that did not touch it last; unknown: the team defending that half
        team = other(last[0]) if last is not None else self.team_on_side(1 if x >= 0 else -1)
        pos = placement_position(self.field, x, y)
        by = f"last touch {last[0]} {last[1]}" if last else "last touch unknown"
        self._log("ball_out", team=team, detail=f"{line} line at ({x:.0f}, {y:.0f}); {by}")
        self.queue.extend([
            Step("hold", "STOP", self.timing.out_stop),
            Step("placement", f"BALL_PLACEMENT_{team.upper()}", team=team, pos=pos),
            Step("kick", f"DIRECT_FREE_{team.upper()}", team=team, set_piece="free"),
        ])

    def _collision(self, ev: Mapping[str, Any]) -> None:
        self._count_event("collision")
        rel = num(ev.get("relative_speed_mps"))
        a, b = ev.get("a"), ev.get("b")
        ka, kb = robot_key(a), robot_key(b)
        if rel is None or rel <= COLLISION_SPEED_MPS or (ka is None and kb is None):
            return
        sa = num(a.get("speed_mps")) if isinstance(a, Mapping) else None
        sb = num(b.get("speed_mps")) if isinstance(b, Mapping) else None
        culprits: list[RobotKey]
        if ka is None or kb is None:
            culprits = [k for k in (ka, kb) if k is not None]
        elif sa is None or sb is None or abs(sa - sb) <= COLLISION_DRAWN_MPS:
            culprits = [ka, kb]
        else:
            culprits = [ka if sa > sb else kb]
        for team, rid in culprits:
            self.stats[team].violations["collision"].count += 1
            self._log("violation", team=team, robot=rid,
                      detail=f"collision at {rel:.2f} m/s relative")

    # -- violations and possession -------------------------------------------------------------

    def _episodes(self, kind: str, offenders: set[RobotKey], dt: float,
                  latched: set[RobotKey] | None = None) -> None:
        prev = self._active[kind]
        for key in offenders:
            v = self.stats[key[0]].violations[kind]
            v.seconds += dt
            if key not in prev and (latched is None or key not in latched):
                v.count += 1
                self._log("violation", team=key[0], robot=key[1],
                          detail=f"{kind}{self._where(key)}")
        if latched is not None:
            latched |= offenders
        self._active[kind] = offenders

    def _judge(self, snap: Snapshot, dt: float) -> None:
        g = self.grace
        cmd = self.referee.command
        since = self.now - self.command_since
        robots = snap.robots
        ball = snap.ball
        found: dict[str, set[RobotKey]] = {k: set() for k in EPISODE_KINDS}
        if cmd == "HALT" and since >= g.halt:
            found["halt_moving"] = {r.key for r in robots if r.speed > HALT_SPEED_LIMIT_MMPS}
        if cmd == "STOP" and since >= g.stop:
            found["stop_speed"] = {r.key for r in robots if r.speed > STOP_SPEED_LIMIT_MMPS}
            if ball is not None:
                found["stop_distance"] = {r.key for r in robots
                                          if dist(r.x, r.y, ball.x, ball.y) < TOO_CLOSE_MM}
        if cmd.startswith("BALL_PLACEMENT_") and ball is not None \
                and self.referee.designated_position is not None:
            # the rules' interference: a robot of the other team inside the corridor for
            # more than 2 s on end (a robot crossing it, or passed by the ball, is not)
            placing = cmd[len("BALL_PLACEMENT_"):].lower()
            px, py = self.referee.designated_position
            inside = {r.key for r in robots if r.team != placing
                      and dist_to_segment(r.x, r.y, ball.x, ball.y, px, py) < TOO_CLOSE_MM}
            entered = self._in_corridor_since
            for key in list(entered):
                if key not in inside:
                    del entered[key]
            for key in inside:
                entered.setdefault(key, self.now)
            found["placement_distance"] = {k for k in inside
                                           if self.now - entered[k] > g.placement_distance}
        else:
            self._in_corridor_since.clear()
        sp = self.set_piece
        if sp is not None and sp[1] in ("kickoff", "free") and ball is not None \
                and self.now - sp[2] >= g.set_piece_distance:
            found["set_piece_distance"] = {r.key for r in robots if r.team != sp[0]
                                           and dist(r.x, r.y, ball.x, ball.y) < TOO_CLOSE_MM}
        if self.running and self.now - self.running_since >= g.defense_area:
            found["defense_area"] = self._defense_area_offenders(robots)
        for kind in EPISODE_KINDS:
            self._episodes(kind, found[kind], dt,
                           self._halt_flagged if kind == "halt_moving" else None)
        if self.running and ball is not None and robots:
            d, r = min(((dist(r.x, r.y, ball.x, ball.y), r) for r in robots),
                       key=lambda p: p[0])
            if d <= POSSESSION_DISTANCE_MM:
                self.stats[r.team].possession_s += dt
            else:
                self.loose_ball_s += dt

    def _where(self, key: RobotKey) -> str:
        """Where an episode starts: the robot (position, speed), the ball and, during a
        placement, the designated position; mm and m/s on fieldsim's ground truth."""
        snap = self.snap
        if snap is None:
            return ""
        r = next((r for r in snap.robots if r.key == key), None)
        if r is None:
            return ""
        out = f": robot at ({r.x:.0f}, {r.y:.0f}) {r.speed / 1000.0:.2f} m/s"
        if snap.ball is not None:
            b = snap.ball
            out += f", ball at ({b.x:.0f}, {b.y:.0f}) {dist(r.x, r.y, b.x, b.y):.0f} mm away"
        dp = self.referee.designated_position
        if self.referee.command.startswith("BALL_PLACEMENT_") and dp is not None:
            out += f", placing to ({dp[0]:.0f}, {dp[1]:.0f})"
            if snap.ball is not None:
                d = dist_to_segment(r.x, r.y, snap.ball.x, snap.ball.y, dp[0], dp[1])
                out += f", {d:.0f} mm from the corridor's line"
        return out

    def _defense_area_offenders(self, robots: tuple[RobotView, ...]) -> set[RobotKey]:
        out: set[RobotKey] = set()
        for r in robots:
            own = self.side_of(r.team)
            keeper = self.cfg.goalkeepers.get(r.team, 0)
            if r.id != keeper and self.field.dist_to_defense_area(r.x, r.y, own) < ROBOT_RADIUS_MM:
                out.add(r.key)
            if self.field.dist_to_defense_area(r.x, r.y, -own) < ROBOT_RADIUS_MM:
                out.add(r.key)
        return out

    def _snapshot_violation(self, kind: str, r: RobotView, why: str) -> None:
        self.stats[r.team].violations[kind].count += 1
        self._log("violation", team=r.team, robot=r.id, detail=f"{kind}: {why}")

    def _judge_kickoff(self, kicking: str) -> None:
        s = self.snap
        if s is None:
            return
        inside_ok = ROBOT_RADIUS_MM - DISTANCE_TOLERANCE_MM  # centre this far into own half
        in_circle = sorted((r for r in s.robots if r.team == kicking
                            and math.hypot(r.x, r.y) < TOO_CLOSE_MM),
                           key=lambda r: math.hypot(r.x, r.y))
        allowed = in_circle[0].key if in_circle else None
        for r in s.robots:
            at = f" at ({r.x:.0f}, {r.y:.0f})"
            if self.side_of(r.team) * r.x < inside_ok:
                self._snapshot_violation("kickoff_position", r, "not in its own half" + at)
            elif math.hypot(r.x, r.y) < TOO_CLOSE_MM and r.key != allowed:
                self._snapshot_violation("kickoff_position", r, "inside the centre circle" + at)

    def _judge_penalty(self, kicking: str) -> None:
        s = self.snap
        if s is None:
            return
        defending = other(kicking)
        side = self.side_of(defending)
        keeper = self.cfg.goalkeepers.get(defending, 0)
        bx, by = (s.ball.x, s.ball.y) if s.ball is not None \
            else self.field.penalty_mark(side)
        kickers = sorted((r for r in s.robots if r.team == kicking),
                         key=lambda r: dist(r.x, r.y, bx, by))
        kicker = kickers[0].key if kickers else None
        goal_x = side * self.field.half_length
        for r in s.robots:
            if r.key == kicker:
                continue
            at = f" at ({r.x:.0f}, {r.y:.0f}), ball ({bx:.0f}, {by:.0f})"
            if r.team == defending and r.id == keeper:
                if abs(r.x - goal_x) > ROBOT_RADIUS_MM + DISTANCE_TOLERANCE_MM or \
                        abs(r.y) > self.field.goal_width / 2.0:
                    self._snapshot_violation("penalty_position", r,
                                             "keeper not on its goal line" + at)
                continue
            if side * (r.x - bx) > -(PENALTY_BEHIND_BALL_MM - DISTANCE_TOLERANCE_MM):
                self._snapshot_violation("penalty_position", r, "not 1 m behind the ball" + at)

    # -- result --------------------------------------------------------------------------------

    def result(self) -> dict[str, Any]:
        held = sum(st.possession_s for st in self.stats.values())
        teams: dict[str, Any] = {}
        for team, st in self.stats.items():
            times = st.placement_times_s
            teams[team] = {
                "play": self.cfg.plays.get(team, ""),
                "goals": st.goals,
                "possession_s": round(st.possession_s, 2),
                "possession_pct": round(100.0 * st.possession_s / held, 1) if held > 0 else None,
                "kicks": st.kicks if self.kicks_measured else None,
                "placements": {
                    "ok": st.placements_ok,
                    "failed": st.placements_failed,
                    "mean_time_s": round(sum(times) / len(times), 2) if times else None,
                    "times_s": [round(x, 2) for x in times],
                },
                "violations": {k: {"count": v.count, "seconds": round(v.seconds, 2)}
                               for k, v in st.violations.items()},
            }
        return {
            "finished": self.finished,
            "score": {t: self.stats[t].goals for t in TEAMS},
            "teams": teams,
            "loose_ball_s": round(self.loose_ball_s, 2),
            "commands": {c: {"count": self.command_counts.get(c, 0),
                             "seconds": round(self.command_seconds.get(c, 0.0), 2)}
                         for c in sorted(set(self.command_counts) | set(self.command_seconds))},
            "stages": {s: round(v, 2) for s, v in self.stage_seconds.items()},
            "events": dict(self.event_counts),
            "events_source": self.events_source,
            "interludes": {i.name: i.done for i in self.interludes},
            "stage": self.referee.stage,
            "command": self.referee.command,
            "elapsed_s": round(self.now - self.t0, 2) if self.t0 is not None else 0.0,
        }
