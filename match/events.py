"""The match's event detection: goals, balls out and collisions, from fieldsim's events (each
handled once, by sequence number) or, with a fieldsim that reports none, from the ball crossing
a line in running play; and the safety net for a ball left outside. What follows an event (a
kick-off, a placement and free kick) is the game flow's: the director's ``_goal`` and
``_ball_out``."""

from __future__ import annotations

from collections.abc import Mapping
from typing import TYPE_CHECKING, Any, Protocol

from domain.field import Field
from domain.rules import BALL_RADIUS_MM
from match.truth import RobotKey, Snapshot, num, robot_key

if TYPE_CHECKING:
    from match.judge import Judge


class Game(Protocol):
    """What the detector reads of the game (the director) and what it calls there."""

    snap: Snapshot | None
    last_touch: RobotKey | None
    field: Field
    now: float
    judge: Judge

    @property
    def running(self) -> bool: ...

    def _log(self, kind: str, team: str | None = None, robot: int | None = None,
             detail: str = "") -> None: ...

    def _goal(self, side: int, last: RobotKey | None) -> None: ...

    def _ball_out(self, line: str, x: float, y: float, last: RobotKey | None) -> None: ...


class EventDetector:
    def __init__(self, game: Game) -> None:
        self.game = game
        #: every event counted by kind (goal, ball_out, collision, no_progress, ...)
        self.counts: dict[str, int] = {}
        #: who reports goals and balls out: "fieldsim" (events) or "director" (self-detected)
        self.source: str | None = None
        self._last_seq = -1
        self._seen_unsequenced: set[tuple[Any, ...]] = set()
        self._outside_since: float | None = None
        self._inside_in_running = False

    def running_resumed(self) -> None:
        """Play runs again: a ball outside is judged afresh."""
        self._outside_since = None
        self._inside_in_running = False

    def count(self, kind: str) -> None:
        self.counts[kind] = self.counts.get(kind, 0) + 1

    def frame(self, snap: Snapshot) -> None:
        if snap.events is None:
            return  # goals and balls out are then seen in _running_checks
        self.source = "fieldsim"
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
        s = self.game.snap
        bx = s.ball.x if s is not None and s.ball is not None else 0.0
        by = s.ball.y if s is not None and s.ball is not None else 0.0
        x, y = num(ev.get("x")), num(ev.get("y"))
        if kind == "collision":
            self.game.judge.collision(ev)
            return
        if kind not in ("goal", "ball_out"):
            return
        self.count(str(kind))
        if not self.game.running:
            self.game._log(f"{kind}_ignored", detail="not in running play")
            return
        last = robot_key(ev.get("last_touch")) if "last_touch" in ev else self.game.last_touch
        if kind == "goal":
            side_txt = ev.get("side")
            if side_txt in ("positive", "negative"):
                side = 1 if side_txt == "positive" else -1
            elif x is not None and x != 0.0:
                side = 1 if x > 0 else -1
            else:
                self.game._log("goal_ignored", detail="event without side or x")
                return
            self.game._goal(side, last)
        else:
            x = bx if x is None else x
            y = by if y is None else y
            line = ev.get("line")
            if line not in ("touch", "goal"):
                line = "goal" if abs(x) >= self.game.field.half_length else "touch"
            self.game._ball_out(str(line), x, y, last)

    def ball_outside(self, snap: Snapshot) -> bool:
        """Running play with the ball fully over a line: True (nothing else is judged then).

        With a fieldsim that reports no events, a ball that crosses a line in running play is a
        goal or a ball out at once. Otherwise this is the safety net for a ball that is outside
        while no event of fieldsim's stopped play (it left while play was stopped, so its event
        was ignored, and FORCE_START followed): after 1 s it is a ball out, never a goal."""
        b = snap.ball
        assert b is not None
        f = self.game.field
        if abs(b.x) <= f.half_length + BALL_RADIUS_MM and abs(b.y) <= f.half_width + BALL_RADIUS_MM:
            self._outside_since = None
            self._inside_in_running = True
            return False
        if self._outside_since is None:
            self._outside_since = self.game.now
        crossed = self._inside_in_running
        self._inside_in_running = False
        if snap.events is None and crossed:
            if self.source is None:
                self.source = "director"
            self._detect_lines(b.x, b.y, goal_possible=True)
        elif self.game.now - self._outside_since >= 1.0:
            self._detect_lines(b.x, b.y, goal_possible=False)
        return True

    def _detect_lines(self, bx: float, by: float, goal_possible: bool) -> None:
        """A goal or a ball out seen from the ball position (no event for it)."""
        self._outside_since = None
        f = self.game.field
        over_goal = abs(bx) > f.half_length + BALL_RADIUS_MM
        if goal_possible and over_goal and abs(by) < f.goal_width / 2.0:
            self.count("goal")
            self.game._goal(1 if bx > 0 else -1, self.game.last_touch)
            return
        self.count("ball_out")
        x = max(-f.half_length, min(f.half_length, bx))
        y = max(-f.half_width, min(f.half_width, by))
        self.game._ball_out("goal" if over_goal else "touch", x, y, self.game.last_touch)
