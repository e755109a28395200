"""The internal referee's processor: its Referee messages at 20 Hz while it is on."""

from __future__ import annotations

import time

from .. import topics
from ..bus import DataBus, Reader
from ..processor import Every, Processor
from ..referee.internal import InternalReferee, RefereeCommandError, robots_for_field
from .common import log


class InternalRefereeProcessor(Processor):
    """Sends the internal referee's state at 20 Hz while it is on; steps aside as soon as
    another referee source (the official game controller) is heard."""

    name = "internal-referee"
    foreign_hold_s = 3.0

    def __init__(self, bus: DataBus, referee: InternalReferee, hz: float = 20.0) -> None:
        super().__init__(Every(hz))
        self.referee = referee
        self.enabled = False
        self.disabled_reason = ""
        self.last_foreign: tuple[float, str] | None = None
        self.out = bus.of(topics.REFEREE_OUT)
        self.reader = Reader(bus.of(topics.REFEREE))
        self.geometry = bus.of(topics.GEOMETRY)
        self._geometry_seq = -1

    def foreign_active(self) -> str | None:
        """The source id of another referee heard recently, if any."""
        if self.last_foreign and time.monotonic() - self.last_foreign[0] < self.foreign_hold_s:
            return self.last_foreign[1] or "(no source identifier)"
        return None

    def enable(self, on: bool) -> None:
        if on:
            other = self.foreign_active()
            if other is not None:
                raise RefereeCommandError(
                    f"a game controller is active ({other}): the internal referee stays off")
            self.disabled_reason = ""
        self.enabled = on

    async def tick(self) -> None:
        if self.geometry.seq != self._geometry_seq:
            # the robots allowed before any card: the division's, by the field (grSim's 12 m
            # field showed B's 6 until a card was given)
            self._geometry_seq = self.geometry.seq
            g = self.geometry.latest_value()
            if g is not None:
                self.referee.robots_per_team = robots_for_field(g["field_length"])
        for r in self.reader.read_new():
            if r.source_identifier != self.referee.source_identifier:
                self.last_foreign = (time.monotonic(), r.source_identifier)
                reason = (f"switched off: a game controller is active "
                          f"({r.source_identifier or 'no source identifier'})")
                if self.enabled:
                    self.enabled = False
                    self.disabled_reason = reason
                    log.warning("internal referee %s", self.disabled_reason)
                elif self.disabled_reason.startswith("switched off: a game controller") \
                        and self.disabled_reason != reason:
                    self.disabled_reason = reason  # a new GC (a new id): the reason names it
        if self.enabled:
            self.out.write(self.referee.encode())
