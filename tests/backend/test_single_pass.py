"""The hot path as one synchronous pass (issue 11): a camera frame written by a source processor
goes through decoding, the world model, control and the command publisher before the source's
task gives the event loop back, without sockets and without a single suspension."""

from __future__ import annotations

import asyncio
import time
from typing import Any

from backend import topics
from backend.bus import DataBus
from backend.control.goto import Target
from backend.messages import TargetEntry
from backend.processor import Processor, Runner
from backend.processors import (
    CommandPublisher,
    ControlProcessor,
    TrackerPublisher,
    VisionIngest,
    WorldProcessor,
)
from sslpb import touchline_pb2 as tl
from sslpb.ssl_vision_wrapper_pb2 import SSL_WrapperPacket
from sslpb.ssl_vision_wrapper_tracked_pb2 import TrackerWrapperPacket


class Wire:
    """What would be the ZeroMQ socket to the relay: frames and the task that sent them."""

    def __init__(self) -> None:
        self.sent: list[tuple[bytes, bytes, str]] = []

    def send_multipart(self, frames: list[bytes], flags: int = 0) -> None:
        task = asyncio.current_task()
        self.sent.append((frames[0], frames[1], task.get_name() if task else ""))

    def of(self, topic: bytes) -> list[bytes]:
        return [body for t, body, _ in self.sent if t == topic]


class Frames(Processor):
    """A source processor like the relay ingest: one envelope per item of its queue."""

    name = "frames"

    def __init__(self, bus: DataBus) -> None:
        super().__init__(None)
        self.packets = bus.of(topics.VISION_PACKETS)
        self.queue: asyncio.Queue[bytes] = asyncio.Queue()
        self.seq = 0

    async def wait_input(self) -> None:
        while self.queue.empty():  # bounded by the test's own loop, which stops the runner
            await asyncio.sleep(0.001)

    async def tick(self) -> None:
        while not self.queue.empty():
            self.seq += 1
            self.packets.write(tl.Envelope(stream=tl.STREAM_VISION, receive_time_ns=time.time_ns(),
                                           sequence=self.seq, source="test",
                                           payload=self.queue.get_nowait()))


def frame(n: int, x_mm: float, camera: int = 0) -> bytes:
    pkt = SSL_WrapperPacket()
    d = pkt.detection
    d.frame_number, d.camera_id = n, camera
    d.t_capture = d.t_sent = time.time()
    r = d.robots_blue.add()
    r.confidence, r.robot_id, r.x, r.y, r.orientation = 0.9, 3, x_mm, 0.0, 0.0
    r.pixel_x = r.pixel_y = 0.0
    return pkt.SerializeToString()


def pipeline() -> tuple[DataBus, Frames, list[Processor], Wire]:
    bus = DataBus({}, check_types=True)
    source = Frames(bus)
    wire = Wire()
    control = ControlProcessor(bus, max_wait_s=10.0, vision_stale_s=1.0)
    control.strategy_stale_s = 3600.0  # no strategy in this pipeline: the targets stay
    publisher = CommandPublisher(bus)
    publisher.attach(wire)  # type: ignore[arg-type]
    tracker = TrackerPublisher(bus, "uuid")
    tracker.attach(wire)  # type: ignore[arg-type]
    procs: list[Processor] = [source, VisionIngest(bus), WorldProcessor(bus), control,
                              publisher, tracker]
    bus.of(topics.TARGETS).write({("blue", 3): TargetEntry(Target(2000.0, 0.0, 0.0), "test")})
    return bus, source, procs, wire


def commands(wire: Wire) -> list[tl.RobotCommandSet]:
    return [tl.RobotCommandSet.FromString(b) for b in wire.of(b"commands")]


async def test_a_frame_becomes_commands_in_the_sources_own_pass() -> None:
    _, source, procs, wire = pipeline()
    runner = Runner()
    for p in procs:
        runner.add(p)
    await runner.start()
    try:
        for _ in range(200):  # the start-up pass (every processor once) settles first
            await asyncio.sleep(0.001)
            if wire.of(b"commands"):
                break
        before = len(wire.sent)
        source.queue.put_nowait(frame(1, 0.0))
        for _ in range(2000):  # bounded: the frame's commands come out
            await asyncio.sleep(0.001)
            if any(c.source_receive_time_ns > 0 for c in commands(wire)):
                break
    finally:
        await runner.stop()
    new = wire.sent[before:]
    moving = [tl.RobotCommandSet.FromString(b) for t, b, _ in new if t == b"commands"]
    assert moving and moving[-1].commands[0].id == 3
    assert moving[-1].commands[0].forward_mps > 0  # towards the target at +x
    # decoded, merged, controlled and sent by the source's task: one pass, no hand-over
    assert {task for t, _, task in new if t in (b"commands", b"tracker-out")} == {"frames"}
    tracked = [TrackerWrapperPacket.FromString(b) for t, b, _ in new if t == b"tracker-out"]
    assert tracked and tracked[-1].tracked_frame.robots[0].robot_id.id == 3


async def test_the_pass_never_suspends() -> None:
    """Driven by hand: the coroutine of one source tick and its pass finishes on its first
    step, so nothing between the camera frame and the command waits for the event loop."""
    _, source, procs, wire = pipeline()
    runner = Runner()
    for p in procs:
        runner.add(p)
    # set up as start() does, without starting the tasks
    runner._loop = asyncio.get_running_loop()
    for p in procs:
        runner._chain(p)
    source.queue.put_nowait(frame(1, 0.0))
    source.queue.put_nowait(frame(2, 5.0, camera=1))
    coro: Any = runner._tick_then_pass(source)
    try:
        coro.send(None)
    except StopIteration:
        pass
    else:  # pragma: no cover - the failure this test is for
        coro.close()
        raise AssertionError("the pass suspended: a stage waited for the event loop")
    sent = commands(wire)
    assert sent and sent[-1].source_receive_time_ns > 0
    assert sent[-1].commands[0].id == 3
    assert len(wire.of(b"tracker-out")) >= 1
