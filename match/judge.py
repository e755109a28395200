"""The match's judge: the violations of the rules on every truth frame (continuous episodes:
HALT, STOP, placement and set-piece distances, defence areas), at one instant (kick-off and
penalty positions) and from events (collisions), and possession. It only reads the game
(``Game``) and writes the statistics and the timeline."""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any, Protocol

from domain.field import Field
from domain.rules import COLLISION_SPEED_MPS, ROBOT_RADIUS_MM
from match.config import MatchConfig
from match.referee import MatchReferee
from match.rules import (
    COLLISION_DRAWN_MPS,
    DISTANCE_TOLERANCE_MM,
    HALT_SPEED_LIMIT_MMPS,
    PENALTY_BEHIND_BALL_MM,
    POSSESSION_DISTANCE_MM,
    STOP_SPEED_LIMIT_MMPS,
    TOO_CLOSE_MM,
    Grace,
    dist,
    dist_to_segment,
)
from match.stats import EPISODE_KINDS, TeamStats
from match.truth import RobotKey, RobotView, Snapshot, num, other, robot_key


class Game(Protocol):
    """What the judge reads of the game (the director) and where it writes."""

    referee: MatchReferee
    now: float
    command_since: float
    set_piece: tuple[str, str, float] | None
    running_since: float
    grace: Grace
    cfg: MatchConfig
    field: Field
    snap: Snapshot | None
    stats: dict[str, TeamStats]
    loose_ball_s: float

    @property
    def running(self) -> bool: ...

    def side_of(self, team: str) -> int: ...

    def _log(self, kind: str, team: str | None = None, robot: int | None = None,
             detail: str = "") -> None: ...

    def _count_event(self, kind: str) -> None: ...


class Judge:
    def __init__(self, game: Game) -> None:
        self.game = game
        self._active: dict[str, set[RobotKey]] = {k: set() for k in EPISODE_KINDS}
        #: since when each robot of the non-placing team is inside the placement corridor
        self._in_corridor_since: dict[RobotKey, float] = {}
        #: robots already counted for moving during this HALT
        self._halt_flagged: set[RobotKey] = set()

    def new_halt(self) -> None:
        """A new HALT: each robot still moving counts once again."""
        self._halt_flagged = set()

    def collision(self, ev: Mapping[str, Any]) -> None:
        self.game._count_event("collision")
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
            self.game.stats[team].violations["collision"].count += 1
            self.game._log("violation", team=team, robot=rid,
                      detail=f"collision at {rel:.2f} m/s relative")

    def _episodes(self, kind: str, offenders: set[RobotKey], dt: float,
                  latched: set[RobotKey] | None = None) -> None:
        prev = self._active[kind]
        # in robot order: a set of (team, id) iterates in an order of its string hashes,
        # which differ from process to process (two offenders in one frame were logged in
        # either order)
        for key in sorted(offenders):
            v = self.game.stats[key[0]].violations[kind]
            v.seconds += dt
            if key not in prev and (latched is None or key not in latched):
                v.count += 1
                self.game._log("violation", team=key[0], robot=key[1],
                          detail=f"{kind}{self._where(key)}")
        if latched is not None:
            latched |= offenders
        self._active[kind] = offenders

    def frame(self, snap: Snapshot, dt: float) -> None:
        g = self.game.grace
        cmd = self.game.referee.command
        since = self.game.now - self.game.command_since
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
                and self.game.referee.designated_position is not None:
            # the rules' interference: a robot of the other team inside the corridor for
            # more than 2 s on end (a robot crossing it, or passed by the ball, is not)
            placing = cmd[len("BALL_PLACEMENT_"):].lower()
            px, py = self.game.referee.designated_position
            inside = {r.key for r in robots if r.team != placing
                      and dist_to_segment(r.x, r.y, ball.x, ball.y, px, py) < TOO_CLOSE_MM}
            entered = self._in_corridor_since
            for key in list(entered):
                if key not in inside:
                    del entered[key]
            for key in inside:
                entered.setdefault(key, self.game.now)
            found["placement_distance"] = {k for k in inside
                                           if self.game.now - entered[k] > g.placement_distance}
        else:
            self._in_corridor_since.clear()
        sp = self.game.set_piece
        if sp is not None and sp[1] in ("kickoff", "free") and ball is not None \
                and self.game.now - sp[2] >= g.set_piece_distance:
            found["set_piece_distance"] = {r.key for r in robots if r.team != sp[0]
                                           and dist(r.x, r.y, ball.x, ball.y) < TOO_CLOSE_MM}
        if self.game.running and self.game.now - self.game.running_since >= g.defense_area:
            found["defense_area"] = self._defense_area_offenders(robots)
        for kind in EPISODE_KINDS:
            self._episodes(kind, found[kind], dt,
                           self._halt_flagged if kind == "halt_moving" else None)
        if self.game.running and ball is not None and robots:
            d, r = min(((dist(r.x, r.y, ball.x, ball.y), r) for r in robots),
                       key=lambda p: p[0])
            if d <= POSSESSION_DISTANCE_MM:
                self.game.stats[r.team].possession_s += dt
            else:
                self.game.loose_ball_s += dt

    def _where(self, key: RobotKey) -> str:
        """Where an episode starts: the robot (position, speed), the ball and, during a
        placement, the designated position; mm and m/s on fieldsim's ground truth."""
        snap = self.game.snap
        if snap is None:
            return ""
        r = next((r for r in snap.robots if r.key == key), None)
        if r is None:
            return ""
        out = f": robot at ({r.x:.0f}, {r.y:.0f}) {r.speed / 1000.0:.2f} m/s"
        if snap.ball is not None:
            b = snap.ball
            out += f", ball at ({b.x:.0f}, {b.y:.0f}) {dist(r.x, r.y, b.x, b.y):.0f} mm away"
        dp = self.game.referee.designated_position
        if self.game.referee.command.startswith("BALL_PLACEMENT_") and dp is not None:
            out += f", placing to ({dp[0]:.0f}, {dp[1]:.0f})"
            if snap.ball is not None:
                d = dist_to_segment(r.x, r.y, snap.ball.x, snap.ball.y, dp[0], dp[1])
                out += f", {d:.0f} mm from the corridor's line"
        return out

    def _defense_area_offenders(self, robots: tuple[RobotView, ...]) -> set[RobotKey]:
        out: set[RobotKey] = set()
        f = self.game.field
        for r in robots:
            own = self.game.side_of(r.team)
            keeper = self.game.cfg.goalkeepers.get(r.team, 0)
            if r.id != keeper and f.dist_to_defense_area(r.x, r.y, own) < ROBOT_RADIUS_MM:
                out.add(r.key)
            if f.dist_to_defense_area(r.x, r.y, -own) < ROBOT_RADIUS_MM:
                out.add(r.key)
        return out

    def _snapshot_violation(self, kind: str, r: RobotView, why: str) -> None:
        self.game.stats[r.team].violations[kind].count += 1
        self.game._log("violation", team=r.team, robot=r.id, detail=f"{kind}: {why}")

    def kickoff(self, kicking: str) -> None:
        """The positions at a kick-off's NORMAL_START, judged (violations counted)."""
        for r, why in self.kickoff_issues(kicking):
            self._snapshot_violation("kickoff_position", r, why)

    def kickoff_issues(self, kicking: str) -> list[tuple[RobotView, str]]:
        """The robots out of place for a kick-off by ``kicking``, and why (none: ready)."""
        s = self.game.snap
        if s is None:
            return []
        inside_ok = ROBOT_RADIUS_MM - DISTANCE_TOLERANCE_MM  # centre this far into own half
        in_circle = sorted((r for r in s.robots if r.team == kicking
                            and math.hypot(r.x, r.y) < TOO_CLOSE_MM),
                           key=lambda r: math.hypot(r.x, r.y))
        allowed = in_circle[0].key if in_circle else None
        out: list[tuple[RobotView, str]] = []
        for r in s.robots:
            at = f" at ({r.x:.0f}, {r.y:.0f})"
            if self.game.side_of(r.team) * r.x < inside_ok:
                out.append((r, "not in its own half" + at))
            elif math.hypot(r.x, r.y) < TOO_CLOSE_MM and r.key != allowed:
                out.append((r, "inside the centre circle" + at))
        return out

    def penalty(self, kicking: str) -> None:
        """The positions at a penalty's NORMAL_START, judged (violations counted)."""
        for r, why in self.penalty_issues(kicking):
            self._snapshot_violation("penalty_position", r, why)

    def penalty_issues(self, kicking: str) -> list[tuple[RobotView, str]]:
        """The robots out of place for a penalty by ``kicking``, and why (none: ready): the
        defending keeper on its goal line, every other robot but the kicker 1 m behind the
        ball."""
        s = self.game.snap
        if s is None:
            return []
        defending = other(kicking)
        side = self.game.side_of(defending)
        keeper = self.game.cfg.goalkeepers.get(defending, 0)
        bx, by = (s.ball.x, s.ball.y) if s.ball is not None \
            else self.game.field.penalty_mark(side)
        kickers = sorted((r for r in s.robots if r.team == kicking),
                         key=lambda r: dist(r.x, r.y, bx, by))
        kicker = kickers[0].key if kickers else None
        goal_x = side * self.game.field.half_length
        out: list[tuple[RobotView, str]] = []
        for r in s.robots:
            if r.key == kicker:
                continue
            at = f" at ({r.x:.0f}, {r.y:.0f}), ball ({bx:.0f}, {by:.0f})"
            if r.team == defending and r.id == keeper:
                if abs(r.x - goal_x) > ROBOT_RADIUS_MM + DISTANCE_TOLERANCE_MM or \
                        abs(r.y) > self.game.field.goal_width / 2.0:
                    out.append((r, "keeper not on its goal line" + at))
                continue
            if side * (r.x - bx) > -(PENALTY_BEHIND_BALL_MM - DISTANCE_TOLERANCE_MM):
                out.append((r, "not 1 m behind the ball" + at))
        return out
