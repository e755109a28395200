"""Robot feedback: decodes what robots and simulators answer (``backend.world.feedback``) and
publishes per robot what it means now (ball contact, kicks, answers, round trip, losses)."""

from __future__ import annotations

import time

from sslnet.streams import StreamCounter

from .. import topics
from ..bus import DataBus, Reader
from ..processor import Every, Processor
from ..world.feedback import Decoder, FeedbackTracker
from .common import badlog


class FeedbackProcessor(Processor):
    """Reads the relay's answers and the station's commands; writes ``robot-feedback`` (a
    ``{(team, id): RobotFeedbackView}``) at its rate, so a robot that stops answering is
    marked even when nothing arrives."""

    name = "feedback"

    def __init__(self, bus: DataBus, hz: float = 50.0) -> None:
        super().__init__(Every(hz))
        self.packets = Reader(bus.of(topics.FEEDBACK_PACKETS))
        self.commands = Reader(bus.of(topics.ROBOT_COMMANDS))
        self.out = bus.of(topics.ROBOT_FEEDBACK)
        self.tracker = FeedbackTracker()
        self.decode = Decoder()
        self.counter = StreamCounter("feedback")

    def reset(self) -> None:
        self.tracker.clear()
        self.decode.clear()

    async def tick(self) -> None:
        now = time.monotonic()
        for cset in self.commands.read_new():
            if cset.stop_all:
                continue
            for c in cset.commands:
                self.tracker.command(c.team, c.id, now)
        for env in self.packets.read_new():
            self.counter.packet(len(env.payload))
            dec = self.decode(env)
            if isinstance(dec, tuple):
                self.counter.error(*dec)
                badlog.warning("feedback", "bad robot feedback from %s: %s", env.source,
                               self.counter.last_error)
                continue
            self.tracker.update(env, dec, now)
        self.out.write(self.tracker.views(now))
