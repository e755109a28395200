"""The match's Referee messages: the station's InternalReferee plus what a whole match needs
(stage changes, stage time left, next command, time left for the current action)."""

from __future__ import annotations

import time
from dataclasses import dataclass

from backend.referee.internal import InternalReferee
from sslpb.ssl_gc_referee_message_pb2 import Referee

STAGES = (
    "NORMAL_FIRST_HALF_PRE", "NORMAL_FIRST_HALF", "NORMAL_HALF_TIME",
    "NORMAL_SECOND_HALF_PRE", "NORMAL_SECOND_HALF", "POST_GAME",
)


@dataclass
class MatchReferee(InternalReferee):
    stage_time_left_us: int | None = None
    next_command: str | None = None
    action_time_remaining_us: int | None = None

    def set_stage(self, stage: str) -> None:
        if stage not in STAGES:
            raise ValueError(f"unknown stage {stage!r}")
        self.stage = stage

    def start_timeout(self, team: str) -> None:
        t = self.blue if team == "blue" else self.yellow
        t.timeouts = max(0, t.timeouts - 1)

    def use_timeout_time(self, team: str, seconds: float) -> None:
        t = self.blue if team == "blue" else self.yellow
        t.timeout_time_us = max(0, t.timeout_time_us - int(seconds * 1e6))

    def message(self, now_us: int | None = None) -> Referee:
        m = super().message(int(time.time() * 1e6) if now_us is None else now_us)
        if self.stage_time_left_us is not None:
            m.stage_time_left = self.stage_time_left_us
        if self.next_command is not None:
            m.next_command = Referee.Command.Value(self.next_command)
        if self.action_time_remaining_us is not None:
            m.current_action_time_remaining = self.action_time_remaining_us
        return m
