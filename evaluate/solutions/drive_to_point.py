"""Exercise "drive to a point": robot task["robot"] to task["target_mm"], planned around the
other robots (Target's avoid=True, the default)."""

from __future__ import annotations

from touchline import Game, Target

TITLE = "Drive to a point (reference)"


def play(game: Game) -> dict[int, Target]:
    rid = int(game.task.get("robot", 0))
    x, y = game.task.get("target_mm", (0.0, 0.0))
    return {rid: Target(float(x), float(y), None)}
