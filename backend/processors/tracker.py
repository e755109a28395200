"""Tracked vision out: the world estimate of every tick as the league's TrackerWrapperPacket,
recorded (type 5 records of the session log) and sent to the relay on ZeroMQ ``tracker-out``
through the command publisher's socket; the relay multicasts it (on loopback unless it is
started with --tracker-out: the game controller adopts the first tracker it hears)."""

from __future__ import annotations

import math
import time
from collections.abc import Callable

from ssllog.format import TYPE_TRACKER_2020
from sslnet.rate import RateCounter

from .. import topics
from ..bus import DataBus, Reader
from ..params.model import StationParams
from ..processor import OnTopic
from ..world.tracked import tracked_packet
from .common import SocketProcessor

TOPIC = b"tracker-out"


class TrackerPublisher(SocketProcessor):
    """One TrackerWrapperPacket per world written, at most ``tracker.max_hz`` by the capture
    clock (the newest world then): ``uuid`` constant for the run,
    ``source_name`` "Touchline", ``frame_number`` increasing by one per packet. Sent while
    ``tracker.publish`` is on, and in replay only with ``tracker.publish_in_replay``;
    recorded in live sessions whatever the parameters say."""

    name = "tracker-out"

    def __init__(self, bus: DataBus, uuid: str, source_name: str = "Touchline") -> None:
        world = bus.of(topics.WORLD)
        super().__init__(OnTopic(world))
        self.reader = Reader(world)
        self.uuid = uuid
        self.source_name = source_name
        self.frame_number = 0
        self.publish = True
        self.publish_in_replay = False
        #: True while a log is replayed (the station's player has a log)
        self.replaying: Callable[[], bool] = lambda: False
        #: every packet of a live session (the session recorder: time_ns, type, bytes)
        self.record: Callable[[int, int, bytes], None] = lambda t, k, b: None
        self.sent = RateCounter()
        self.min_period_s = 0.01  # tracker.max_hz
        self._last_t = -math.inf  # capture time of the last frame published
        #: called after each frame sent (a stall hunt: backend/stalldump.py)
        self.after_send: Callable[[], None] | None = None

    def configure(self, params: StationParams) -> None:
        self.publish = params.tracker.publish
        self.publish_in_replay = params.tracker.publish_in_replay
        self.min_period_s = 1.0 / params.tracker.max_hz

    def sending(self) -> bool:
        """Whether tracked vision goes to the relay now."""
        return self.publish and (self.publish_in_replay or not self.replaying())

    def step(self) -> None:
        worlds = self.reader.read_new()
        if not worlds:
            return
        replay = self.replaying()
        send = self.attached and self.publish and (self.publish_in_replay or not replay)
        if replay and not send:
            return  # nothing recorded in replay, nothing sent
        w = worlds[-1]  # the newest estimate, at most max_hz (by the capture clock)
        if w.t_capture < self._last_t + self.min_period_s and w.t_capture >= self._last_t:
            return
        self._last_t = w.t_capture
        self.frame_number += 1
        pkt = tracked_packet(w, self.uuid, self.frame_number, self.source_name)
        if not replay:
            self.record(w.receive_time_ns or time.time_ns(), TYPE_TRACKER_2020, pkt)
        if send:
            self.send([TOPIC, pkt])
            self.sent.add()
            if self.after_send is not None:
                self.after_send()
