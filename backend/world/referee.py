"""The referee state as the station uses it, from the game controller's Referee message."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from sslpb.ssl_gc_referee_message_pb2 import Referee


@dataclass(frozen=True, slots=True)
class RefereeState:
    command: str
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

    @property
    def halted(self) -> bool:
        return self.command == "HALT"

    @property
    def stopped(self) -> bool:
        return self.command in ("STOP", "BALL_PLACEMENT_BLUE", "BALL_PLACEMENT_YELLOW",
                                "GOAL_BLUE", "GOAL_YELLOW")

    def to_dict(self) -> dict[str, Any]:
        return {
            "source": self.source,
            "source_identifier": self.source_identifier,
            "command": self.command,
            "stage": self.stage,
            "command_counter": self.command_counter,
            "stage_time_left_s": self.stage_time_left_s,
            "blue": self.blue,
            "yellow": self.yellow,
            "designated_position": (
                None if self.designated_position is None
                else {"x": self.designated_position[0], "y": self.designated_position[1]}
            ),
            "blue_team_on_positive_half": self.blue_team_on_positive_half,
        }


def _team(info: Referee.TeamInfo) -> dict[str, Any]:
    return {
        "name": info.name,
        "score": info.score,
        "yellow_cards": info.yellow_cards,
        "red_cards": info.red_cards,
        "goalkeeper": info.goalkeeper,
        "yellow_card_times_s": [t / 1e6 for t in info.yellow_card_times],
        "timeouts": info.timeouts,
    }


def decode_referee(msg: Referee) -> RefereeState:
    dp = None
    if msg.HasField("designated_position"):
        dp = (msg.designated_position.x, msg.designated_position.y)
    return RefereeState(
        command=Referee.Command.Name(msg.command),
        stage=Referee.Stage.Name(msg.stage),
        command_counter=msg.command_counter,
        stage_time_left_s=msg.stage_time_left / 1e6 if msg.HasField("stage_time_left") else None,
        blue=_team(msg.blue),
        yellow=_team(msg.yellow),
        designated_position=dp,
        blue_team_on_positive_half=(
            msg.blue_team_on_positive_half if msg.HasField("blue_team_on_positive_half") else None
        ),
        packet_timestamp_us=msg.packet_timestamp,
        source_identifier=msg.source_identifier,
    )
