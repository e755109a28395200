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


class Signalled(Processor):
    """A source that signals its input through the loop, like the relay ingest's ZeroMQ
    descriptor: the runner ticks it (and runs the pass) inside the loop's callback."""

    name = "signalled"

    def __init__(self, bus: DataBus) -> None:
        super().__init__(None)
        self.packets = bus.of(topics.VISION_PACKETS)
        self.queue: asyncio.Queue[bytes] = asyncio.Queue()
        self.seq = 0
        self.ready: Any = None
        self.tasks: list[Any] = []  # the task of each step (None: a plain callback)

    def watch_input(self, ready: Any) -> bool:
        self.ready = ready
        return True

    def step(self) -> None:
        self.tasks.append(asyncio.current_task())
        while not self.queue.empty():
            self.seq += 1
            self.packets.write(tl.Envelope(stream=tl.STREAM_VISION, receive_time_ns=time.time_ns(),
                                           sequence=self.seq, source="test",
                                           payload=self.queue.get_nowait()))


async def test_a_signalled_frame_becomes_commands_inside_the_loops_callback() -> None:
    """No task and no future per frame: the loop's callback (the descriptor's, here called
    soon) runs the source's step and the whole pass; the processors with a plain ``step``
    (vision ingest, command publisher) are called without a coroutine."""
    bus, _, procs, wire = pipeline()
    source = Signalled(bus)
    procs[0] = source
    runner = Runner()
    for p in procs:
        runner.add(p)
    await runner.start()
    try:
        assert source.ready is not None
        assert not any(t.get_name() == "signalled" for t in asyncio.all_tasks())
        loop = asyncio.get_running_loop()
        for n in range(1, 4):
            source.queue.put_nowait(frame(n, 100.0 * n, camera=n % 2))
            loop.call_soon(source.ready)
            for _ in range(2000):  # bounded: the callback runs in the loop's next turn
                await asyncio.sleep(0.001)
                if source.stats.rate.total >= n:
                    break
    finally:
        await runner.stop()
    moving = [(tl.RobotCommandSet.FromString(b), task) for t, b, task in wire.sent
              if t == b"commands"]
    fed = [(cs, task) for cs, task in moving if cs.source_receive_time_ns > 0]
    assert len(fed) >= 3 and all(task == "" for _, task in fed)  # outside any task
    assert fed[-1][0].commands[0].id == 3
    assert source.tasks == [None, None, None]
    assert source.stats.rate.total == 3 and procs[1].stats.rate.total >= 3


class Waits(Processor):
    """A topic-triggered processor whose tick really waits for the loop."""

    name = "waits"

    def __init__(self, src: Any, dst: Any, log: list[str]) -> None:
        from backend.processor import OnTopic

        super().__init__(OnTopic(src))
        from backend.bus import Reader

        self.reader = Reader(src)
        self.dst, self.log = dst, log

    async def tick(self) -> None:
        vals = self.reader.read_new()
        if vals:
            self.log.append(f"waits {vals}")
            await asyncio.sleep(0.01)
            self.dst.write(vals[-1])
            self.log.append("waited")


class After(Processor):
    name = "after"

    def __init__(self, src: Any, log: list[str]) -> None:
        from backend.bus import Reader
        from backend.processor import OnTopic

        super().__init__(OnTopic(src))
        self.reader = Reader(src)
        self.log = log

    def step(self) -> None:
        vals = self.reader.read_new()
        if vals:
            self.log.append(f"after {vals}")


async def test_a_tick_that_waits_hands_the_rest_of_the_pass_to_a_task() -> None:
    """The pass is plain calls, but a coroutine tick that really waits is not cut short:
    the processors after it run once it is done, in order, and input signalled meanwhile
    is taken after that pass."""
    from backend.bus import Topic

    a: Topic[int] = Topic("a", 8)
    b: Topic[int] = Topic("b", 8)
    log: list[str] = []
    waits, after = Waits(a, b, log), After(b, log)
    runner = Runner()
    runner.add(waits)
    runner.add(after)
    await runner.start()
    try:
        a.write(1)
        a.write(2)  # written together: one run sees both
        for _ in range(2000):  # bounded
            await asyncio.sleep(0.001)
            if "after [2]" in log:
                break
        await runner._pass()  # nothing left: returns at once
    finally:
        await runner.stop()
    assert log == ["waits [1, 2]", "waited", "after [2]"]
    assert waits.stats.rate.total >= 1 and waits.stats.summary()["tick_mean_ms"] >= 5.0
