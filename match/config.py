"""How one match is played: the length of a half, the division, who kicks off, the goalkeepers
and plays, the scripted interludes, and the director's timings and grace periods
(``match/rules.py``). The director, the judge and the runner read it; it reads none of them."""

from __future__ import annotations

from dataclasses import dataclass, field

from match.rules import Grace, Timing


@dataclass
class MatchConfig:
    half_s: float = 90.0
    division: str = "B"
    first_kickoff: str = "blue"
    blue_on_positive: bool = False
    goalkeepers: dict[str, int] = field(default_factory=lambda: {"blue": 0, "yellow": 0})
    plays: dict[str, str] = field(default_factory=lambda: {"blue": "match", "yellow": "simple"})
    interludes: bool = True
    timing: Timing = field(default_factory=Timing)
    grace: Grace = field(default_factory=Grace)
