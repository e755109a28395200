"""The interface between a team's own code and the station (API version 1).

A team's play, role or processor imports only from here::

    from touchline import Game, Target, Velocity, STOP

    TITLE = "Pass drill"

    def play(game: Game) -> dict[int, Target]:
        ...

A play is a file of the team folder with a top-level ``def play(game)``, or a ``class Play``
whose ``tick(self, game)`` is called (one instance; its ``keep()`` / ``restore(kept)``, when
it defines them, carry its state across a save of the file, as a ``Processor``'s do).

``touchline.lib`` lends a play Touchline's own pieces: the geometry library, the path planner
(``plan_path(game, rid, x, y)``) and the built-in roles (goalkeeper, attacker, defenders).

Everything in this package is a stable promise: fields are added, never renamed or removed
within one ``API_VERSION``; Touchline's internals (``backend``) may change freely. The station
builds a ``Game`` snapshot for every tick, hands it to the team's code in a worker process of
its own, and checks every order that comes back (docs/team-code.md, docs/team-api.md).

Coordinates are always in *our frame*: our goal is at negative x whatever half we defend in
the vision frame (a half-time side switch changes no team code). Lengths in mm, velocities in
mm/s, angles in rad (counter-clockwise, 0 along +x), speeds given to the robots in m/s.
"""

from .game import (
    API_VERSION,
    Ball,
    FieldSize,
    Game,
    Kick,
    Referee,
    Robot,
)
from .orders import STOP, Order, Target, Velocity
from .processor import Processor

__all__ = [
    "API_VERSION",
    "STOP",
    "Ball",
    "FieldSize",
    "Game",
    "Kick",
    "Order",
    "Processor",
    "Referee",
    "Robot",
    "Target",
    "Velocity",
]
