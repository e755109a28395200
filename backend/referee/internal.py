"""An internal referee that produces real Referee messages (pure: no I/O).

When no game controller is present, a class needs nothing else: the operator clicks HALT,
STOP, FORCE START, kickoff/free kick/penalty per team, ball placement at a clicked point, and
the station's robots obey it exactly as they obey the official game controller."""

from __future__ import annotations

import time
import uuid
from dataclasses import dataclass, field

from domain.rules import RefereeCommand
from sslpb.ssl_gc_referee_message_pb2 import Referee

# Commands the operator may give, and the stage the game is in afterwards.
OPERATOR_COMMANDS: tuple[RefereeCommand, ...] = (
    "HALT", "STOP", "NORMAL_START", "FORCE_START",
    "PREPARE_KICKOFF_BLUE", "PREPARE_KICKOFF_YELLOW",
    "PREPARE_PENALTY_BLUE", "PREPARE_PENALTY_YELLOW",
    "DIRECT_FREE_BLUE", "DIRECT_FREE_YELLOW",
    "TIMEOUT_BLUE", "TIMEOUT_YELLOW",
    "BALL_PLACEMENT_BLUE", "BALL_PLACEMENT_YELLOW",
)


class RefereeCommandError(ValueError):
    pass


#: a yellow card lasts this long (the rules: 120 s of playing time; here: wall time)
YELLOW_CARD_US = 120_000_000
CARDS = ("yellow", "red", "clear")  # clear: the operator withdraws the team's cards


def robots_for_field(field_length_mm: float | None) -> int:
    """The division's robots per team by the field's size (A: 12 m x 9 m, 11; B: 6)."""
    return 11 if field_length_mm is not None and field_length_mm >= 11000 else 6


@dataclass
class _Team:
    name: str
    score: int = 0
    yellow_cards: int = 0
    red_cards: int = 0
    timeouts: int = 4
    timeout_time_us: int = 300_000_000
    goalkeeper: int = 0
    yellow_card_ends_us: list[int] = field(default_factory=list)  # of the active cards
    carded: bool = False  # once a card was given, max_allowed_bots is sent

    def active_yellow_us(self, now_us: int) -> list[int]:
        """Time left (us) of each yellow card still running, the soonest first."""
        return sorted(t - now_us for t in self.yellow_card_ends_us if t > now_us)


#: how long the timed stages last (the rules: 5 min halves and half time, 2.5 min extra
#: halves); the others have no clock (0 is sent)
STAGE_DURATION_US: dict[str, int] = {
    "NORMAL_FIRST_HALF": 300_000_000, "NORMAL_HALF_TIME": 300_000_000,
    "NORMAL_SECOND_HALF": 300_000_000, "EXTRA_TIME_BREAK": 300_000_000,
    "EXTRA_FIRST_HALF": 150_000_000, "EXTRA_HALF_TIME": 120_000_000,
    "EXTRA_SECOND_HALF": 150_000_000, "PENALTY_SHOOTOUT_BREAK": 120_000_000,
}


@dataclass
class InternalReferee:
    source_identifier: str = field(default_factory=lambda: f"touchline-{uuid.uuid4()}")
    command: RefereeCommand = "HALT"
    stage: str = "NORMAL_FIRST_HALF_PRE"
    command_counter: int = 0
    command_timestamp_us: int = field(default_factory=lambda: int(time.time() * 1e6))
    designated_position: tuple[float, float] | None = None
    blue_team_on_positive_half: bool = False
    blue: _Team = field(default_factory=lambda: _Team("Blue"))
    yellow: _Team = field(default_factory=lambda: _Team("Yellow"))
    robots_per_team: int = 6  # the division's number (B: 6, A: 11); cards lower it
    #: the stage whose clock runs, and when it began (us): stage_time_left is sent like the
    #: game controller sends it (the league's tools expect it: ssl-log-stats failed without)
    _clock_stage: str = ""
    _stage_start_us: int = 0

    def card(self, team: str, kind: str, now_us: int | None = None) -> None:
        """A yellow card (one robot fewer for 120 s) or a red card (for the rest of the
        game); the game goes on: the team takes a robot out by itself. ``clear`` withdraws
        the team's cards (an operator's mistake)."""
        if team not in ("blue", "yellow"):
            raise RefereeCommandError(f"unknown team {team!r}; blue or yellow")
        if kind not in CARDS:
            raise RefereeCommandError(f"unknown card {kind!r}; one of {', '.join(CARDS)}")
        t = self.blue if team == "blue" else self.yellow
        now = int(time.time() * 1e6) if now_us is None else now_us
        t.carded = True
        if kind == "yellow":
            t.yellow_cards += 1
            t.yellow_card_ends_us.append(now + YELLOW_CARD_US)
        elif kind == "red":
            t.red_cards += 1
        else:
            t.yellow_cards = t.red_cards = 0
            t.yellow_card_ends_us.clear()

    def max_allowed_bots(self, team: str, now_us: int | None = None) -> int:
        t = self.blue if team == "blue" else self.yellow
        now = int(time.time() * 1e6) if now_us is None else now_us
        return max(0, self.robots_per_team - t.red_cards - len(t.active_yellow_us(now)))

    def give(self, command: str, designated_position: tuple[float, float] | None = None,
             now_us: int | None = None) -> None:
        """The operator's command. Ball placement needs a designated position (mm)."""
        if command not in OPERATOR_COMMANDS:
            raise RefereeCommandError(
                f"unknown command {command!r}; one of {', '.join(OPERATOR_COMMANDS)}")
        placement = command.startswith("BALL_PLACEMENT")
        if placement and designated_position is None:
            raise RefereeCommandError(f"{command} needs a designated position")
        if command == "NORMAL_START" and not self.command.startswith("PREPARE_"):
            raise RefereeCommandError("NORMAL_START follows a PREPARE_KICKOFF or PREPARE_PENALTY")
        self.command = command  # narrowed: one of OPERATOR_COMMANDS
        self.designated_position = designated_position if placement else None
        self.command_counter += 1
        self.command_timestamp_us = int(time.time() * 1e6) if now_us is None else now_us
        if command in ("NORMAL_START", "FORCE_START") and self.stage.endswith("_PRE"):
            self.stage = self.stage[: -len("_PRE")]

    def goal(self, team: str) -> None:
        (self.blue if team == "blue" else self.yellow).score += 1
        self.give("STOP")

    def message(self, now_us: int | None = None) -> Referee:
        now = int(time.time() * 1e6) if now_us is None else now_us
        if self.stage != self._clock_stage:
            self._clock_stage, self._stage_start_us = self.stage, now
        m = Referee(
            source_identifier=self.source_identifier,
            packet_timestamp=now,
            stage_time_left=STAGE_DURATION_US.get(self.stage, 0) - (now - self._stage_start_us)
            if self.stage in STAGE_DURATION_US else 0,
            stage=Referee.Stage.Value(self.stage),
            command=Referee.Command.Value(self.command),
            command_counter=self.command_counter,
            command_timestamp=self.command_timestamp_us,
            blue_team_on_positive_half=self.blue_team_on_positive_half,
        )
        for info, t in ((m.blue, self.blue), (m.yellow, self.yellow)):
            info.name, info.score = t.name, t.score
            info.red_cards, info.yellow_cards = t.red_cards, t.yellow_cards
            info.timeouts, info.timeout_time = t.timeouts, t.timeout_time_us
            info.goalkeeper = t.goalkeeper
            info.yellow_card_times.extend(t.active_yellow_us(now))
            if t.carded:
                info.max_allowed_bots = self.max_allowed_bots(
                    "blue" if t is self.blue else "yellow", now)
        if self.designated_position is not None:
            m.designated_position.x, m.designated_position.y = self.designated_position
        return m

    def encode(self, now_us: int | None = None) -> bytes:
        return self.message(now_us).SerializeToString()
