"""A team's processor: the paper's unit of work, run by the station in a worker process.

    from touchline import Game, Processor

    class Possession(Processor):
        rate_hz = 20.0
        reads = ("robot-feedback",)

        def tick(self, game: Game, inputs: dict) -> dict[str, float]:
            return {"ours": 0.7}

Its numeric outputs become the topic ``team/<file name>``: drawn in the Plots tab
(``team.<file name>.<field>``), recorded in the session log, and given to every play as
``game.topics["<file name>"]``.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from .game import Game


class Processor:
    """Subclass it; the station makes one instance and calls ``tick``."""

    #: how often ``tick`` runs (Hz), unless ``trigger`` is set
    rate_hz: float = 10.0
    #: "world": run on every new world state instead (at most ``max_hz``)
    trigger: str | None = None
    #: with ``trigger = "world"``: at most this often (Hz); the station runs processors at
    #: most 100 times a second
    max_hz: float = 100.0
    #: the station's Data Bus topics to read besides the game (their latest values as plain
    #: data: dicts, lists, numbers), e.g. ("robot-commands", "robot-feedback", "targets")
    reads: tuple[str, ...] = ()

    def tick(self, game: Game, inputs: Mapping[str, Any]) -> Mapping[str, float | int | bool]:
        """One step; returns this tick's numeric outputs (the same names every tick)."""
        raise NotImplementedError

    def keep(self) -> Any:
        """State to carry across a reload of the file (picklable); None: start afresh."""
        return None

    def restore(self, kept: Any) -> None:
        """Receives what the previous version's ``keep`` returned."""
