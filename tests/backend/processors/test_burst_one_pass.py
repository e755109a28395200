"""One pass per burst (issue 29): camera frames of one burst (cameras triggered together:
grSim, fieldsim --camera-phases together) are all ingested, then the world model, control and
the command publisher run once: one command set for the lot, the world with every frame's
detections. While the rest of a burst is awaited the pass is held, not waited for: the
station thread runs timers and anything else meanwhile, and whatever asks for a pass (a
referee datagram, the control's own deadline) runs it at once. Real ZeroMQ sockets to and
from the station's processors in a real Runner."""

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
from backend.processor import OnTopic, Processor, Runner
from backend.processors import (
    CommandPublisher,
    ControlProcessor,
    RelayIngest,
    VisionIngest,
    WorldProcessor,
)
from backend.processors.relay_ingest import (
    BURST_GAP_NS,
    BURST_GAPS,
    BURST_HISTORY,
    BURST_WAIT_MAX_NS,
    capture_ns,
)
from backend.zmqio import pub_socket, sub_socket
from sslpb import touchline_pb2 as tl
from sslpb.ssl_vision_geometry_pb2 import SSL_GeometryData
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
    runner: Runner
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

    def send_referee(self, recv_ns: int) -> None:
        self.seq += 1
        env = tl.Envelope(stream=tl.STREAM_REFEREE, receive_time_ns=recv_ns, sequence=self.seq,
                          source="test", payload=b"")
        self.relay_pub.send_multipart([b"referee", env.SerializeToString()])


@asynccontextmanager
async def rig(vision_endpoint: str, sizes: dict[str, int] | None = None) -> AsyncIterator[Rig]:
    """``vision_endpoint``: inproc (a message is in the station's queue when send returns)
    or tcp (as the station's); ``sizes``: the bus's topic capacities."""
    sync = zmq.Context()
    actx = zmq.asyncio.Context()
    relay_pub, relay_sub = sync.socket(zmq.PUB), sync.socket(zmq.SUB)
    for s in (relay_pub, relay_sub):
        s.setsockopt(zmq.LINGER, 0)
    if vision_endpoint.startswith("tcp"):
        vision_endpoint = f"tcp://127.0.0.1:{relay_pub.bind_to_random_port('tcp://127.0.0.1')}"
        vision_sub = sub_socket(actx, vision_endpoint, [b"vision", b"referee"])
    else:
        relay_pub.bind(vision_endpoint)
        vision_sub = sync.socket(zmq.SUB)  # type: ignore[assignment]
        vision_sub.setsockopt(zmq.LINGER, 0)
        vision_sub.setsockopt(zmq.SUBSCRIBE, b"")
        vision_sub.connect(vision_endpoint)
    relay_sub.setsockopt(zmq.SUBSCRIBE, b"commands")
    port = relay_sub.bind_to_random_port("tcp://127.0.0.1")
    bus = DataBus(sizes or {}, check_types=True)
    ingest, world = RelayIngest(bus), WorldProcessor(bus)
    ingest.attach(vision_sub)
    control = ControlProcessor(bus, max_wait_s=10.0, vision_stale_s=10.0)
    control.strategy_stale_s = 3600.0
    publisher = CommandPublisher(bus)
    # its own refresh (a pass when no command set came for 50 ms) would also end a held
    # pass: the tests' passes are the frames' and their own deadlines'
    assert isinstance(publisher.trigger, OnTopic)
    publisher.trigger = OnTopic(publisher.trigger.topic, max_wait_s=3600.0)
    publisher.attach(pub_socket(actx, f"tcp://127.0.0.1:{port}"))
    procs: list[Processor] = [ingest, VisionIngest(bus), world, control, publisher]
    bus.of(topics.TARGETS).write({("blue", i): TargetEntry(Target(0.0, 2000.0, 0.0), "strategy")
                                  for i in range(N)})
    runner = Runner()
    r = Rig(relay_pub, relay_sub, bus, ingest, world, publisher, procs, runner)
    for p in procs:
        runner.add(p)
    await runner.start()
    runner.end_hold_on(bus.of(topics.ESTOP))  # as the station does
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


def check_one_pass(r: Rig, runs0: dict[str, int], sent0: int, last_stamp: int,
                   ticks: int = 1, n: int = N) -> None:
    """The ingest's ``ticks`` took ``n`` frames, one pass ran the pipeline once, and the
    pass is no longer held (its timer gone: it will not run again)."""
    runs = {k: v - runs0[k] for k, v in r.runs().items()}
    # (the publisher also runs on its own max wait: its sets are what counts)
    assert runs == {"relay-ingest": ticks, "vision-ingest": 1, "world-model": 1,
                    "control": 1}, runs
    assert r.publisher.sent.total == sent0 + 1
    (cs,) = r.sets
    assert cs.source_receive_time_ns == last_stamp  # the burst's newest frame
    assert set(range(n)) <= {c.id for c in cs.commands}
    w = r.world.world.latest_value()
    assert w is not None
    if n == N:
        assert sorted(f.camera_id for f in w.cameras) == list(range(N))
    assert r.runner._held_by is None and r.runner._hold_timer is None
    for cam in range(n):  # every frame's detection merged, each robot seen by its camera
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


Burst = list[tuple[int, float]]  # each frame's relay stamp (ns) and capture time (s)
#: bursts sent before the one measured: as many as the ingest remembers less one, so the
#: rig's probe frames (bursts of one) are forgotten but one
LEARN = BURST_HISTORY - 1


def burst(base_ns: int, gap_ns: int, t: float, n: int = N, t_step: float = 0.0) -> Burst:
    """``n`` frames, stamped ``gap_ns`` apart by the relay from ``base_ns``, captured at ``t``
    (each ``t_step`` after the one before: 0, cameras triggered together)."""
    return [(base_ns + gap_ns * cam, t + t_step * cam) for cam in range(n)]


async def learn(r: Rig, period_ns: int, gap_ns: int, t_step: float = 0.0,
                sizes: tuple[int, ...] = (N,) * LEARN) -> Burst:
    """Bursts of ``sizes`` frames (``burst``), ``period_ns`` apart, sent whole, each once the
    one before has its command set; returns the next burst of N. The ingest's clock is far
    past every stamp (and runs on: a burst smaller than expected ends its wait)."""
    r.ingest.clock_ns = lambda: time.time_ns() + 10**12
    t, base = time.time(), time.time_ns()
    for k, n in enumerate(sizes):
        b = burst(base + period_ns * k, gap_ns, t + period_ns * k / 1e9, n, t_step)
        for cam, (stamp, tc) in enumerate(b):
            r.send(cam, stamp, tc, cam)
        await until(lambda last=b[-1][0]: any(  # type: ignore[misc]
            s.source_receive_time_ns == last for s in r.heard()), 10.0,
            what="a learning burst's command set")
    await until(lambda: r.ingest._out.get(zmq.EVENTS) & zmq.POLLIN == 0, 5.0)
    k = len(sizes)
    return burst(base + period_ns * k, gap_ns, t + period_ns * k / 1e9, N, t_step)


#: the hold's time in the tests that send a burst frame by frame: as long as the test takes
#: (a slow machine does not end it)
LONG_NS = 60 * 10**9


async def frame_by_frame(r: Rig, b: Burst, hold_ns: int = LONG_NS
                         ) -> tuple[dict[str, int], int, int]:
    """Sends ``b`` as the relay forwards a burst: one frame after the other, each only once
    the station has taken the one before (each would have started a pass of its own). The
    ingest's clock (the relay stamps' clock) is the test's, a moment after the burst's first
    frame, and the hold ``hold_ns`` from a frame's stamp, until the first command set is
    heard. Returns the runs and the sets sent before, and the times the ingest held the
    pass."""
    packets = r.bus.of(topics.VISION_PACKETS)
    r.sets.clear()
    runs0, sent0, held0 = r.runs(), r.publisher.sent.total, r.ingest.held
    now = [b[0][0] + 100_000]
    r.ingest.clock_ns = lambda: now[0]
    r.ingest.burst_wait_ns, r.ingest.hold_max_s = hold_ns, 2 * hold_ns / 1e9
    seq0 = packets.seq

    def the_rest() -> None:  # each frame once the station has the one before
        for cam in range(1, len(b)):
            deadline = time.monotonic() + 10.0
            while packets.seq < seq0 + cam and time.monotonic() < deadline:
                time.sleep(0.0005)
            r.send(cam, b[cam][0], b[cam][1], cam)

    r.send(0, b[0][0], b[0][1], 0)
    sender = threading.Thread(target=the_rest)
    sender.start()
    try:
        await until(lambda: packets.seq >= seq0 + len(b) and r.heard(), 10.0,
                    what="the burst's frames and a command set")
    finally:
        sender.join(20)
        now[0] = time.time_ns() + 10**12
    return runs0, sent0, r.ingest.held - held0


async def one_pass_frame_by_frame(period_ns: int, spread_ns: int,
                                  sizes: tuple[int, ...] = (N,) * LEARN) -> None:
    """Through TCP, bursts of N learnt (``learn``'s stamps ``period_ns`` apart, a burst's
    frames ``spread_ns``), then one more sent frame by frame: held after each frame but the
    last, one pass for its N frames."""
    async with rig("tcp") as r:
        b = await learn(r, period_ns, spread_ns, sizes=sizes)
        runs0, sent0, held = await frame_by_frame(r, b)
        check_one_pass(r, runs0, sent0, b[-1][0], ticks=N)
        assert held == N - 1


async def test_a_burst_arriving_frame_by_frame_is_one_pass() -> None:
    """Through TCP, as the relay forwards a burst. After bursts of N (the relay's stamps
    20 us apart), the pass is held after each of the burst's frames but the last: one pass
    for its N frames."""
    await one_pass_frame_by_frame(13_300_000, 20_000)


async def test_a_burst_the_relay_stamped_far_apart_is_one_pass_by_its_capture_time() -> None:
    """grSim's four cameras of a step share one capture time, but the relay stamps them
    after its recvfrom, spread by its scheduling (1 ms apart here: more than the 0.3 ms gap;
    by the stamps every frame was a burst of its own and had a pass of its own)."""
    await one_pass_frame_by_frame(16_600_000, 1_000_000)


async def test_a_burst_with_a_frame_lost_before_does_not_end_the_holding() -> None:
    """Bursts of N, then one of N - 1 (a datagram lost): the next burst of N is still one
    pass (the smaller of the last two bursts' sizes held it for N - 1 frames only)."""
    await one_pass_frame_by_frame(16_600_000, 20_000, sizes=(N,) * (LEARN - 1) + (N - 1,))


async def test_cameras_with_phases_of_their_own_never_hold_the_pass() -> None:
    """Cameras captured 3.3 ms apart (each its own phase) whose frames the relay stamped
    20 us apart (it forwarded a backlog): no burst, the pass is never held (by the stamps they
    were bursts of N, and the pass waited for each frame after the first)."""
    async with rig("tcp") as r:
        b = await learn(r, 13_300_000, 20_000, t_step=0.0033)
        await frame_by_frame(r, b)
        assert r.ingest.held == 0
        assert r.ingest.burst_expected == 1


async def test_a_burst_cut_short_has_its_pass_when_the_hold_is_over_once() -> None:
    """Bursts of N, then N - 1 frames (the last one lost): the pass is held after each, and
    runs when the hold is over (the loop's timer: nothing else comes), once, for the N - 1
    frames. The ingest's clock is the relay's (this machine's wall clock) and the hold 0.2 s
    from each frame's stamp, so each frame comes within it."""
    async with rig("tcp") as r:
        b = await learn(r, 16_600_000, 20_000)
        r.ingest.clock_ns = time.time_ns
        # the stamps (not before the learnt ones) and the capture time moved on alike
        now = max(time.time_ns(), b[0][0])
        t = b[0][1] + (now - b[0][0]) / 1e9
        b = [(now + 20_000 * cam, t) for cam in range(N - 1)]
        hold_ns = 200_000_000
        t0 = time.monotonic()
        runs0, sent0, held = await frame_by_frame(r, b, hold_ns)
        r.ingest.clock_ns = time.time_ns
        check_one_pass(r, runs0, sent0, b[-1][0], ticks=N - 1, n=N - 1)
        assert held == N - 1
        # the pass came with the timer: not before the hold's time
        assert time.monotonic() - t0 >= hold_ns / 1e9


async def test_the_station_thread_is_not_blocked_while_a_pass_is_held() -> None:
    """After a burst's first frame the pass is held (its time far off): a timer of the loop
    set then fires, and the pass is still held; the rest of the burst then has one pass
    with every frame (the ingest blocked its thread for the rest of a burst: the timer
    waited behind it, and the pass ran without the rest when the wait was over)."""
    async with rig("tcp") as r:
        b = await learn(r, 16_600_000, 20_000)
        packets = r.bus.of(topics.VISION_PACKETS)
        r.sets.clear()
        runs0, sent0 = r.runs(), r.publisher.sent.total
        r.ingest.clock_ns = lambda: b[0][0] + 100_000
        r.ingest.burst_wait_ns, r.ingest.hold_max_s = LONG_NS, 2 * LONG_NS / 1e9
        seq0 = packets.seq
        r.send(0, b[0][0], b[0][1], 0)
        await until(lambda: packets.seq > seq0, 10.0, what="the burst's first frame")
        fired = asyncio.Event()
        asyncio.get_running_loop().call_later(0.001, fired.set)
        await asyncio.wait_for(fired.wait(), 10.0)
        assert r.runs()["world-model"] == runs0["world-model"]  # still held
        for cam in range(1, N):
            r.send(cam, b[cam][0], b[cam][1], cam)
        await until(lambda: packets.seq >= seq0 + N and r.heard(), 10.0,
                    what="the burst's frames and a command set")
        check_one_pass(r, runs0, sent0, b[-1][0], ticks=r.runs()["relay-ingest"]
                       - runs0["relay-ingest"])


async def test_a_referee_datagram_runs_a_held_pass_at_once() -> None:
    """A referee datagram (a HALT's way in) drained while a burst's pass is held: the pass
    runs with it at once (what came of the burst in it), not at the hold's time."""
    async with rig("tcp") as r:
        b = await learn(r, 16_600_000, 20_000)
        referee = r.bus.of(topics.REFEREE_PACKETS)
        runs0 = r.runs()
        r.ingest.clock_ns = lambda: b[0][0] + 100_000
        r.ingest.burst_wait_ns, r.ingest.hold_max_s = LONG_NS, 2 * LONG_NS / 1e9
        held0, seq0 = r.ingest.held, referee.seq
        r.send(0, b[0][0], b[0][1], 0)
        await until(lambda: r.ingest.held > held0, 10.0, what="the pass held")
        r.send_referee(b[0][0] + 50_000)
        await until(lambda: r.runs()["world-model"] > runs0["world-model"], 10.0,
                    what="the pass")
        assert referee.seq == seq0 + 1
        assert r.runner._held_by is None and r.runner._hold_timer is None


async def test_the_controls_deadline_runs_while_a_pass_is_held() -> None:
    """The control's max wait (how lost vision and a stalled strategy stop the robots)
    comes while a burst's pass is held: the control runs then (its stop never waits for the
    hold), the held frame is left to the burst's pass, which comes with the rest, once."""
    async with rig("tcp") as r:
        b = await learn(r, 16_600_000, 20_000)
        control = r.procs[3]
        world = r.bus.of(topics.WORLD)
        packets = r.bus.of(topics.VISION_PACKETS)
        runs0 = r.runs()
        r.ingest.clock_ns = lambda: b[0][0] + 100_000
        r.ingest.burst_wait_ns, r.ingest.hold_max_s = LONG_NS, 2 * LONG_NS / 1e9
        held0, seq0 = r.ingest.held, packets.seq
        r.send(0, b[0][0], b[0][1], 0)
        await until(lambda: r.ingest.held > held0, 10.0, what="the pass held")
        control.trigger = OnTopic(world, max_wait_s=0.05)
        await until(lambda: r.runs()["control"] > runs0["control"], 10.0,
                    what="the control's deadline")
        control.trigger = OnTopic(world, max_wait_s=3600.0)
        assert r.runs()["vision-ingest"] == runs0["vision-ingest"]  # the frame still held
        assert r.runner._held_by is r.ingest
        for cam in range(1, N):
            r.send(cam, b[cam][0], b[cam][1], cam)
        await until(lambda: packets.seq >= seq0 + N
                    and r.runs()["world-model"] > runs0["world-model"], 10.0,
                    what="the burst's pass")
        runs = {k: v - runs0[k] for k, v in r.runs().items()}
        assert runs["vision-ingest"] == runs["world-model"] == 1, runs
        w = r.world.world.latest_value()
        assert w is not None and sorted(f.camera_id for f in w.cameras) == list(range(N))
        assert r.runner._held_by is None and r.runner._hold_timer is None


async def test_the_emergency_stop_runs_a_held_pass_at_once() -> None:
    """The emergency stop pressed while a burst's pass is held (the control reads it in the
    pass; nothing else would run the control before the hold's time): the held pass runs
    at once, with the frame it held, and its command set stops every robot."""
    async with rig("tcp") as r:
        b = await learn(r, 16_600_000, 20_000)
        packets = r.bus.of(topics.VISION_PACKETS)
        r.sets.clear()
        runs0 = r.runs()
        r.ingest.clock_ns = lambda: b[0][0] + 100_000
        r.ingest.burst_wait_ns, r.ingest.hold_max_s = LONG_NS, 2 * LONG_NS / 1e9
        held0, seq0 = r.ingest.held, packets.seq
        r.send(0, b[0][0], b[0][1], 0)
        await until(lambda: r.ingest.held > held0, 10.0, what="the pass held")
        assert r.runs()["control"] == runs0["control"]
        r.bus.of(topics.ESTOP).write(True)
        await until(lambda: r.runs()["control"] > runs0["control"] and r.heard(), 10.0,
                    what="the stop's pass and command set")
        runs = {k: v - runs0[k] for k, v in r.runs().items()}
        assert runs == {"relay-ingest": 1, "vision-ingest": 1, "world-model": 1,
                        "control": 1}, runs
        assert packets.seq == seq0 + 1
        assert r.sets[-1].stop_all or all(
            c.forward_mps == 0 and c.left_mps == 0 for c in r.sets[-1].commands)
        assert r.runner._held_by is None and r.runner._hold_timer is None


async def test_a_held_pass_never_lets_an_ingest_topic_overflow_unread() -> None:
    """The vision topic holds 2 records: a burst of N arriving frame by frame is held after
    its first frame, but its second fills the topic, so the pass runs then (a third frame
    drained before it would overwrite the first unread); the rest is held again and has a
    pass of its own. Nothing is lost on the bus."""
    async with rig("tcp", sizes={topics.VISION_PACKETS.name: 2}) as r:
        b = await learn(r, 16_600_000, 20_000)
        vision_ingest = r.procs[1]
        assert isinstance(vision_ingest, VisionIngest)
        missed0 = vision_ingest.reader.missed
        runs0, _sent0, held = await frame_by_frame(r, b)
        await until(lambda: r.runs()["world-model"] >= runs0["world-model"] + 2, 10.0,
                    what="two passes")
        runs = {k: v - runs0[k] for k, v in r.runs().items()}
        assert runs == {"relay-ingest": N, "vision-ingest": 2, "world-model": 2,
                        "control": 2}, runs
        assert held == 2  # after the first and the third frame
        assert vision_ingest.reader.missed == missed0


def geometry() -> SSL_GeometryData:
    g = SSL_GeometryData()
    f = g.field
    f.field_length, f.field_width, f.goal_width, f.goal_depth, f.boundary_width = (
        12000, 9000, 1200, 180, 300)
    return g


def test_the_capture_time_is_read_off_the_datagram_as_every_known_sender_writes_it() -> None:
    """The detection's ``t_capture`` from the first bytes, whatever the lengths before it
    take (a frame number and a detection long enough for varints of several bytes); None
    where it is not where the senders write it (the ingest then groups by the relay's
    stamps)."""
    t = 1795943061.953123
    pkt = SSL_WrapperPacket()
    pkt.detection.frame_number, pkt.detection.t_capture = 3, t
    pkt.detection.t_sent, pkt.detection.camera_id = t, 1
    assert capture_ns(pkt.SerializeToString()) == int(t * 1e9)
    pkt.detection.frame_number = 2**31  # a five-byte varint
    for i in range(40):  # a detection of more than 127 bytes: a two-byte length
        r = pkt.detection.robots_yellow.add()
        r.confidence, r.robot_id, r.x, r.y, r.pixel_x, r.pixel_y = 0.9, i, 1.0, 2.0, 0.0, 0.0
    pkt.geometry.CopyFrom(geometry())  # grSim's: geometry in a camera frame
    data = pkt.SerializeToString()
    assert data[1] & 0x80 and capture_ns(data) == int(t * 1e9)
    geometry_only = SSL_WrapperPacket(geometry=geometry())
    for payload in (geometry_only.SerializeToString(), b"", b"\x0a", data[:12], b"\x0a\x05\x08",
                    b"\x0a\x0a\x08\x01\x19" + bytes(8)):  # t_sent where t_capture should be
        assert capture_ns(payload) is None, payload
    pkt.detection.t_capture = float("nan")
    assert capture_ns(pkt.SerializeToString()) is None


def test_the_wait_for_a_burst_follows_the_relays_spread_of_its_frames() -> None:
    """Bursts of N frames of one capture time, the relay's stamps ``gap`` apart: once
    BURST_GAPS gaps are in, the wait is their 95th percentile, within 0.3 ms and 2 ms."""
    for gap, wait in ((20_000, BURST_GAP_NS), (1_000_000, 1_000_000),
                      (5_000_000, BURST_WAIT_MAX_NS)):
        ingest = RelayIngest(DataBus({}, check_types=True))
        assert ingest.burst_wait_ns == BURST_GAP_NS
        bursts = -(-BURST_GAPS // (N - 1))  # enough for BURST_GAPS gaps
        for k in range(bursts):
            for cam in range(N):
                ingest._burst(10**18 + 16_600_000 * k + gap * cam, 16_600_000 * k)
        assert ingest.burst_wait_ns == wait, gap
        assert ingest.burst_expected == N
