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
from dataclasses import dataclass
from typing import Any

from domain.field import division
from domain.rules import (
    PLACEMENT_TOLERANCE_MM,
)

# re-exported: match.config is its home; callers that import it from here keep working
from match.config import MatchConfig as MatchConfig
from match.events import EventDetector
from match.judge import Judge
from match.referee import MatchReferee
from match.rules import (
    BALL_IN_PLAY_MM,
    NO_PROGRESS_MM,
    NO_PROGRESS_S,
    PLACEMENT_STILL_MMPS,
    TOUCH_DISTANCE_MM,
    dist,
    placement_position,
)
from match.stats import TeamStats
from match.truth import TEAMS, RobotKey, Snapshot, other, parse_truth

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
class _Interlude:
    name: str
    half: int
    at: float
    done: bool = False


class Director:
    def __init__(self, config: MatchConfig | None = None, *, wall_offset_s: float = 0.0,
                 source_identifier: str | None = None) -> None:
        self.cfg = config if config is not None else MatchConfig()
        self.field = division(self.cfg.division)
        self.timing = self.cfg.timing
        self.grace = self.cfg.grace
        self.wall_offset_s = wall_offset_s
        # a live match is one of a kind; a headless one names itself (the same seed gives the
        # same log, byte for byte)
        self.referee = MatchReferee(
            source_identifier=source_identifier or f"touchline-match-{uuid.uuid4()}")
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
        self._kicks_seen: dict[RobotKey, int] = {}
        self.last_touch: RobotKey | None = None
        self._actions: list[TeleportBall] = []
        self._issued = False  # the first HALT is issued even though the referee starts in HALT
        self.judge = Judge(self)
        self.events = EventDetector(self)
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
            self.events.frame(snap)
        if self.running:
            self._running_checks()
        self._advance()
        if snap is not None:
            tdt = 0.0 if self._last_truth_now is None else min(now - self._last_truth_now,
                                                               MAX_DT_S)
            self._last_truth_now = now
            self.judge.frame(snap, max(0.0, tdt))
        self._update_timers()
        return self._actions

    # -- bookkeeping ---------------------------------------------------------------------------

    def _log(self, kind: str, team: str | None = None, robot: int | None = None,
             detail: str = "") -> None:
        self.timeline.append({
            # (t0 is None before the start; 0.0 is a start, on the headless virtual clock)
            "t": round(self.now - self.t0, 3) if self.t0 is not None else 0.0,
            "kind": kind, "team": team,
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
            self.judge.new_halt()
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
        self.events.running_resumed()
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
                self.judge.kickoff(step.team)
            elif step.set_piece == "penalty":
                self.judge.penalty(step.team)
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
        if s is not None and s.ball is not None and self.events.ball_outside(s):
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

    def _count_event(self, kind: str) -> None:
        self.events.count(kind)

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
            "events": dict(self.events.counts),
            "events_source": self.events.source,
            "interludes": {i.name: i.done for i in self.interludes},
            "stage": self.referee.stage,
            "command": self.referee.command,
            "elapsed_s": round(self.now - self.t0, 2) if self.t0 is not None else 0.0,
        }
