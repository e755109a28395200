"""What a match counts: the violation kinds and each team's statistics."""

from __future__ import annotations

from dataclasses import dataclass, field

# Violations judged continuously (counted once per episode, plus robot-seconds in violation)
EPISODE_KINDS = (
    "halt_moving", "stop_speed", "stop_distance", "set_piece_distance", "placement_distance",
    "defense_area",
)
# Violations judged at one instant (counted once per robot) or from events
SNAPSHOT_KINDS = ("kickoff_position", "penalty_position", "collision")
VIOLATION_KINDS = EPISODE_KINDS + SNAPSHOT_KINDS


@dataclass
class Violation:
    count: int = 0
    seconds: float = 0.0


@dataclass
class TeamStats:
    goals: int = 0
    possession_s: float = 0.0
    kicks: int = 0
    placements_ok: int = 0
    placements_failed: int = 0
    placement_times_s: list[float] = field(default_factory=list)
    violations: dict[str, Violation] = field(
        default_factory=lambda: {k: Violation() for k in VIOLATION_KINDS})
