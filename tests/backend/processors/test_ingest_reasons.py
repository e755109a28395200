"""The backend's own ingest counts refused datagrams by reason (sslnet.streams), per stream,
with the total and the last error kept: the same names as the relay and the Health tab."""

from __future__ import annotations

import time

from backend import topics
from backend.bus import DataBus
from backend.processors import RefereeIngest, VisionIngest
from sslnet.streams import StreamCounter
from sslpb import touchline_pb2 as tl
from sslpb.ssl_gc_referee_message_pb2 import Referee as Ref
from tests.relay.test_relay_codecs import make_detection_wrapper, make_referee


def _env(stream: int, payload: bytes, seq: int) -> tl.Envelope:
    return tl.Envelope(stream=stream, receive_time_ns=time.time_ns(), sequence=seq,
                       source="127.0.0.1:1", payload=payload)


async def test_vision_ingest_counts_each_reason() -> None:
    bus = DataBus({})
    ingest = VisionIngest(bus)
    packets = bus.of(topics.VISION_PACKETS)
    good = make_detection_wrapper(7)
    payloads = [
        good[: len(good) // 2],  # cut short
        good[:-1],  # cut by one byte
        b"\x07\x00 not a wrapper",  # field number 0: not the wire format
        b"\x0a\x02\x08\x05",  # a detection without its required fields
        b"\x1a\x03cam",  # a wrapper with only a source: neither detection nor geometry
        good,
    ]
    for i, p in enumerate(payloads):
        packets.write(_env(tl.STREAM_VISION, p, i + 1))
    await ingest.tick()
    c = ingest.counter
    assert c.by_reason == {"truncated": 2, "not protobuf": 1, "missing required field": 1,
                           "no content": 1}
    assert c.errors == 5 and c.packets == 6
    assert c.last_error.startswith("no content: ")
    assert ingest.detections.latest_value() is not None
    d = c.to_dict()
    assert d["errors_by_reason"] == {"missing required field": 1, "no content": 1,
                                     "not protobuf": 1, "truncated": 2}


async def test_referee_ingest_counts_bad_strings_and_uses_the_message() -> None:
    bus = DataBus({})
    ingest = RefereeIngest(bus)
    packets = bus.of(topics.REFEREE_PACKETS)
    good = make_referee(Ref.STOP, 1)
    packets.write(_env(tl.STREAM_REFEREE, good.replace(b"\x0a\x01x", b"\x0a\x01\xff", 1), 1))
    packets.write(_env(tl.STREAM_REFEREE, good[:-2], 2))
    await ingest.tick()
    assert ingest.counter.by_reason == {"bad string": 1, "truncated": 1}
    assert ingest.counter.errors == 2
    assert ingest.referee.latest_value() is not None  # used all the same


def test_the_counter_api_the_world_model_uses() -> None:
    """Other stages count through the same API (e.g. the world model's capture-time check):
    the total, the reason and the last error move together."""
    c = StreamCounter("vision")
    c.error("time out of range", "camera 1: 3600 s ahead of the receive clock")
    c.error("truncated")
    assert (c.errors, c.by_reason) == (2, {"time out of range": 1, "truncated": 1})
    assert c.last_error == "truncated"


async def test_ingest_counts_what_was_overwritten_before_it_read_it() -> None:
    """A flood faster than the ingest decodes: what the bus overwrote before the ingest read
    it is counted as "backend behind", so every forwarded datagram is counted somewhere."""
    bus = DataBus({})
    ingest = VisionIngest(bus)
    packets = bus.of(topics.VISION_PACKETS)
    n = packets.capacity + 36
    for i in range(n):
        packets.write(_env(tl.STREAM_VISION, b"\x07\x00 not a wrapper", i + 1))
    await ingest.tick()
    c = ingest.counter
    assert c.by_reason == {"backend behind": 36, "not protobuf": packets.capacity}
    assert c.errors == n and c.packets == n
    await ingest.tick()  # nothing new: nothing more counted
    assert c.errors == n


async def test_world_counts_frames_overwritten_before_it_merged_them() -> None:
    """Camera frames the world model never read (the detections topic overwrote them under a
    flood) are counted as "backend behind" in its rejections, which health adds to vision."""
    from backend.processors import WorldProcessor
    from backend.world.state import CameraFrame

    bus = DataBus({})
    world = WorldProcessor(bus)
    frames = bus.of(topics.VISION_DETECTIONS)
    n = frames.capacity + 10
    for i in range(n):
        t = 1000.0 + i / 60
        frames.write(CameraFrame(0, i, t, t, int(t * 1e9), (), ()))
    await world.tick()
    assert world.model.rejected.get("backend behind") == 10
    await world.tick()
    assert world.model.rejected.get("backend behind") == 10
