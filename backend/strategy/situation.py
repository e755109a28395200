"""What the referee asks of our team right now, seen from our side.

The game controller sends commands like ``PREPARE_KICKOFF_YELLOW``; a play needs "their
kickoff: take kickoff positions". ``SituationTracker`` turns the command stream into a
``Situation`` for our team, including the states the command alone does not tell: after
``NORMAL_START`` of a kickoff or a free kick the kick is still to be taken until the ball
has moved (then the game runs), and the kicker may not touch the ball again at once.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Literal

from domain.rules import SLOW_COMMANDS

SituationKind = Literal[
    "halt",  # every robot stands still
    "stop",  # <= 1.5 m/s, >= 0.5 m from the ball
    "running",  # normal play
    "kickoff-prepare",  # take kickoff positions
    "kickoff",  # NORMAL_START after a kickoff: the kicker kicks, others keep positions
    "penalty-prepare",
    "penalty",
    "free-kick",  # DIRECT_FREE / INDIRECT_FREE until the ball moved
    "placement",  # BALL_PLACEMENT
    "timeout",
]

#: The ball counts as "in play" after a kick once it moved this far (SSL rules: 0.05 m).
BALL_MOVED_MM = 50.0


@dataclass(frozen=True, slots=True)
class Situation:
    kind: SituationKind
    ours: bool | None  # True: our set piece / placement / timeout; None: not a team thing
    command: str  # the referee command behind it ("" without a referee)
    indirect: bool = False  # an indirect free kick (no direct shot on goal)
    designated: tuple[float, float] | None = None  # ball placement target, field frame (mm)

    @property
    def key(self) -> str:
        """A short name for the UI and logs, e.g. ``our-kickoff-prepare``, ``stop``."""
        if self.ours is None:
            return self.kind
        return f"{'our' if self.ours else 'their'}-{self.kind}"

    def text(self) -> str:
        """One line for a coach: what the robots are doing and why."""
        who = "Our" if self.ours else "Their"
        k = self.kind
        if k == "halt":
            return "HALT: every robot stands still"
        if k == "stop":
            return "STOP: at most 1.5 m/s, keep 0.5 m from the ball"
        if k == "running":
            return "Game running" if self.command else "No referee: playing freely"
        if k == "kickoff-prepare":
            return f"{who} kickoff: take positions in our half"
        if k == "kickoff":
            return f"{who} kickoff: {'kick' if self.ours else 'wait for the kick'}"
        if k == "penalty-prepare":
            return f"{who} penalty: take positions (others 1 m behind the ball)"
        if k == "penalty":
            return f"{who} penalty: {'shoot' if self.ours else 'keeper on the goal line'}"
        if k == "free-kick":
            kind = "indirect" if self.indirect else "direct"
            return (f"Our {kind} free kick: take it" if self.ours
                    else f"Their {kind} free kick: keep 0.5 m from the ball")
        if k == "placement":
            return ("Our ball placement: bring the ball to the mark" if self.ours
                    else "Their ball placement: keep clear of ball and mark")
        if k == "timeout":
            return f"{who} timeout: robots parked"
        return k


class SituationTracker:
    """Feeds on (referee command, command counter, ball position) every strategy tick."""

    def __init__(self) -> None:
        self._counter: int | None = None
        self._command = ""
        self._prepared: str = ""  # the PREPARE_* command a NORMAL_START follows
        self._ball_at_start: tuple[float, float] | None = None
        self._in_play = False

    def update(self, command: str | None, counter: int, our_team: str,
               ball: tuple[float, float] | None,
               designated: tuple[float, float] | None = None) -> Situation:
        if command is None:
            self._counter = None
            self._command = ""
            return Situation("running", None, "")
        if counter != self._counter or command != self._command:
            if command.startswith("PREPARE_"):
                self._prepared = command
            elif command not in ("NORMAL_START", "HALT"):
                self._prepared = ""
            self._counter = counter
            self._command = command
            self._ball_at_start = ball
            self._in_play = False
        if (not self._in_play and ball is not None and self._ball_at_start is not None
                and math.dist(ball, self._ball_at_start) > BALL_MOVED_MM):
            self._in_play = True
        elif self._ball_at_start is None and ball is not None:
            self._ball_at_start = ball
        return self._classify(command, our_team.upper(), designated)

    def _classify(self, cmd: str, us: str, designated: tuple[float, float] | None) -> Situation:
        def ours(c: str) -> bool:
            return c.rsplit("_", 1)[-1] == us

        if cmd == "HALT":
            return Situation("halt", None, cmd)
        if cmd in SLOW_COMMANDS:  # STOP, and the old goal commands with STOP semantics
            return Situation("stop", None, cmd)
        if cmd == "FORCE_START":
            return Situation("running", None, cmd)
        if cmd == "NORMAL_START":
            prep = self._prepared
            if prep.startswith("PREPARE_KICKOFF_") and not self._in_play:
                return Situation("kickoff", ours(prep), cmd)
            if prep.startswith("PREPARE_PENALTY_") and not self._in_play:
                # the others wait behind the line until the kicker has touched the ball
                return Situation("penalty", ours(prep), cmd)
            return Situation("running", None, cmd)
        if cmd.startswith("PREPARE_KICKOFF_"):
            return Situation("kickoff-prepare", ours(cmd), cmd)
        if cmd.startswith("PREPARE_PENALTY_"):
            return Situation("penalty-prepare", ours(cmd), cmd)
        if cmd.startswith(("DIRECT_FREE_", "INDIRECT_FREE_")):
            if self._in_play:
                return Situation("running", None, cmd)
            return Situation("free-kick", ours(cmd), cmd, indirect=cmd.startswith("INDIRECT"))
        if cmd.startswith("BALL_PLACEMENT_"):
            return Situation("placement", ours(cmd), cmd, designated=designated)
        if cmd.startswith("TIMEOUT_"):
            return Situation("timeout", ours(cmd), cmd)
        return Situation("stop", None, cmd)  # an unknown command: the careful choice
