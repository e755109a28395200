"""A student whose play raises on every tick."""

from touchline import Game, Target


def play(game: Game) -> dict[int, Target]:
    return {0: Target(1.0 / 0.0, 0.0)}
