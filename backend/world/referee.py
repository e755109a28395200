"""The referee state as the station uses it, from the game controller's Referee message."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, cast

from domain.rules import RefereeCommand
from sslpb.ssl_gc_common_pb2 import Team
from sslpb.ssl_gc_game_event_pb2 import GameEvent
from sslpb.ssl_gc_referee_message_pb2 import MatchType, Referee

from .. import contract


@dataclass(frozen=True, slots=True)
class RefereeState:
    command: RefereeCommand
    stage: str
    command_counter: int
    stage_time_left_s: float | None
    blue: dict[str, Any]
    yellow: dict[str, Any]
    designated_position: tuple[float, float] | None
    blue_team_on_positive_half: bool | None
    packet_timestamp_us: int
    source_identifier: str = ""
    source: str = "game-controller"
    next_command: str | None = None
    status_message: str = ""
    match_type: str | None = None
    current_action_time_remaining_s: float | None = None
    #: the newest game events first, as {id, type, by_team, origin, created_s}
    game_events: tuple[dict[str, Any], ...] = ()

    def team(self, colour: str) -> dict[str, Any]:
        return self.blue if colour == "blue" else self.yellow

    def max_allowed_bots(self, colour: str) -> int | None:
        """How many robots the team may have on the field (cards lower it); None when the
        game controller does not say."""
        v = self.team(colour).get("max_allowed_bots")
        return int(v) if isinstance(v, int) else None

    @property
    def halted(self) -> bool:
        return self.command == "HALT"

    def to_dict(self, age_s: float, source: str | None = None) -> contract.Referee:
        """The browser's view (``source``: overrides this state's, e.g. "internal")."""
        return {
            "source": source or self.source,
            "source_identifier": self.source_identifier,
            "command": self.command,
            "stage": self.stage,
            "command_counter": self.command_counter,
            "stage_time_left_s": self.stage_time_left_s,
            "blue": cast(contract.RefereeTeam, self.blue),
            "yellow": cast(contract.RefereeTeam, self.yellow),
            "designated_position": (
                None if self.designated_position is None
                else {"x": self.designated_position[0], "y": self.designated_position[1]}
            ),
            "blue_team_on_positive_half": self.blue_team_on_positive_half,
            "next_command": self.next_command,
            "status_message": self.status_message,
            "match_type": self.match_type,
            "current_action_time_remaining_s": self.current_action_time_remaining_s,
            "game_events": cast(list[contract.RefereeGameEvent], list(self.game_events)),
            "age_s": age_s,
        }


def wire_str(value: object, bad: list[str] | None = None, where: str = "") -> str:
    """A string from the network, always valid UTF-8: proto2 ``string`` fields that are not
    UTF-8 come out of the parser as bytes (or strings with lone surrogates); they are decoded
    with replacement characters here, at the edge, and noted in ``bad``."""
    if isinstance(value, bytes):
        if bad is not None:
            bad.append(where)
        return value.decode("utf-8", "replace")
    s = str(value)
    try:
        s.encode("utf-8")
    except UnicodeEncodeError:
        if bad is not None:
            bad.append(where)
        return s.encode("utf-8", "replace").decode("utf-8")
    return s


def _team(info: Referee.TeamInfo, bad: list[str], colour: str) -> dict[str, Any]:
    return {
        "name": wire_str(info.name, bad, f"{colour} team name"),
        "score": info.score,
        "yellow_cards": info.yellow_cards,
        "red_cards": info.red_cards,
        "goalkeeper": info.goalkeeper,
        "yellow_card_times_s": [t / 1e6 for t in info.yellow_card_times],
        "timeouts": info.timeouts,
        "timeout_time_s": info.timeout_time / 1e6,
        # optional in the protocol: None when this game controller does not send it
        "foul_counter": info.foul_counter if info.HasField("foul_counter") else None,
        "ball_placement_failures": (info.ball_placement_failures
                                    if info.HasField("ball_placement_failures") else None),
        "can_place_ball": info.can_place_ball if info.HasField("can_place_ball") else None,
        "max_allowed_bots": info.max_allowed_bots if info.HasField("max_allowed_bots") else None,
        "bot_substitution_intent": (info.bot_substitution_intent
                                    if info.HasField("bot_substitution_intent") else None),
        "bot_substitution_allowed": (info.bot_substitution_allowed
                                     if info.HasField("bot_substitution_allowed") else None),
    }


#: game events kept per Referee message (the game controller sends the recent ones)
MAX_GAME_EVENTS = 8


def _game_event(ev: Any, bad: list[str]) -> dict[str, Any]:
    kind = ev.WhichOneof("event")
    by_team = None
    if kind is not None:
        body = getattr(ev, kind)
        if body.HasField("by_team"):
            by_team = _enum_name(Team, body.by_team)
    return {
        "id": wire_str(ev.id, bad, "game event id"),
        "type": _enum_name(GameEvent.Type, ev.type) if ev.HasField("type") else (kind or "UNKNOWN"),
        "by_team": by_team,
        "origin": [wire_str(o, bad, "game event origin") for o in ev.origin],
        "created_s": ev.created_timestamp / 1e6 if ev.HasField("created_timestamp") else None,
    }


def _enum_name(enum: Any, value: int) -> str:
    """The enum's name, or the number for a value newer than our .proto."""
    try:
        return str(enum.Name(value))
    except ValueError:
        return str(value)


def decode_referee(msg: Referee, bad: list[str] | None = None) -> RefereeState:
    """The station's referee state. Strings that are not UTF-8 are decoded with replacement
    and named in ``bad`` (the message is used all the same: nothing else in it is wrong)."""
    bad = [] if bad is None else bad
    dp = None
    if msg.HasField("designated_position"):
        dp = (msg.designated_position.x, msg.designated_position.y)
        if not all(math.isfinite(v) for v in dp):
            dp = None  # no place to put the ball: as if none was sent
    return RefereeState(
        # a required enum: always one of ours (tests/domain/test_rules.py holds the two equal)
        command=cast(RefereeCommand, Referee.Command.Name(msg.command)),
        stage=Referee.Stage.Name(msg.stage),
        command_counter=msg.command_counter,
        stage_time_left_s=msg.stage_time_left / 1e6 if msg.HasField("stage_time_left") else None,
        blue=_team(msg.blue, bad, "blue"),
        yellow=_team(msg.yellow, bad, "yellow"),
        designated_position=dp,
        blue_team_on_positive_half=(
            msg.blue_team_on_positive_half if msg.HasField("blue_team_on_positive_half") else None
        ),
        packet_timestamp_us=msg.packet_timestamp,
        source_identifier=wire_str(msg.source_identifier, bad, "source identifier"),
        next_command=(_enum_name(Referee.Command, msg.next_command)
                      if msg.HasField("next_command") else None),
        status_message=wire_str(msg.status_message, bad, "status message"),
        match_type=(_enum_name(MatchType, msg.match_type)
                    if msg.HasField("match_type") else None),
        current_action_time_remaining_s=(
            msg.current_action_time_remaining / 1e6
            if msg.HasField("current_action_time_remaining") else None),
        game_events=tuple(_game_event(e, bad)
                          for e in msg.game_events[-MAX_GAME_EVENTS:][::-1]),
    )
