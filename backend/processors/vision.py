"""Vision ingest: the one decoder of vision datagrams."""

from __future__ import annotations

from time import time_ns

from sslnet import streams
from sslnet.streams import StreamCounter
from sslpb.ssl_vision_wrapper_pb2 import SSL_WrapperPacket

from .. import topics
from ..bus import DataBus, Reader
from ..processor import OnTopic, Processor
from ..world.decode import decode_detection, geometry_to_dict
from .common import LatencyStage, badlog, read_counting_missed


class VisionIngest(Processor):
    """Decodes vision datagrams: detection frames and geometry onto their topics."""

    name = "vision-ingest"

    def __init__(self, bus: DataBus) -> None:
        packets = bus.of(topics.VISION_PACKETS)
        super().__init__(OnTopic(packets))
        self.reader = Reader(packets)
        self.detections = bus.of(topics.VISION_DETECTIONS)
        self.geometry = bus.of(topics.GEOMETRY)
        self.counter = StreamCounter("vision")
        self.latency = LatencyStage()  # relay arrival -> decoded on the bus
        self._last_geometry_bytes = b""
        self._last_geometry_bad: list[str] = []  # its names that are not UTF-8

    def step(self) -> None:
        counter = self.counter
        count, write, latency = counter.rate.add, self.detections.write, self.latency.add_at
        for env in read_counting_missed(self.reader, counter, "vision"):
            count()
            pkt = SSL_WrapperPacket()
            reason = streams.parse_message(pkt, env.payload)
            if reason is not None:
                counter.error(*reason)
                badlog.warning("vision", "bad vision packet from %s: %s", env.source,
                               counter.last_error)
                continue
            has_detection, has_geometry = pkt.HasField("detection"), pkt.HasField("geometry")
            if not (has_detection or has_geometry):
                counter.error(streams.NO_CONTENT, "SSL_WrapperPacket has neither "
                              "detection nor geometry")
                badlog.warning("vision", "empty vision packet from %s", env.source)
                continue
            if has_detection:
                recv_ns = env.receive_time_ns
                write(decode_detection(pkt.detection, recv_ns))
                latency(time_ns(), recv_ns)  # (add_since, without its own call)
            if has_geometry:
                raw = pkt.geometry.field.SerializeToString()
                if raw != self._last_geometry_bytes:  # only a change goes on the bus
                    self._last_geometry_bytes = raw
                    self._last_geometry_bad = []
                    self.geometry.write(geometry_to_dict(pkt.geometry, self._last_geometry_bad))
                if self._last_geometry_bad:  # used all the same, counted in every packet
                    bad = ", ".join(sorted(set(self._last_geometry_bad)))
                    counter.error(streams.BAD_STRING, "not UTF-8: " + bad)
                    badlog.warning("vision-string", "geometry from %s: not UTF-8 (%s); "
                                   "decoded with replacement characters", env.source, bad)
