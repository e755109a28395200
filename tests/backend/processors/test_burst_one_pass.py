"""One pass per burst (issue 29): camera frames of one burst (cameras triggered together:
grSim, fieldsim --camera-phases together) are all ingested, then the world model, control and
the command publisher run once: one command set for the lot, the world with every frame's
detections. Real ZeroMQ sockets to and from the station's processors in a real Runner."""

from __future__ import annotations

import asyncio
import threading
import time
from collections.abc import AsyncIterator
from contextlib import asynccontextmanager
from dataclasses import dataclass, field

import zmq
import zmq.asyncio

from backend import topics
from backend.bus import DataBus
from backend.control.goto import Target
from backend.messages import TargetEntry
from backend.processor import Processor, Runner
from backend.processors import (
    CommandPublisher,
    ControlProcessor,
    RelayIngest,
    VisionIngest,
    WorldProcessor,
)
from backend.zmqio import pub_socket, sub_socket
from sslpb import touchline_pb2 as tl
from sslpb.ssl_vision_wrapper_pb2 import SSL_WrapperPacket
from tests.waiting import until

N = 4  # cameras in a burst, each seeing one blue robot of its own


def frame(camera: int, n: int, t: float, robot_id: int) -> bytes:
    pkt = SSL_WrapperPacket()
    d = pkt.detection
    d.frame_number, d.camera_id = n, camera
    d.t_capture = d.t_sent = t
    r = d.robots_blue.add()
    r.confidence, r.robot_id, r.orientation = 0.9, robot_id, 0.0
    r.x, r.y = -3000.0 + 1500.0 * robot_id, 0.0
    r.pixel_x = r.pixel_y = 0.0
    return pkt.SerializeToString()


def envelope(seq: int, recv_ns: int, payload: bytes) -> bytes:
    return tl.Envelope(stream=tl.STREAM_VISION, receive_time_ns=recv_ns, sequence=seq,
                       source="test", payload=payload).SerializeToString()


@dataclass
class Rig:
    """The relay's two sockets (its vision PUB, its command SUB) and the station's pipeline
    between them, running."""

    relay_pub: zmq.Socket[bytes]
    relay_sub: zmq.Socket[bytes]
    bus: DataBus
    ingest: RelayIngest
    world: WorldProcessor
    publisher: CommandPublisher
    procs: list[Processor]
    seq: int = 0
    sets: list[tl.RobotCommandSet] = field(default_factory=list)

    def send(self, camera: int, recv_ns: int, t: float, robot_id: int) -> None:
        self.seq += 1
        self.relay_pub.send_multipart([b"vision", envelope(self.seq, recv_ns,
                                                           frame(camera, self.seq, t, robot_id))])

    def heard(self) -> list[tl.RobotCommandSet]:
        while self.relay_sub.poll(0):
            self.sets.append(tl.RobotCommandSet.FromString(self.relay_sub.recv_multipart()[1]))
        return self.sets

    def runs(self) -> dict[str, int]:
        return {p.name: p.stats.rate.total for p in self.procs[:4]}


@asynccontextmanager
async def rig(vision_endpoint: str) -> AsyncIterator[Rig]:
    """``vision_endpoint``: inproc (a message is in the station's queue when send returns)
    or tcp (as the station's)."""
    sync = zmq.Context()
    actx = zmq.asyncio.Context()
    relay_pub, relay_sub = sync.socket(zmq.PUB), sync.socket(zmq.SUB)
    for s in (relay_pub, relay_sub):
        s.setsockopt(zmq.LINGER, 0)
    if vision_endpoint.startswith("tcp"):
        vision_endpoint = f"tcp://127.0.0.1:{relay_pub.bind_to_random_port('tcp://127.0.0.1')}"
        vision_sub = sub_socket(actx, vision_endpoint, [b"vision"])
    else:
        relay_pub.bind(vision_endpoint)
        vision_sub = sync.socket(zmq.SUB)  # type: ignore[assignment]
        vision_sub.setsockopt(zmq.LINGER, 0)
        vision_sub.setsockopt(zmq.SUBSCRIBE, b"")
        vision_sub.connect(vision_endpoint)
    relay_sub.setsockopt(zmq.SUBSCRIBE, b"commands")
    port = relay_sub.bind_to_random_port("tcp://127.0.0.1")
    bus = DataBus({}, check_types=True)
    ingest, world = RelayIngest(bus), WorldProcessor(bus)
    ingest.attach(vision_sub)
    control = ControlProcessor(bus, max_wait_s=10.0, vision_stale_s=10.0)
    control.strategy_stale_s = 3600.0
    publisher = CommandPublisher(bus)
    publisher.attach(pub_socket(actx, f"tcp://127.0.0.1:{port}"))
    procs: list[Processor] = [ingest, VisionIngest(bus), world, control, publisher]
    bus.of(topics.TARGETS).write({("blue", i): TargetEntry(Target(0.0, 2000.0, 0.0), "strategy")
                                  for i in range(N)})
    r = Rig(relay_pub, relay_sub, bus, ingest, world, publisher, procs)
    runner = Runner()
    for p in procs:
        runner.add(p)
    await runner.start()
    try:
        for _ in range(500):  # both subscriptions join: a probe frame a turn until the
            r.send(0, time.time_ns(), time.time(), 0)  # relay's SUB hears a command set
            await asyncio.sleep(0.01)  # (bounded)
            if r.heard():
                break
        assert r.sets, "the relay's SUB heard no command set"
        yield r
    finally:
        await runner.stop()
        vision_sub.close()
        for s in (relay_pub, relay_sub):
            s.close()
        actx.destroy(linger=0)
        sync.term()


def check_one_pass(r: Rig, runs0: dict[str, int], sent0: int, last_stamp: int) -> None:
    runs = {k: v - runs0[k] for k, v in r.runs().items()}
    # one tick of the ingest took the N frames, one pass ran the pipeline once (the
    # publisher also runs on its own max wait: its sets are what counts)
    assert runs == {"relay-ingest": 1, "vision-ingest": 1, "world-model": 1, "control": 1}, runs
    assert r.publisher.sent.total == sent0 + 1
    (cs,) = r.sets
    assert cs.source_receive_time_ns == last_stamp  # the burst's newest frame
    assert sorted(c.id for c in cs.commands) == list(range(N))
    w = r.world.world.latest_value()
    assert w is not None
    assert sorted(f.camera_id for f in w.cameras) == list(range(N))
    for cam in range(N):  # every frame's detection merged, each robot seen by its camera
        rob = w.robot("blue", cam)
        assert rob is not None and rob.visible and rob.cameras == (cam,)
        assert rob.raw_x == -3000.0 + 1500.0 * cam


async def test_frames_waiting_together_are_one_pass_and_one_command_set() -> None:
    """The relay's PUB over inproc: the burst is in the station's queue when the loop next
    runs, as frames the relay forwarded while the station was busy."""
    async with rig("inproc://relay-vision") as r:
        await until(lambda: r.ingest._out.get(zmq.EVENTS) & zmq.POLLIN == 0, 5.0)
        r.sets.clear()
        runs0, sent0 = r.runs(), r.publisher.sent.total
        t, stamps = time.time(), []
        for cam in range(N):  # all sent before the loop runs again (no await in between)
            stamps.append(time.time_ns())
            r.send(cam, stamps[-1], t, cam)
        await until(lambda: r.publisher.sent.total > sent0 and r.heard(), 10.0,
                    what="the burst's command set")
        check_one_pass(r, runs0, sent0, stamps[-1])


async def test_a_burst_arriving_frame_by_frame_is_one_pass() -> None:
    """Through TCP, as the relay forwards a burst: one frame after the other, each sent
    only once the station has taken the one before (each would have started a pass of its
    own). After two bursts of N, the third is held for its rest: one pass for its N frames.
    The ingest's clock (the relay stamps' clock) is the test's, a moment after the burst's
    first frame until the test is done, so a slow machine does not end the wait."""
    async with rig("tcp") as r:
        now = [time.time_ns() + 10**12]  # far past every stamp: nothing held
        r.ingest.clock_ns = lambda: now[0]
        packets = r.bus.of(topics.VISION_PACKETS)
        for k in range(2):  # two bursts of N, 13 ms apart by their stamps
            t, base = time.time() + 0.0133 * k, time.time_ns() + 13_300_000 * k
            for cam in range(N):
                r.send(cam, base + 20_000 * cam, t, cam)
            await until(lambda base=base: any(  # type: ignore[misc]
                s.source_receive_time_ns == base + 20_000 * (N - 1) for s in r.heard()), 10.0,
                what="a learning burst's command set")
        await until(lambda: r.ingest._out.get(zmq.EVENTS) & zmq.POLLIN == 0, 5.0)
        r.sets.clear()
        runs0, sent0 = r.runs(), r.publisher.sent.total
        t, base = time.time() + 0.03, time.time_ns() + 30_000_000
        stamps = [base + 20_000 * cam for cam in range(N)]
        now[0] = base + 100_000  # within the gap of every stamp of the burst
        seq0 = packets.seq

        def the_rest() -> None:  # each frame once the station has the one before
            for cam in range(1, N):
                deadline = time.monotonic() + 10.0
                while packets.seq < seq0 + cam and time.monotonic() < deadline:
                    time.sleep(0.0005)
                r.send(cam, stamps[cam], t, cam)

        r.send(0, stamps[0], t, 0)
        sender = threading.Thread(target=the_rest)
        sender.start()
        try:
            await until(lambda: r.publisher.sent.total > sent0 and r.heard(), 10.0,
                        what="the burst's command set")
        finally:
            sender.join(20)
        now[0] = time.time_ns() + 10**12
        check_one_pass(r, runs0, sent0, stamps[-1])
        assert r.ingest.held == N - 1
