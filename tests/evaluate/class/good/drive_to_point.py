"""A student who did it: robot task["robot"] to task["target_mm"]."""

from touchline import Game, Target


def play(game: Game) -> dict[int, Target]:
    rid = int(game.task.get("robot", 0))
    x, y = game.task.get("target_mm", (0.0, 0.0))
    return {rid: Target(float(x), float(y), 0.0)}
