"""One run: a scenario (placed, refereed, recorded, judged, checked) or a whole match (the
match director's game flow), each on the headless engine. Both are plain functions of a
picklable spec, so a process pool or a Dask worker runs them alike and returns plain data.
"""

from __future__ import annotations

import math
import os
import time
import traceback
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from backend.params.model import PLAYS
from domain.field import division
from fieldsim.config import SimConfig
from fieldsim.world import Team as SimTeam
from match.director import Director, MatchConfig
from match.judge import Judge
from match.referee import MatchReferee
from match.rules import BALL_IN_PLAY_MM, Grace
from match.stats import TeamStats
from match.truth import Snapshot, parse_truth

from .checks import BUILTIN, Result, load_custom, run_check
from .headless import EPOCH_UNIX_S, SIDES, Engine, RunError, station_params
from .record import Run, RunBuilder
from .scenario import Scenario

#: a run's wall-clock limit by default (a run that hangs fails on its own)
MAX_WALL_S = 600.0
#: a NORMAL_START ``when = "ready"`` comes once the robots have been in place this long, as
#: the game controller continues (its ``preparation-time-before-resume``, 2 s)
READY_HOLD_S = 2.0
#: a penalty ends this long after its NORMAL_START (the game controller's PENALTY_KICK_FAILED,
#: "Time run out": its prepare timeout): the run ends there, as ``end_on`` would
PENALTY_S = 10.0


@dataclass(frozen=True)
class Entrant:
    """Who plays: a play (built-in, or a team play's file stem in ``team_dir``) with
    parameter overrides (dotted names), under a label for the report."""

    play: str | None = None
    params: Mapping[str, Any] = field(default_factory=dict)
    team_dir: str | None = None
    label: str = ""

    def name(self) -> str:
        if self.label:
            return self.label
        extra = ",".join(f"{k}={v}" for k, v in sorted(self.params.items()))
        # no play given: each scenario runs the play its file names (not "?" in the report)
        return (self.play or "each scenario's play") + (f"[{extra}]" if extra else "")


# -- scenarios --------------------------------------------------------------------------------


class _ScenarioGame:
    """What the match judge reads of a game (``match.judge.Game``), for a scenario: the
    scenario's referee, no game flow of its own."""

    def __init__(self, field_: Any, keepers: dict[str, int], blue_on_positive: bool,
                 on_log: Any) -> None:
        self.referee = MatchReferee(source_identifier="touchline-evaluate")
        self.referee.blue_team_on_positive_half = blue_on_positive
        self.referee.blue.goalkeeper = keepers["blue"]
        self.referee.yellow.goalkeeper = keepers["yellow"]
        self.now = 0.0
        self.command_since = 0.0
        self.set_piece: tuple[str, str, float] | None = None
        self.running_since = 0.0
        self.grace = Grace()
        self.cfg = MatchConfig(goalkeepers=keepers, interludes=False)
        self.field = field_
        self.snap: Snapshot | None = None
        self.stats = {t: TeamStats() for t in SIDES}
        self.loose_ball_s = 0.0
        self.is_running = True
        self._on_log = on_log
        self.anchor: tuple[float, float] | None = None

    @property
    def running(self) -> bool:
        return self.is_running

    def side_of(self, team: str) -> int:
        blue_pos = self.referee.blue_team_on_positive_half
        return 1 if (team == "blue") == blue_pos else -1

    def _log(self, kind: str, team: str | None = None, robot: int | None = None,
             detail: str = "") -> None:
        self._on_log(kind, team, robot, detail)

    def _count_event(self, kind: str) -> None:
        pass


class ScenarioRun(Engine):
    O_JUDGE = Engine.O_SAMPLE

    def __init__(self, sc: Scenario, entrant: Entrant, log_path: str | None,
                 max_wall_s: float | None = MAX_WALL_S) -> None:
        self.sc = sc
        play = entrant.play or sc.play
        if play is None:
            raise RunError("no play: give one (--play) or name it in the scenario's [ours]")
        self.play = play
        self.sign = 1.0 if sc.our_side == "negative-x" else -1.0
        self.ours = sc.our_team
        self.theirs = "yellow" if sc.our_team == "blue" else "blue"
        cfg = SimConfig(seed=sc.seed, division=sc.division, blue=0, yellow=0,
                        cameras=sc.cameras, blue_on_positive_half=(
                            (sc.our_team == "blue") == (sc.our_side == "positive-x")))
        for k, v in sc.sim.items():
            setattr(cfg, k, int(v) if k == "generation" else v)
        super().__init__(cfg, sc.vision_latency_ms / 1000.0, sc.command_latency_ms / 1000.0,
                         log_path, {"our_team": self.ours, "scenario": sc.name,
                                    "play": play, "seed": sc.seed}, max_wall_s)
        w = self.world
        for r in sc.robots:
            colour = self.ours if r.team == "ours" else self.theirs
            x, y = self.sign * r.x, self.sign * r.y
            heading = r.heading if self.sign > 0 else r.heading + math.pi
            w.add_robot(SimTeam.BLUE if colour == "blue" else SimTeam.YELLOW, r.id, x, y,
                        heading)
        if sc.ball is not None:
            b = sc.ball
            w.teleport_ball(self.sign * b.x, self.sign * b.y, self.sign * b.vx,
                            self.sign * b.vy)
        else:
            w.teleport_ball(0.0, 0.0)
        params = station_params({**dict(sc.params), **dict(entrant.params),
                                 "strategy.play": play}, self.ours, sc.our_side)
        self.our_side = self.add_side(self.ours, params, record=True)
        if play not in PLAYS:
            self.our_side.use_team_play(entrant.team_dir, play)
            self.our_side.strategy.task = dict(sc.task)
        if sc.opponent_play is not None:
            if sc.opponent_play not in PLAYS:
                raise RunError(f"opponent play {sc.opponent_play!r}: an opponent plays a "
                               f"built-in play ({', '.join(PLAYS)})")
            their_side = "positive-x" if sc.our_side == "negative-x" else "negative-x"
            self.add_side(self.theirs, station_params(
                {**dict(sc.opponent_params), "strategy.play": sc.opponent_play}, self.theirs,
                their_side, "opponent.params"), record=False)
        for t in sc.operator_targets:
            self.our_side.operator_target(t.id, self.sign * t.x * 1000.0,
                                          self.sign * t.y * 1000.0,
                                          None if t.heading is None else
                                          t.heading if self.sign > 0 else t.heading + math.pi)
        self.rb = RunBuilder(sc.task)
        # the goalkeepers the referee names (and the judge allows in their defence areas)
        keepers = {self.ours: 0, self.theirs: 0}
        self.game = _ScenarioGame(division(sc.division), keepers,
                                  cfg.blue_on_positive_half, self._judge_log)
        self.judge = Judge(self.game)
        self.refereed = bool(sc.referee)
        if not self.refereed:
            self.game.referee.command = "FORCE_START"  # judged as running play, never sent
        self._last_touch = w.last_touch
        self._kicks = {k: r.kicks for k, r in w.robots.items()}
        self._event_seq = 0
        self.ended_by = ""
        self._given: set[int] = set()  # referee steps given (a ready one may come early)
        self._ready_since: float | None = None

    # -- frames ---------------------------------------------------------------------------

    def _ours(self, colour: str | None) -> str | None:
        return None if colour is None else "ours" if colour == self.ours else "theirs"

    def _judge_log(self, kind: str, team: str | None, robot: int | None, detail: str) -> None:
        if kind != "violation":
            return
        vk = detail.split(":")[0].split(" ")[0]
        self.rb.event(self.clock.t, "violation", self._ours(team), robot, vk, text=detail)

    def _sample(self) -> None:
        w = self.world
        s = self.sign
        b = w.ball
        robots = {}
        for (team, rid), r in w.robots.items():
            side = "ours" if team.label == self.ours else "theirs"
            heading = r.theta if s > 0 else math.atan2(-math.sin(r.theta), -math.cos(r.theta))
            robots[(side, rid)] = (s * r.x, s * r.y, heading, s * r.vx, s * r.vy, r.omega)
        self.rb.sample(self.clock.t, (s * b.x, s * b.y, s * b.vx, s * b.vy), robots)
        truth = w.truth()
        snap = parse_truth(truth)
        g = self.game
        dt = self.clock.t - g.now
        g.now = self.clock.t
        g.snap = snap
        self._set_piece_progress(snap)
        self.judge.frame(snap, max(0.0, dt))

    def _set_piece_progress(self, snap: Snapshot) -> None:
        g = self.game
        if g.set_piece is None or snap.ball is None:
            return
        if g.anchor is None:
            g.anchor = (snap.ball.x, snap.ball.y)
        elif math.hypot(snap.ball.x - g.anchor[0], snap.ball.y - g.anchor[1]) > BALL_IN_PLAY_MM:
            g.set_piece = None  # the ball is in play
            g.anchor = None
            g.is_running = True
            g.running_since = g.now

    def on_step(self) -> None:
        w = self.world
        t = self.clock.t
        if w.last_touch != self._last_touch:
            self._last_touch = w.last_touch
            if w.last_touch is not None:
                team, rid = w.last_touch
                self.rb.event(t, "touch", self._ours(team.label), rid)
        if w.stats.kicks:
            for key, r in w.robots.items():
                if r.kicks != self._kicks.get(key, 0):
                    self._kicks[key] = r.kicks
                    self.rb.event(t, "kick", self._ours(key[0].label), key[1],
                                  chip=r.last_kick_chip)
        while w.events and w.events[-1]["seq"] > self._event_seq:
            fresh = [e for e in w.events if e["seq"] > self._event_seq]
            self._event_seq = fresh[-1]["seq"]
            for ev in fresh:
                self._world_event(ev)

    def _world_event(self, ev: Mapping[str, Any]) -> None:
        kind = ev["kind"]
        t = float(ev["t"])
        if kind == "collision":
            a, b = ev["a"], ev["b"]
            for me, other in ((a, b), (b, a)):
                self.rb.event(t, "collision", self._ours(me["team"]), me["id"],
                              other_team=self._ours(other["team"]), other=other["id"],
                              relative_speed_mps=ev["relative_speed_mps"])
            self.judge.collision(ev)
            return
        lt = ev.get("last_touch")
        team = self._ours(lt["team"]) if isinstance(lt, Mapping) else None
        rid = lt["id"] if isinstance(lt, Mapping) else None
        if kind == "goal":
            positive = ev.get("side") == "positive"
            # the goal on the positive x side is ours when our goal is at positive x
            ours = positive == (self.sign < 0)
            self.rb.event(t, "goal", team, rid, "ours" if ours else "theirs")
        elif kind == "ball_out":
            self.rb.event(t, "ball_out", team, rid, str(ev.get("line", "")))
        if kind in self.sc.end_on:
            self.ended_by = kind
            self.stopped = True

    # -- referee and actions ----------------------------------------------------------------

    def _referee_step(self, i: int) -> None:
        if i in self._given:  # (a NORMAL_START given when ready: its latest time passes)
            return
        self._given.add(i)
        step = self.sc.referee[i]
        ref = self.game.referee
        colour = None if step.team is None else self.ours if step.team == "ours" else self.theirs
        cmd = step.command if colour is None else f"{step.command}_{colour.upper()}"
        pos = None
        if step.designated is not None:
            pos = (self.sign * step.designated[0] * 1000.0, self.sign * step.designated[1] * 1000.0)
            self.rb.designated = step.designated
        ref.give(cmd, pos, now_us=self.clock.us())
        g = self.game
        g.command_since = self.clock.t
        g.anchor = None
        if cmd == "HALT":
            self.judge.new_halt()
        if step.command == "FORCE_START":
            g.set_piece, g.is_running, g.running_since = None, True, self.clock.t
        elif step.command == "NORMAL_START":
            prev = self.sc.referee[i - 1]
            kind = "kickoff" if prev.command == "PREPARE_KICKOFF" else "penalty"
            kicker = self.ours if prev.team == "ours" else self.theirs
            if kind == "kickoff":
                self.judge.kickoff(kicker)
            else:
                self.judge.penalty(kicker)
                self.at(self.clock.t + PENALTY_S, self.O_REFEREE, self._penalty_over)
            g.set_piece, g.is_running = (kicker, kind, self.clock.t), False
        elif step.command == "DIRECT_FREE":
            g.set_piece, g.is_running = (colour or "", "free", self.clock.t), False
        elif step.command.startswith("PREPARE_"):
            kind = "kickoff" if "KICKOFF" in step.command else "penalty"
            g.set_piece, g.is_running = (colour or "", kind, self.clock.t), False
        else:
            g.set_piece, g.is_running = None, False
        self.rb.event(self.clock.t, "referee", step.team, None, step.command,
                      designated=step.designated)
        self.send_referee(ref)

    def _penalty_over(self) -> None:
        self.ended_by = "penalty_time"
        self.stopped = True

    def _watch_ready(self, i: int) -> None:
        """A NORMAL_START ``when = "ready"`` (step ``i``): given once the robots have kept the
        positions its PREPARE_* asks for ``READY_HOLD_S`` (the judge's own rule, so given
        early it finds nothing), or at its ``at`` whatever they do (the game controller's
        prepare timeout). Looked at once a camera frame while the PREPARE_* holds."""
        if i in self._given or i - 1 not in self._given:
            self._ready_since = None
            return
        prev = self.sc.referee[i - 1]
        kicker = self.ours if prev.team == "ours" else self.theirs
        issues = (self.judge.kickoff_issues(kicker) if prev.command == "PREPARE_KICKOFF"
                  else self.judge.penalty_issues(kicker))
        t = self.clock.t
        if issues or self.game.snap is None:
            self._ready_since = None
        elif self._ready_since is None:
            self._ready_since = t
        elif t - self._ready_since >= READY_HOLD_S - 1e-9:
            self._ready_since = None
            self._referee_step(i)
            return
        if t < self.sc.referee[i].at:
            self.at(t + 1.0 / self.sim.camera_hz, self.O_REFEREE, lambda: self._watch_ready(i))

    def _action(self, i: int) -> None:
        a = self.sc.actions[i]
        s = self.sign
        if a.ball is not None:
            b = a.ball
            self.world.teleport_ball(s * b.x, s * b.y, s * b.vx, s * b.vy)
            self._last_touch = None
        elif a.robot is not None:
            r = a.robot
            colour = self.ours if r.team == "ours" else self.theirs
            self.world.teleport_robot(SimTeam.BLUE if colour == "blue" else SimTeam.YELLOW,
                                      r.id, s * r.x, s * r.y,
                                      r.heading if s > 0 else r.heading + math.pi)

    # -- running it -------------------------------------------------------------------------

    def run(self) -> Run:
        sc = self.sc
        for i, a in enumerate(sc.actions):
            self.at(a.at, self.O_ACTION, lambda i=i: self._action(i))  # type: ignore[misc]
        for i, step in enumerate(sc.referee):
            self.at(step.at, self.O_REFEREE, lambda i=i: self._referee_step(i))  # type: ignore[misc]
            if step.when_ready:  # watched from its PREPARE_* on (given just before)
                self.at(sc.referee[i - 1].at, self.O_REFEREE + 1,
                        lambda i=i: self._watch_ready(i))  # type: ignore[misc]
        if self.refereed:
            first = sc.referee[0].at
            self.every(1.0 / 10.0, self.O_REFEREE,
                       lambda: self.send_referee(self.game.referee), first + 0.1)
        self.every(1.0 / self.sim.camera_hz, self.O_JUDGE, self._sample)
        self.start_parts()
        try:
            self.run_until(sc.duration_s)
        finally:
            self.close()
        self.rb.ended_by = self.ended_by
        for t, rid, why in self.our_side.team_errors:
            self.rb.event(t, "team_error", "ours", rid if rid >= 0 else None, why)
        return self.rb.build(self.clock.t)


def _scenario_checks(sc: Scenario, checks_py: str | None) -> dict[str, Any]:
    fns: dict[str, Any] = dict(BUILTIN)
    if checks_py is not None and any(c.name not in BUILTIN for c in sc.checks):
        fns.update(load_custom(checks_py))
    return fns


def score_run(sc: Scenario, run: Run, checks_py: str | None = None) -> dict[str, Any]:
    """Every check of the scenario on the run: pass (all passed) and the weighted score."""
    fns = _scenario_checks(sc, checks_py)
    out = []
    total_w = sum(c.weight for c in sc.checks) or 1.0
    score = 0.0
    for c in sc.checks:
        fn = fns.get(c.name)
        res = (run_check(fn, run, c.params) if fn is not None else
               Result(False, 0.0, f"no check named {c.name!r}"))
        score += c.weight * res.score
        out.append({"name": c.name, "label": c.label or c.name, "weight": c.weight,
                    **res.as_dict()})
    return {"passed": all(c["passed"] for c in out), "score": round(score / total_w, 4),
            "checks": out}


@dataclass(frozen=True)
class ScenarioTask:
    """One run of one scenario (picklable: what a pool or cluster worker gets)."""

    scenario: Scenario
    run_index: int
    entrant: Entrant
    log_path: str | None  # where the SSL log goes (None: not recorded)
    checks_py: str | None = None
    ship_log: bool = False  # return the log's bytes (a cluster worker on another machine)
    max_wall_s: float = MAX_WALL_S

    @property
    def name(self) -> str:
        sc = self.scenario
        return sc.name if sc.runs == 1 else f"{sc.name}#{self.run_index + 1}"


def _run_log_path(log_path: str | None, ship_log: bool) -> str | None:
    """Where a run writes its SSL log: the report's path, or a temporary file on a worker that
    ships the log back to the report's machine (``ship_log``)."""
    if ship_log and log_path is not None:
        import tempfile
        fd, log_path = tempfile.mkstemp(prefix="evaluate-", suffix=".log")
        os.close(fd)
        os.unlink(log_path)
    return log_path


def run_scenario_task(task: ScenarioTask) -> dict[str, Any]:
    """Runs one scenario run; never raises: an error is a failed run that says why."""
    sc = task.scenario.for_run(task.run_index)
    wall0 = time.perf_counter()
    log_path = _run_log_path(task.log_path, task.ship_log)
    res: dict[str, Any] = {
        "kind": "scenario", "name": task.name, "scenario": sc.name, "title": sc.title,
        "run": task.run_index, "seed": sc.seed, "entrant": task.entrant.name(),
        "play": task.entrant.play or sc.play, "log": task.log_path, "error": None,
    }
    try:
        if log_path is not None:
            Path(log_path).parent.mkdir(parents=True, exist_ok=True)
        runner = ScenarioRun(sc, task.entrant, log_path, task.max_wall_s)
        run = runner.run()
        res.update(score_run(sc, run, task.checks_py))
        res["sim_s"] = round(run.duration_s, 3)
        res["ended_by"] = run.ended_by
        errs = run.of("team_error")
        # the file's own error (with its line) says most; else why its robots stood still
        files = [e for e in errs if e.robot is None]
        res["team_error"] = (files or errs)[0].detail if errs else None
        if files:  # the play failed (not a tick held): no credit for what its stopped robots
            # "did" (a crashed keeper standing at the goal centre "saved" the shots that missed)
            res.update(passed=False, score=0.0)
        res["events"] = _events_summary(run)
    except RunError as exc:
        res.update(passed=False, score=0.0, checks=[], error=str(exc))
    except Exception as exc:  # a bug: fail this run with the traceback, not the series
        res.update(passed=False, score=0.0, checks=[],
                   error=f"{type(exc).__name__}: {exc}\n{traceback.format_exc(limit=8)}")
    res["wall_s"] = round(time.perf_counter() - wall0, 3)
    if task.ship_log and log_path is not None and os.path.exists(log_path):
        with open(log_path, "rb") as f:
            res["log_bytes"] = f.read()
        os.unlink(log_path)
    return res


def _events_summary(run: Run) -> list[dict[str, Any]]:
    keep = ("goal", "ball_out", "collision", "referee", "violation", "kick", "team_error")
    out = []
    for e in run.events:
        if e.kind not in keep or (e.kind == "collision" and e.team != "ours"):
            continue
        out.append({"t": round(e.t, 3), "kind": e.kind, "team": e.team, "robot": e.robot,
                    "detail": str(e.data.get("text", e.detail))})
    return out[:200]


# -- matches ----------------------------------------------------------------------------------


@dataclass(frozen=True)
class MatchTask:
    """One match of a series: ``blue`` against ``yellow`` (each an entrant), ``half_s`` a half,
    ``seed`` for fieldsim, ``blue_on_positive`` for the first half's sides."""

    name: str
    blue: Entrant
    yellow: Entrant
    seed: int
    half_s: float
    blue_on_positive: bool = False
    log_path: str | None = None
    ship_log: bool = False
    division: str = "B"
    robots: int = 6
    cameras: int = 4  #: fieldsim's default (make match); 2 halves the vision work
    #: every speed controller's limit (m/s), as ``make match`` sets it (None: the defaults)
    robot_speed_mps: float | None = 2.0
    interludes: bool = True
    max_wall_s: float = MAX_WALL_S * 4

    @property
    def labels(self) -> dict[str, str]:
        return {"blue": self.blue.name(), "yellow": self.yellow.name()}


class MatchRun(Engine):
    O_DIRECTOR = Engine.O_REFEREE

    def __init__(self, task: MatchTask, log_path: str | None) -> None:
        self.task = task
        cfg = SimConfig(seed=task.seed, division=task.division, blue=task.robots,
                        yellow=task.robots, blue_on_positive_half=task.blue_on_positive,
                        cameras=task.cameras)
        super().__init__(cfg, 0.0, 0.0, log_path,
                         {"our_team": "blue", "match": task.name, "seed": task.seed,
                          "blue": task.blue.name(), "yellow": task.yellow.name()},
                         task.max_wall_s)
        speed: dict[str, Any] = {}
        if task.robot_speed_mps is not None:
            speed = {f"control.params.{c}.v_mps": task.robot_speed_mps
                     for c in ("algorithm1", "algorithm2", "proportional")}
        for colour, ent in (("blue", task.blue), ("yellow", task.yellow)):
            if ent.play is None:
                raise RunError(f"{colour}: no play")
            positive = task.blue_on_positive == (colour == "blue")
            params = station_params({**speed, **dict(ent.params), "strategy.play": ent.play},
                                    colour, "positive-x" if positive else "negative-x",
                                    f"{colour}.params")
            side = self.add_side(colour, params, record=colour == "blue")
            if ent.play not in PLAYS:
                side.use_team_play(ent.team_dir, ent.play)
        self.director = Director(MatchConfig(
            half_s=task.half_s, division=task.division, blue_on_positive=task.blue_on_positive,
            plays=task.labels, interludes=task.interludes), wall_offset_s=float(EPOCH_UNIX_S),
            source_identifier=f"touchline-evaluate-{task.name}-seed-{task.seed}")
        self._revision = -1

    def _direct(self) -> None:
        d = self.director
        for tp in d.tick(self.clock.t, self.world.truth()):
            self.world.teleport_ball(tp.x / 1000.0, tp.y / 1000.0)
        if d.revision != self._revision:
            self._revision = d.revision
            self.send_referee(d.referee)
        if d.finished:
            self.stopped = True

    def run(self) -> dict[str, Any]:
        self.every(1.0 / self.sim.camera_hz, self.O_DIRECTOR, self._direct)
        self.every(1.0 / 10.0, self.O_DIRECTOR, lambda: self.send_referee(self.director.referee),
                   0.05)
        self.start_parts()
        bound = self.task.half_s * 2 * 3 + 300.0  # like the real match's own bound
        try:
            self.run_until(bound)
        finally:
            self.close()
        res = self.director.result()
        res["timeline"] = self.director.timeline[-400:]
        res["team_errors"] = {c: [{"t": round(t, 3), "robot": r, "why": w}
                                  for t, r, w in s.team_errors[:20]]
                              for c, s in self.sides.items() if s.team_errors}
        res["sim_s"] = round(self.clock.t, 3)
        return res


def run_match_task(task: MatchTask) -> dict[str, Any]:
    """Plays one match; never raises (an error is a match without a result that says why)."""
    wall0 = time.perf_counter()
    log_path = _run_log_path(task.log_path, task.ship_log)
    out: dict[str, Any] = {"kind": "match", "name": task.name, "seed": task.seed,
                           "blue": task.blue.name(), "yellow": task.yellow.name(),
                           "blue_on_positive": task.blue_on_positive, "log": task.log_path,
                           "error": None}
    try:
        if log_path is not None:
            Path(log_path).parent.mkdir(parents=True, exist_ok=True)
        res = MatchRun(task, log_path).run()
        out["result"] = res
        out["score"] = res["score"]
        out["sim_s"] = res["sim_s"]
        if not res.get("finished"):
            out["error"] = "the match did not finish in its time bound"
    except RunError as exc:
        out["error"] = str(exc)
    except Exception as exc:
        out["error"] = f"{type(exc).__name__}: {exc}\n{traceback.format_exc(limit=8)}"
    out["wall_s"] = round(time.perf_counter() - wall0, 3)
    if task.ship_log and log_path is not None and os.path.exists(log_path):
        with open(log_path, "rb") as f:
            out["log_bytes"] = f.read()
        os.unlink(log_path)
    return out
