"""A student whose play never returns."""

from touchline import Game, Target


def play(game: Game) -> dict[int, Target]:
    n = 0
    while True:
        n += 1
