"""The two teams, by the colours the league names them."""

from __future__ import annotations

from typing import Literal

Team = Literal["blue", "yellow"]
TEAMS: tuple[Team, Team] = ("blue", "yellow")


def other_team(team: Team) -> Team:
    return "yellow" if team == "blue" else "blue"
