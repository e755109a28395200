"""The latency a robot experiences (issue 29): for each robot command sent to the relay, the age
of the newest frame that saw that robot, beside the per-set arrival -> command latency (the
world's newest frame). Two frames merged in one pass: the set's latency is the newer frame's,
the robot seen only in the older one gets the older frame's age."""

from __future__ import annotations

import time

from backend import topics
from backend.bus import DataBus
from backend.control.goto import Target
from backend.messages import TargetEntry
from backend.processors import (
    CommandPublisher,
    ControlProcessor,
    VisionIngest,
    WorldProcessor,
)
from sslpb import touchline_pb2 as tl
from sslpb.ssl_vision_wrapper_pb2 import SSL_WrapperPacket


class Wire:
    """The publisher's socket to the relay: what it sent."""

    def __init__(self) -> None:
        self.sent: list[list[bytes]] = []

    def send_multipart(self, frames: list[bytes], flags: int = 0) -> None:
        self.sent.append(frames)


def frame(n: int, camera: int, robot_id: int, x_mm: float, t: float) -> bytes:
    pkt = SSL_WrapperPacket()
    d = pkt.detection
    d.frame_number, d.camera_id = n, camera
    d.t_capture = d.t_sent = t
    r = d.robots_blue.add()
    r.confidence, r.robot_id, r.x, r.y, r.orientation = 0.9, robot_id, x_mm, 0.0, 0.0
    r.pixel_x = r.pixel_y = 0.0
    return pkt.SerializeToString()


def _pipeline(ids: tuple[int, ...]) -> tuple[DataBus, VisionIngest, WorldProcessor,
                                              ControlProcessor, CommandPublisher]:
    """Vision ingest -> world -> control -> publisher on a bus, wired as the station wires
    them, with strategy targets for blue ``ids``."""
    bus = DataBus({}, check_types=True)
    vision, world = VisionIngest(bus), WorldProcessor(bus)
    control = ControlProcessor(bus, max_wait_s=10.0, vision_stale_s=10.0)
    control.strategy_stale_s = 3600.0
    publisher = CommandPublisher(bus)
    publisher.attach(Wire())  # type: ignore[arg-type]
    publisher.arrivals = world.arrivals
    bus.of(topics.TARGETS).write({("blue", i): TargetEntry(Target(2000.0, 0.0, 0.0), "strategy")
                                  for i in ids})
    return bus, vision, world, control, publisher


def test_each_robot_gets_the_age_of_its_own_newest_frame() -> None:
    bus, vision, world, control, publisher = _pipeline((3, 4))
    packets = bus.of(topics.VISION_PACKETS)
    now = time.time()
    t_old = time.time_ns() - 4_000_000
    t_new = t_old + 3_000_000
    # robot 3 in the older frame (camera 0), robot 4 in the newer one (camera 1): one pass
    for seq, (cam, rid, recv) in enumerate(((0, 3, t_old), (1, 4, t_new))):
        packets.write(tl.Envelope(stream=tl.STREAM_VISION, receive_time_ns=recv, sequence=seq,
                                  source="test", payload=frame(seq, cam, rid, 0.0, now)))
    for p in (vision, world, control, publisher):
        p.step()
    sets = [tl.RobotCommandSet.FromString(f[1]) for f in publisher._out.sent
            if f[0] == b"commands"]
    assert len(sets) == 1 and sorted(c.id for c in sets[0].commands) == [3, 4]
    assert sets[0].source_receive_time_ns == t_new  # the set: the world's newest frame
    (per_set,) = publisher.latency.samples
    ages = sorted(publisher.frame_age.samples)
    assert len(ages) == 2
    # robot 4's frame is the set's: the same age; robot 3's is 3 ms older (one clock read)
    assert ages[0] == per_set
    assert abs(ages[1] - ages[0] - 3.0) < 1e-6
    assert world.arrivals == {("blue", 3): t_old, ("blue", 4): t_new}


def test_a_robot_not_seen_and_a_stop_give_no_age() -> None:
    # robot 5 has a target and was never seen: commanded zero, no frame behind it
    bus, vision, world, control, publisher = _pipeline((3, 5))
    bus.of(topics.VISION_PACKETS).write(tl.Envelope(
        stream=tl.STREAM_VISION, receive_time_ns=time.time_ns(), sequence=1, source="test",
        payload=frame(1, 0, 3, 0.0, time.time())))
    for p in (vision, world, control, publisher):
        p.step()
    assert len(publisher.frame_age.samples) == 1  # robot 3's only
    bus.of(topics.ESTOP).write(True)
    for p in (control, publisher):
        p.step()
    assert len(publisher.frame_age.samples) == 1  # the stop's set: no frame behind it
