"""Tracked vision out: one TrackerWrapperPacket per world on ``tracker-out`` (uuid constant,
frame numbers increasing), recorded in live sessions, switched by the tracker parameters and
silent in replay unless tracker.publish_in_replay."""

from __future__ import annotations

from typing import Any

import pytest

from backend import topics
from backend.bus import DataBus
from backend.params.model import StationParams
from backend.processors import TrackerPublisher
from backend.world.state import RobotState, WorldState
from ssllog.format import TYPE_TRACKER_2020
from sslpb.ssl_vision_wrapper_tracked_pb2 import TrackerWrapperPacket


class FakeSocket:
    def __init__(self) -> None:
        self.sent: list[list[bytes]] = []

    def send_multipart(self, frames: list[bytes], flags: int = 0) -> None:
        self.sent.append(frames)


def world(t: float, x: float = 100.0) -> WorldState:
    return WorldState(t, int(t * 1e9), None, (RobotState("blue", 1, x, -50.0, 0.5),))


def setup() -> tuple[TrackerPublisher, DataBus, FakeSocket, list[tuple[int, int, bytes]]]:
    bus = DataBus({})
    tp = TrackerPublisher(bus, "run-uuid")
    sock = FakeSocket()
    tp.attach(sock)  # type: ignore[arg-type]
    recorded: list[tuple[int, int, bytes]] = []
    tp.record = lambda t, k, b: recorded.append((t, k, b))
    return tp, bus, sock, recorded


def packets(sock: FakeSocket) -> list[TrackerWrapperPacket]:
    out = []
    for topic, body in sock.sent:
        assert topic == b"tracker-out"
        p = TrackerWrapperPacket.FromString(body)
        assert p.IsInitialized()
        out.append(p)
    return out


def params(**tracker: Any) -> StationParams:
    return StationParams.model_validate({"tracker": tracker})


async def test_the_newest_world_at_most_max_hz_uuid_constant_frames_increasing() -> None:
    tp, bus, sock, recorded = setup()
    tp.configure(StationParams())  # tracker.max_hz 100: 10 ms of capture time apart
    w = bus.of(topics.WORLD)
    w.write(world(1.0))
    w.write(world(1.004, 200.0))  # two worlds before one tick: the newest
    await tp.tick()
    w.write(world(1.009, 250.0))  # 5 ms later: not yet
    await tp.tick()
    w.write(world(1.0145, 300.0))  # 10.5 ms after the last one sent
    await tp.tick()
    await tp.tick()  # nothing new: nothing sent
    ps = packets(sock)
    assert [p.tracked_frame.frame_number for p in ps] == [1, 2]
    assert {p.uuid for p in ps} == {"run-uuid"}
    assert {p.source_name for p in ps} == {"Touchline"}
    assert [p.tracked_frame.robots[0].pos.x for p in ps] == pytest.approx([0.2, 0.3])
    assert [b for _, _, b in recorded] == [f[1] for f in sock.sent]  # the same bytes
    assert {k for _, k, _ in recorded} == {TYPE_TRACKER_2020}
    w.write(world(0.5, 400.0))  # time went back (a replay seeked): published at once
    await tp.tick()
    assert len(packets(sock)) == 3


async def test_max_hz_is_a_parameter() -> None:
    tp, bus, sock, _ = setup()
    tp.configure(params(max_hz=1000.0))
    w = bus.of(topics.WORLD)
    for i in range(5):
        w.write(world(1.0 + 0.002 * i, 100.0 * i))
        await tp.tick()
    assert len(packets(sock)) == 5


async def test_switched_off_it_only_records() -> None:
    tp, bus, sock, recorded = setup()
    tp.configure(params(publish=False))
    bus.of(topics.WORLD).write(world(1.0))
    await tp.tick()
    assert sock.sent == [] and len(recorded) == 1


async def test_nothing_in_replay_unless_asked() -> None:
    tp, bus, sock, recorded = setup()
    replay = [True]
    tp.replaying = lambda: replay[0]
    tp.configure(StationParams())
    w = bus.of(topics.WORLD)
    w.write(world(1.0))
    await tp.tick()
    assert sock.sent == [] and recorded == [] and not tp.sending()
    tp.configure(params(publish_in_replay=True))
    w.write(world(1.1))
    await tp.tick()
    assert len(sock.sent) == 1 and recorded == []  # a replay is never recorded again
    replay[0] = False  # back to live
    tp.configure(StationParams())
    w.write(world(2.0))
    await tp.tick()
    assert [p.tracked_frame.frame_number for p in packets(sock)] == [1, 2]
    assert len(recorded) == 1
