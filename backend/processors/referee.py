"""Referee ingest: the one decoder of referee datagrams; notices a silent referee."""

from __future__ import annotations

from sslnet import streams
from sslnet.streams import StreamCounter
from sslpb.ssl_gc_referee_message_pb2 import Referee

from .. import topics
from ..bus import DataBus, Reader
from ..processor import OnTopic, Processor
from ..referee.watch import RefereeWatch
from ..world.referee import decode_referee
from .common import badlog, read_counting_missed


class RefereeIngest(Processor):
    """Decodes referee datagrams onto the referee topic; also runs when none arrives for
    ``SILENCE_CHECK_S``, so a silent referee is noticed (and logged) as it happens."""

    name = "referee-ingest"

    def __init__(self, bus: DataBus, watch: RefereeWatch | None = None) -> None:
        packets = bus.of(topics.REFEREE_PACKETS)
        super().__init__(OnTopic(packets, max_wait_s=SILENCE_CHECK_S))
        self.reader = Reader(packets)
        self.referee = bus.of(topics.REFEREE)
        self.counter = StreamCounter("referee")
        self.watch = watch or RefereeWatch()

    async def tick(self) -> None:
        for env in read_counting_missed(self.reader, self.counter, "referee"):
            self.counter.rate.add()
            msg = Referee()
            reason = streams.parse_message(msg, env.payload)
            if reason is not None:
                self.counter.error(*reason)
                badlog.warning("referee", "bad referee packet from %s: %s", env.source,
                                self.counter.last_error)
                continue
            bad: list[str] = []
            state = decode_referee(msg, bad)
            if bad:  # used all the same, with replacement characters
                self.counter.error(streams.BAD_STRING, "not UTF-8: " + ", ".join(bad))
                badlog.warning("referee-string", "referee message from %s: not UTF-8 (%s); "
                                "decoded with replacement characters", env.source, ", ".join(bad))
            self.watch.heard(state)
            self.referee.write(state)
        self.watch.check()


#: how often the referee ingest looks for a silent referee when nothing arrives
SILENCE_CHECK_S = 0.5
