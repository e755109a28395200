"""The digest of everything a real relay emits for a fixed sequence of inputs (a check, not a
timing): run it before and after a change to the relay that must not change its behaviour,
and compare the hashes.

Three relays, one after the other, each in-process on its own thread and loop with real
sockets on loopback (multicast in, ZeroMQ both ways, UDP out): the SSL simulation protocol
(arming required, the seed's compat sockets, tracker input and tracked vision out), legacy
grSim, and the robot box (arming required, our team yellow). Each gets vision and referee
datagrams (good, empty, oversized), command sets (good and bad robots, stop_all, other team),
the e-stop (press, release), arming (arm, disarm, refused), simulator commands, referee-out
and tracker-out, simulator answers / grSim robot status (valid, repeated, bad) and seed
matrices; the script waits for each step's effect (a datagram, an envelope, a counter) before
the next, and stops the relay (its last word) at the end.

What it records, normalised so that only timing is taken out: every ZeroMQ message (vision,
referee, tracker and feedback envelopes with the receive time zeroed, the sequence counted
from a marker sent after the slow-joiner probes, sources by name; the feedback's ``sent``
by robot ids only (the counts depend on how many cycles ran); the arming acknowledgements'
statistics without rates, ages, CPU and the output's counts), the compat PUBs, and every UDP
datagram to the simulator, grSim (timestamp zeroed), the robot box and the tracked vision
group, per destination (the robot box: per robot), consecutive repeats collapsed (a cycle
repeats what is due 120 times a second: how often is timing, what is not); last, each relay's
final statistics. The hash is over the streams in name order.

    PYTHONPATH=. .venv/bin/python bench/relay_digest.py [--before DIR] [--dump FILE]

``--before DIR``: the same run with the larcmacs_relay package from DIR too (e.g.
``git archive main larcmacs_relay | tar -x -C DIR``); ``--dump FILE``: the records, one a
line, to diff two runs.
"""

from __future__ import annotations

import argparse
import asyncio
import hashlib
import json
import os
import socket
import subprocess
import sys
import threading
import time
from collections import defaultdict
from collections.abc import Callable
from pathlib import Path
from typing import Any

import zmq

from tests.ports import free_port, random_multicast_port

ROOT = Path(__file__).resolve().parent.parent
STEP_TIMEOUT_S = 10.0


def udp_server() -> socket.socket:
    s = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    s.bind(("127.0.0.1", 0))
    s.setblocking(False)
    return s


# ----------------------------------------------------------------------------- inputs


def vision(frame: int, robots: int = 3) -> bytes:
    from sslpb import ssl_vision_wrapper_pb2

    w = ssl_vision_wrapper_pb2.SSL_WrapperPacket()
    d = w.detection
    d.frame_number, d.camera_id, d.t_capture, d.t_sent = frame, frame % 4, 1.0 + frame, 1.5
    for i in range(robots):
        r = d.robots_blue.add()
        r.confidence, r.x, r.y, r.orientation = 0.9, 100.0 * i + frame, 50.0, 0.5
        r.pixel_x, r.pixel_y, r.robot_id = 1.0, 1.0, i
    return w.SerializeToString()


def referee(command: int, counter: int) -> bytes:
    from sslpb.ssl_gc_referee_message_pb2 import Referee

    r = Referee()
    r.packet_timestamp = 1_700_000_000_000_000 + counter
    r.stage = Referee.NORMAL_FIRST_HALF
    r.command = command  # type: ignore[assignment]
    r.command_counter = counter
    r.command_timestamp = 1_700_000_000_000_000
    for t in (r.yellow, r.blue):
        t.name = "x"
        t.score = t.red_cards = t.yellow_cards = t.timeouts = t.timeout_time = t.goalkeeper = 0
    return r.SerializeToString()


def tracked(frame: int, uuid: str) -> bytes:
    from sslpb.ssl_gc_common_pb2 import BLUE
    from sslpb.ssl_vision_wrapper_tracked_pb2 import TrackerWrapperPacket

    p = TrackerWrapperPacket(uuid=uuid, source_name="digest")
    p.tracked_frame.frame_number = frame
    p.tracked_frame.timestamp = 1.7e9 + frame / 60
    r = p.tracked_frame.robots.add(orientation=0.5, visibility=1.0)
    r.robot_id.id, r.robot_id.team = frame % 11, BLUE
    r.pos.x, r.pos.y = 0.1 * frame, -0.2
    return p.SerializeToString()


def command_set(robots: list[tuple[int, int, float]], *, stop_all: bool = False,
                bad: bool = False) -> bytes:
    """(team, id, speed) each; ``bad`` adds one robot of each kind the relay refuses."""
    import math

    from sslpb import touchline_pb2 as tl

    cset = tl.RobotCommandSet(stop_all=stop_all, source_receive_time_ns=time.time_ns())
    for team, rid, v in robots:
        cset.commands.add(team=team, id=rid, forward_mps=v, left_mps=-v / 2,
                          angular_radps=0.25, kick_speed_mps=2.0 if rid == 1 else 0.0,
                          chip=rid == 1 and v > 0.5, dribbler_rpm=300.0 if rid == 2 else 0.0)
    if bad:
        cset.commands.add(team=tl.TEAM_BLUE, id=16, forward_mps=1.0)
        cset.commands.add(team=7, id=1, forward_mps=1.0)
        cset.commands.add(team=tl.TEAM_BLUE, id=5, forward_mps=math.nan)
        cset.commands.add(team=tl.TEAM_BLUE, id=6, kick_speed_mps=-1.0)
    return cset.SerializeToString()


def estop(press: bool) -> bytes:
    from sslpb import touchline_pb2 as tl

    action = tl.EmergencyStop.PRESS if press else tl.EmergencyStop.RELEASE
    return tl.EmergencyStop(action=action, by="digest").SerializeToString()


def arming(armed: bool) -> bytes:
    from sslpb import touchline_pb2 as tl

    return tl.Arming(armed=armed, by="digest").SerializeToString()


def teleport(x: float, robot: int | None = None) -> bytes:
    from sslpb import ssl_gc_common_pb2, ssl_simulation_control_pb2

    cmd = ssl_simulation_control_pb2.SimulatorCommand()
    tb = cmd.control.teleport_ball
    tb.x, tb.y = x, -x / 2
    if robot is not None:
        tr = cmd.control.teleport_robot.add(x=x, y=0.5, orientation=1.0)
        tr.id.id, tr.id.team = robot, ssl_gc_common_pb2.YELLOW
    return cmd.SerializeToString()


def matrix(row: int, speed_x: float, kick: bool = False) -> bytes:
    import numpy as np

    m = np.zeros((32, 13), dtype=np.float64)
    m[row, 0], m[row, 1], m[row, 2], m[row, 3] = 1, speed_x, -10, 20
    if kick:
        m[row, 5], m[row, 7], m[row, 8], m[row, 9], m[row, 10] = 1, 8, 1, 3, 1
    return m.astype("<f8").tobytes()


def sim_answer(contact: int | None = None, error: str | None = None) -> bytes:
    from sslpb import ssl_simulation_robot_feedback_pb2 as fb

    r = fb.RobotControlResponse()
    if contact is not None:
        r.feedback.add(id=contact, dribbler_ball_contact=True)
    if error is not None:
        r.errors.add(code=error, message=f"{error} happened")
    return r.SerializeToString()


def robots_status(rid: int, infrared: bool) -> bytes:
    from sslpb import grsim_robot_status_pb2 as gs

    st = gs.Robots_Status()
    st.robots_status.add(robot_id=rid, infrared=infrared, flat_kick=False, chip_kick=rid == 1)
    return st.SerializeToString()


# ----------------------------------------------------------------------------- recording


class Recorder:
    """Every socket the relay writes to, read into normalised records per stream."""

    def __init__(self) -> None:
        self.poller = zmq.Poller()
        self.readers: dict[Any, Callable[[], None]] = {}
        self.records: dict[str, list[str]] = defaultdict(list)
        self.names: dict[int, str] = {}  # port -> name, for sources
        self.offsets: dict[str, int] = {}  # envelope stream -> the marker's sequence
        self.came_from: dict[str, tuple[str, int]] = {}  # UDP stream -> its last sender
        self.probes: dict[str, tuple[int, int]] = {}  # stream -> probes and marker sent

    def add(self, stream: str, record: str, collapse: bool = False) -> None:
        rec = self.records[stream]
        if collapse and rec and rec[-1] == record:
            return
        rec.append(record)

    def watch(self, sock: Any, reader: Callable[[], None]) -> None:
        self.poller.register(sock, zmq.POLLIN)
        # the poller answers with the socket for ZeroMQ sockets, with the FD for the others
        self.readers[sock if isinstance(sock, zmq.Socket) else sock.fileno()] = reader

    def pump(self, timeout_ms: int = 10) -> None:
        for sock, _ in self.poller.poll(timeout_ms):
            self.readers[sock]()

    def wait(self, cond: Callable[[], bool], what: str) -> None:
        deadline = time.monotonic() + STEP_TIMEOUT_S
        self.pump(0)
        while not cond():
            if time.monotonic() > deadline:
                raise RuntimeError(f"timed out waiting for {what}")
            self.pump(10)

    def settle(self) -> None:
        """After the relay stopped: everything it sent is in the sockets already."""
        for _ in range(3):
            self.pump(20)

    def source(self, source: str) -> str:
        host, _, port = source.rpartition(":")
        return f"{host}:{self.names.get(int(port), 'relay')}"

    # the relay's native PUB
    def on_pub(self, sub: zmq.Socket[bytes]) -> Callable[[], None]:
        from sslpb import touchline_pb2 as tl

        def read() -> None:
            while True:
                try:
                    topic, body = sub.recv_multipart(zmq.NOBLOCK)
                except zmq.Again:
                    return
                name = topic.decode()
                if name in ("vision", "referee", "tracker"):
                    env = tl.Envelope.FromString(body)
                    env.receive_time_ns = 0
                    env.sequence -= self.offsets.get(name, 0)
                    env.source = self.source(env.source)
                    self.add(f"pub {name}", env.SerializeToString().hex())
                elif name == "feedback":
                    fe = tl.RobotFeedbackEnvelope.FromString(body)
                    fe.receive_time_ns = 0
                    fe.source = self.source(fe.source)
                    for s in fe.sent:
                        s.commands_sent = s.last_sent_time_ns = 0
                    self.add("pub feedback", fe.SerializeToString().hex())
                elif name == "stats":
                    self.add("pub stats", stats_text(tl.RelayStats.FromString(body),
                                                     self.probes))
                else:
                    self.add(f"pub {name}", body.hex())
        return read

    def on_zmq_raw(self, sub: zmq.Socket[bytes], stream: str) -> Callable[[], None]:
        def read() -> None:
            while True:
                try:
                    frames = sub.recv_multipart(zmq.NOBLOCK)
                except zmq.Again:
                    return
                self.add(stream, b"|".join(frames).hex())
        return read

    def on_udp(self, sock: socket.socket, stream: Callable[[bytes], str | None],
               normalise: Callable[[bytes], bytes] = lambda d: d) -> Callable[[], None]:
        def read() -> None:
            while True:
                try:
                    data, addr = sock.recvfrom(65536)
                except BlockingIOError:
                    return
                name = stream(data)
                if name is not None:
                    self.came_from[name] = addr
                    self.add(name, normalise(data).hex(), collapse=True)
        return read

    def count(self, stream: str) -> int:
        return len(self.records.get(stream, ()))


def stats_text(s: Any, probes: dict[str, tuple[int, int]]) -> str:
    """RelayStats without what depends on timing (rates, ages, CPU, the output's counts, the
    slow-joiner probes: ``probes`` {stream: (datagrams, bytes)})."""
    from google.protobuf import text_format

    s.time_ns = 0
    s.output_rate_hz = s.cpu_percent = s.rss_mb = 0.0
    s.command_latency_ms = s.command_latency_p50_ms = s.command_latency_p99_ms = 0.0
    for st in s.streams:
        st.rate_hz = st.last_age_s = 0.0
        if st.name == "output":
            st.packets = st.bytes = 0
        n, nbytes = probes.get(st.name, (0, 0))
        st.packets -= n
        st.bytes -= nbytes
    return str(text_format.MessageToString(s, as_one_line=True))


def grsim_stream(data: bytes) -> str:
    from sslpb import grsim_packet_pb2

    pkt = grsim_packet_pb2.grSim_Packet.FromString(data)
    if pkt.HasField("replacement"):
        return "udp grsim replacement"
    return f"udp grsim {'yellow' if pkt.commands.isteamyellow else 'blue'}"


def grsim_normalise(data: bytes) -> bytes:
    from sslpb import grsim_packet_pb2

    pkt = grsim_packet_pb2.grSim_Packet.FromString(data)
    if pkt.HasField("commands"):
        pkt.commands.timestamp = 0.0
    out: bytes = pkt.SerializeToString()
    return out


# ----------------------------------------------------------------------------- one relay


class Run:
    """One relay on its own thread and loop, and the script's sockets around it."""

    def __init__(self, name: str, **overrides: Any) -> None:
        from larcmacs_relay import Relay, RelayConfig
        from sslnet.multicast import open_multicast_receiver, open_multicast_sender

        self.name = name
        self.ctx: zmq.Context[zmq.Socket[bytes]] = zmq.Context()
        self.rec = Recorder()
        self.sim_blue, self.sim_yellow, self.sim_control, self.box = (
            udp_server(), udp_server(), udp_server(), udp_server())
        self.status_blue, self.status_yellow = free_port(), free_port()
        tracker_port = random_multicast_port()
        self.compat_port = free_port(socket.SOCK_STREAM)
        def port(s: socket.socket) -> int:
            p: int = s.getsockname()[1]
            return p

        cfg = RelayConfig(
            vision_port=random_multicast_port(), referee_port=random_multicast_port(),
            tracker_port=tracker_port, tracker_out_port=tracker_port,
            pub_endpoint="tcp://127.0.0.1:*", sub_endpoint="tcp://127.0.0.1:*",
            sim_blue_port=port(self.sim_blue), sim_yellow_port=port(self.sim_yellow),
            sim_control_port=port(self.sim_control), grsim_port=port(self.sim_blue),
            grsim_status_host="127.0.0.1", grsim_status_blue_port=self.status_blue,
            grsim_status_yellow_port=self.status_yellow, robot_box_port=port(self.box),
            compat_vision_pub="tcp://127.0.0.1:*", compat_referee_pub="tcp://127.0.0.1:*",
            compat_commands=f"tcp://127.0.0.1:{self.compat_port}",
            command_timeout_s=1.0, hold_time_s=30.0, stats_interval_s=3600.0,
            max_datagram_bytes=2048,
        )
        import dataclasses

        self.cfg = cfg = dataclasses.replace(cfg, **overrides)
        self.sender = open_multicast_sender("127.0.0.1")
        self.rec.names[port(self.sender)] = "sender"
        for label, s in (("sim-blue", self.sim_blue), ("sim-yellow", self.sim_yellow),
                         ("sim-control", self.sim_control)):
            self.rec.names[port(s)] = label
        self.tracker_listener = open_multicast_receiver(cfg.tracker_out_group,
                                                        cfg.tracker_out_port, "127.0.0.1")
        self.tracker_listener.setblocking(False)
        # the seed strategy-bridge's PUB (the relay connects): an XPUB tells when it has
        self.bridge = self.ctx.socket(zmq.XPUB)
        self.bridge.setsockopt(zmq.LINGER, 0)
        self.bridge.bind(f"tcp://127.0.0.1:{self.compat_port}")
        self.relay = Relay(cfg)
        self.loop = asyncio.new_event_loop()
        self.ready = threading.Event()
        self.error: BaseException | None = None
        self.thread = threading.Thread(target=self._run, daemon=True)
        self.thread.start()
        if not self.ready.wait(STEP_TIMEOUT_S):
            raise RuntimeError(f"relay {name} did not come up: {self.error!r}")
        self._connect()

    def _run(self) -> None:
        async def main() -> None:
            task = asyncio.create_task(self.relay.run())
            waiter = asyncio.create_task(self.relay.ready.wait())
            await asyncio.wait([task, waiter], return_when=asyncio.FIRST_COMPLETED)
            self.ready.set()
            await task

        try:
            self.loop.run_until_complete(main())
        except BaseException as exc:  # reported by the main thread
            self.error = exc
            self.ready.set()

    def _connect(self) -> None:
        rec, relay, cfg = self.rec, self.relay, self.cfg
        self.pub = self.ctx.socket(zmq.XPUB)
        self.pub.setsockopt(zmq.LINGER, 0)
        self.pub.connect(relay.sub_address)
        topics = {b"commands", b"sim", b"referee-out", b"tracker-out", b"estop", b"arming"}
        seen: set[bytes] = set()
        deadline = time.monotonic() + STEP_TIMEOUT_S
        while seen != topics:  # the relay's SUB has subscribed: nothing sent is lost
            if time.monotonic() > deadline or not self.pub.poll(1000):
                raise RuntimeError("the relay's SUB never subscribed")
            seen.add(self.pub.recv()[1:])
        self.sub = self.ctx.socket(zmq.SUB)
        self.sub.setsockopt(zmq.LINGER, 0)
        self.sub.setsockopt(zmq.SUBSCRIBE, b"")
        self.sub.connect(relay.pub_address)
        subs = [self.sub]
        if cfg.compat:
            if not self.bridge.poll(int(STEP_TIMEOUT_S * 1000)):
                raise RuntimeError("the relay never subscribed to the bridge")
            self.bridge.recv()
            self.cv = self.ctx.socket(zmq.SUB)
            self.cr = self.ctx.socket(zmq.SUB)
            for s, addr in ((self.cv, relay.compat_vision_address),
                            (self.cr, relay.compat_referee_address)):
                s.setsockopt(zmq.LINGER, 0)
                s.setsockopt(zmq.SUBSCRIBE, b"")
                s.connect(addr)
            subs += [self.cv, self.cr]
        # slow joiners: probes until every subscriber hears, then a marker, then the digest
        self._probe(lambda: self.send_vision(vision(0)), vision(999), "vision",
                    [s for s in subs if s is not getattr(self, "cr", None)])
        self._probe(lambda: self.send_referee(referee(0, 0)), referee(1, 999), "referee",
                    [s for s in subs if s is not getattr(self, "cv", None)])
        if cfg.tracker_enabled:
            self._probe(lambda: self.send_tracker(tracked(0, "probe")), tracked(999, "marker"),
                        "tracker", [self.sub])
        rec.watch(self.sub, rec.on_pub(self.sub))
        if cfg.compat:
            rec.watch(self.cv, rec.on_zmq_raw(self.cv, "compat vision"))
            rec.watch(self.cr, rec.on_zmq_raw(self.cr, "compat referee"))
        if cfg.output == "sim":
            rec.watch(self.sim_blue, rec.on_udp(self.sim_blue, lambda d: "udp sim blue"))
            rec.watch(self.sim_yellow, rec.on_udp(self.sim_yellow, lambda d: "udp sim yellow"))
            rec.watch(self.sim_control, rec.on_udp(self.sim_control, lambda d: "udp sim control"))
        elif cfg.output == "grsim":
            rec.watch(self.sim_blue, rec.on_udp(self.sim_blue, grsim_stream, grsim_normalise))
        else:
            rec.watch(self.box, rec.on_udp(self.box, lambda d: f"udp box robot {d[1]}"))

        def ours(data: bytes) -> str | None:  # the relay's tracked vision, not the script's
            return "udp tracker-out" if b"touchline-digest" in data else None

        rec.watch(self.tracker_listener, rec.on_udp(self.tracker_listener, ours))

    def _probe(self, probe: Callable[[], int], marker: bytes, stream: str,
               subs: list[zmq.Socket[bytes]]) -> None:
        from sslpb import touchline_pb2 as tl

        deadline = time.monotonic() + STEP_TIMEOUT_S
        heard: set[int] = set()
        sent = 1, len(marker)
        while len(heard) < len(subs):
            if time.monotonic() > deadline:
                raise RuntimeError(f"subscribers never heard {stream}")
            sent = sent[0] + 1, sent[1] + probe()
            for i, s in enumerate(subs):
                if i not in heard and s.poll(50):
                    heard.add(i)
        {"vision": self.send_vision, "referee": self.send_referee,
         "tracker": self.send_tracker}[stream](marker)
        self.rec.probes[stream] = sent
        for s in subs:
            while True:  # everything up to the marker is a probe
                if not s.poll(int(STEP_TIMEOUT_S * 1000)):
                    raise RuntimeError(f"no {stream} marker")
                frames = s.recv_multipart()
                if s is self.sub:
                    if frames[0] != stream.encode():
                        continue
                    env = tl.Envelope.FromString(frames[1])
                    if env.payload == marker:
                        self.rec.offsets[stream] = env.sequence
                        break
                elif s is getattr(self, "cv", None):
                    if frames[-1] == marker:
                        break
                elif b'"state": 1' in frames[-1]:  # the referee marker is a STOP
                    break

    # what the script sends
    def send_vision(self, data: bytes) -> int:
        return self.sender.sendto(data, (self.cfg.vision_group, self.cfg.vision_port))

    def send_referee(self, data: bytes) -> int:
        return self.sender.sendto(data, (self.cfg.referee_group, self.cfg.referee_port))

    def send_tracker(self, data: bytes) -> int:
        return self.sender.sendto(data, (self.cfg.tracker_group, self.cfg.tracker_port))

    def send(self, topic: bytes, body: bytes) -> None:
        self.pub.send_multipart([topic, body])

    def counter(self, stream: str) -> tuple[int, int]:
        c = self.relay.streams[stream]
        return c.packets, c.errors

    def wait_counter(self, stream: str, packets: int, errors: int) -> None:
        self.rec.wait(lambda: self.counter(stream) == (packets, errors),
                      f"{self.name}: {stream} at {packets} packets, {errors} errors")

    def wait_new(self, stream: str, before: int, what: str = "") -> None:
        self.rec.wait(lambda: self.rec.count(stream) > before,
                      f"{self.name}: {what or 'a new record'} on {stream}")

    def finish(self) -> dict[str, list[str]]:
        self.loop.call_soon_threadsafe(self.relay.stop)
        self.thread.join(STEP_TIMEOUT_S)
        if self.error is not None:
            raise self.error
        self.rec.settle()
        self.rec.add("final stats", stats_text(self.relay.stats(), self.rec.probes))
        for s in (self.sim_blue, self.sim_yellow, self.sim_control, self.box, self.sender,
                  self.tracker_listener):
            s.close()
        self.ctx.destroy(linger=0)
        self.loop.close()
        return dict(self.rec.records)


# ----------------------------------------------------------------------------- scenarios


def common_inputs(r: Run) -> None:
    """Vision (good, empty, oversized) and referee datagrams."""
    n = r.rec.count("pub vision")
    for f in range(1, 6):
        r.send_vision(vision(f, robots=f % 4))
    r.send_vision(b"")
    r.send_vision(b"\x0a" + b"\x00" * 3000)
    r.send_vision(vision(6))
    r.rec.wait(lambda: r.rec.count("pub vision") == n + 6, "six vision envelopes")
    r.rec.wait(lambda: r.counter("vision")[1] == 2, "two vision errors")
    n = r.rec.count("pub referee")
    from sslpb.ssl_gc_referee_message_pb2 import Referee

    for k, cmd in enumerate((Referee.PREPARE_KICKOFF_BLUE, Referee.NORMAL_START,
                             Referee.DIRECT_FREE_YELLOW), start=1):
        r.send_referee(referee(cmd, k))
    r.send_referee(b"")
    r.send_referee(referee(Referee.STOP, 4))
    r.rec.wait(lambda: r.rec.count("pub referee") == n + 4, "four referee envelopes")
    r.rec.wait(lambda: r.counter("referee")[1] == 1, "one referee error")


def sim_scenario() -> dict[str, list[str]]:
    from sslpb import touchline_pb2 as tl

    B, Y = tl.TEAM_BLUE, tl.TEAM_YELLOW
    r = Run("sim", output="sim", require_arming=True, compat=True, tracker_enabled=True)
    rec = r.rec
    common_inputs(r)
    if r.cfg.compat:
        rec.wait(lambda: rec.count("compat referee") >= 4, "compat referee")
    # tracker: a foreign one is forwarded, our own out and its echo is not
    r.send_tracker(tracked(5, "foreign"))
    rec.wait(lambda: rec.count("pub tracker") == 1, "a foreign tracker")
    r.send(b"tracker-out", tracked(1, "touchline-digest"))
    r.send(b"tracker-out", b"\x0a\x01x")  # no tracked frame
    rec.wait(lambda: rec.count("udp tracker-out") == 1, "tracked vision out")
    r.wait_counter("tracker_out", 1, 1)
    rec.wait(lambda: r.relay.own_tracker_echoes >= 1, "its own tracked vision heard back")
    r.send_tracker(tracked(6, "foreign"))
    rec.wait(lambda: rec.count("pub tracker") == 2, "another foreign tracker")
    # disarmed: a command set is dropped
    r.send(b"commands", command_set([(B, 0, 0.4)]))
    r.wait_counter("commands", 0, 1)
    # arming (acknowledged with the statistics)
    r.send(b"arming", arming(True))
    rec.wait(lambda: rec.count("pub stats") == 1, "the arming acknowledgement")
    r.send(b"commands", command_set([(B, 0, 0.4), (B, 1, 0.9), (B, 2, 0.3), (Y, 3, 0.2)]))
    rec.wait(lambda: rec.count("udp sim blue") == 1 and rec.count("udp sim yellow") == 1,
             "the first commands")
    n = rec.count("udp sim blue")
    r.send(b"commands", command_set([(B, 0, 0.6), (B, 2, 0.3)], bad=True))
    r.wait_new("udp sim blue", n, "the second commands")
    r.wait_counter("commands", 2, 5)
    # simulator control
    r.send(b"sim", teleport(1.5, robot=3))
    r.send(b"sim", b"\xff\xff")
    r.send(b"sim", teleport(-0.5))
    rec.wait(lambda: rec.count("udp sim control") == 2, "two simulator commands")
    r.wait_counter("sim_commands", 2, 1)
    # referee out: multicast, heard back on the referee input
    from sslpb.ssl_gc_referee_message_pb2 import Referee

    n = rec.count("pub referee")
    r.send(b"referee-out", referee(Referee.HALT, 7))
    r.send(b"referee-out", b"\x08")
    rec.wait(lambda: rec.count("pub referee") == n + 1, "the referee out heard back")
    r.wait_counter("referee_out", 1, 1)
    # the simulator's answers (the relay's output socket is where they go)
    relay_out = rec.came_from["udp sim blue"]  # the relay's output socket
    for data in (sim_answer(), sim_answer(), sim_answer(contact=1), b"\xff\xff",
                 sim_answer(error="BAD")):
        r.sim_blue.sendto(data, relay_out)
    r.sim_yellow.sendto(sim_answer(contact=3), relay_out)
    r.sim_control.sendto(sim_answer(error="CTL"), relay_out)
    rec.wait(lambda: rec.count("pub feedback") == 5, "five feedback envelopes")
    rec.wait(lambda: r.counter("sim_responses") == (7, 3), "seven answers, three errors")
    # the seed's matrix drives blue 4
    n = rec.count("udp sim blue")
    r.bridge.send(matrix(4, 40.0, kick=True))
    r.wait_new("udp sim blue", n, "the seed's robot 4")
    r.bridge.send(b"short")
    r.wait_counter("compat_commands", 1, 1)
    # stop_all, then commands again
    n = rec.count("udp sim blue")
    r.send(b"commands", command_set([(B, 2, 0.7)], stop_all=True))
    r.wait_new("udp sim blue", n, "stop_all's zeros")
    n = rec.count("udp sim blue")
    r.send(b"commands", command_set([(B, 0, 0.8), (B, 4, 0.1)]))
    r.wait_new("udp sim blue", n, "commands after stop_all")
    # the e-stop: zeros, disarmed; commands and the seed's matrix dropped; arming refused
    n = rec.count("udp sim blue")
    r.send(b"estop", estop(True))
    r.wait_new("udp sim blue", n, "the e-stop's zeros")
    r.send(b"commands", command_set([(B, 0, 1.0)]))
    r.bridge.send(matrix(4, 60.0))
    r.send(b"arming", arming(True))
    rec.wait(lambda: r.counter("compat_commands") == (2, 1), "the matrix while latched")
    r.wait_counter("commands", 5, 6)
    r.send(b"estop", estop(False))
    r.send(b"estop", b"\x08\x09")
    r.send(b"arming", arming(True))
    rec.wait(lambda: rec.count("pub stats") == 2, "re-armed")
    n = rec.count("udp sim blue")
    r.send(b"commands", command_set([(B, 0, 0.5), (B, 1, 0.2), (Y, 3, 0.9)]))
    r.wait_new("udp sim blue", n, "commands after the release")
    # disarm and arm again
    r.send(b"arming", arming(False))
    rec.wait(lambda: rec.count("pub stats") == 3, "disarmed")
    r.send(b"arming", arming(False))  # a repeat: nothing
    r.send(b"arming", arming(True))
    rec.wait(lambda: rec.count("pub stats") == 4, "armed again")
    # the stale stop: a robot's command older than the timeout becomes zero
    n = rec.count("udp sim yellow")
    r.send(b"commands", command_set([(Y, 3, 0.3), (Y, 5, 0.1)]))
    r.wait_new("udp sim yellow", n, "yellow commands")
    n = rec.count("udp sim yellow")
    r.wait_new("udp sim yellow", n, "the stale stop")
    n = rec.count("udp sim blue")
    r.send(b"commands", command_set([(B, 1, 0.45)]))
    r.wait_new("udp sim blue", n, "commands after the stale stop")
    return r.finish()


def grsim_scenario() -> dict[str, list[str]]:
    from sslpb import touchline_pb2 as tl

    B, Y = tl.TEAM_BLUE, tl.TEAM_YELLOW
    r = Run("grsim", output="grsim")
    rec = r.rec
    common_inputs(r)
    r.send(b"arming", arming(False))  # always armed: ignored
    r.send(b"commands", command_set([(B, 0, 0.4), (B, 1, 0.9), (Y, 2, 0.3)], bad=True))
    rec.wait(lambda: rec.count("udp grsim blue") == 1 and rec.count("udp grsim yellow") == 1,
             "the first commands")
    r.send(b"sim", teleport(1.5, robot=3))
    r.send(b"sim", tl.Arming().SerializeToString())  # a SimulatorCommand with nothing in it
    r.send(b"sim", teleport(0.5))
    rec.wait(lambda: rec.count("udp grsim replacement") == 2, "two replacements")
    r.wait_counter("sim_commands", 3, 0)
    status = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    status.bind(("127.0.0.1", 0))
    rec.names[status.getsockname()[1]] = "grsim"
    for data, port in ((robots_status(0, True), r.status_blue),
                       (robots_status(0, True), r.status_blue),
                       (b"\xff", r.status_blue), (robots_status(1, False), r.status_yellow)):
        status.sendto(data, ("127.0.0.1", port))
    rec.wait(lambda: rec.count("pub feedback") == 3, "three robot status envelopes")
    r.wait_counter("grsim_status", 3, 1)
    status.close()
    n = rec.count("udp grsim blue")
    r.send(b"estop", estop(True))
    r.wait_new("udp grsim blue", n, "the e-stop's zeros")
    r.send(b"commands", command_set([(B, 0, 1.0)]))
    r.wait_counter("commands", 2, 4)
    r.send(b"estop", estop(False))
    n = rec.count("udp grsim blue")
    r.send(b"commands", command_set([(B, 0, 0.7), (B, 3, 0.2)]))
    r.wait_new("udp grsim blue", n, "commands after the release")
    n = rec.count("udp grsim blue")
    r.send(b"commands", command_set([(Y, 2, 0.1)], stop_all=True))
    r.wait_new("udp grsim blue", n, "stop_all")
    return r.finish()


def box_scenario() -> dict[str, list[str]]:
    from sslpb import touchline_pb2 as tl

    B, Y = tl.TEAM_BLUE, tl.TEAM_YELLOW
    r = Run("robot-box", output="robot-box", require_arming=True, our_team="yellow")
    rec = r.rec
    common_inputs(r)
    r.send(b"commands", command_set([(Y, 1, 0.4)]))
    r.wait_counter("commands", 0, 1)
    r.send(b"arming", arming(True))
    rec.wait(lambda: rec.count("pub stats") == 1, "armed")
    r.send(b"commands", command_set([(Y, 0, 0.4), (Y, 1, 0.9), (Y, 2, 0.3), (B, 3, 0.5)]))
    rec.wait(lambda: all(rec.count(f"udp box robot {i}") == 1 for i in range(3)),
             "the first commands")
    r.wait_counter("commands", 1, 2)
    r.send(b"sim", teleport(1.0))
    r.wait_counter("sim_commands", 1, 1)
    n = rec.count("udp box robot 1")
    r.send(b"commands", command_set([(Y, 1, 0.2), (Y, 0, 0.4)]))
    r.wait_new("udp box robot 1", n, "the second commands")
    n = rec.count("udp box robot 0")
    r.send(b"estop", estop(True))
    r.wait_new("udp box robot 0", n, "the e-stop's zeros")
    r.send(b"arming", arming(True))
    r.wait_counter("commands", 2, 3)
    r.send(b"estop", estop(False))
    r.send(b"arming", arming(True))
    rec.wait(lambda: rec.count("pub stats") == 2, "re-armed")
    n = rec.count("udp box robot 2")
    r.send(b"commands", command_set([(Y, 2, 0.6)]))
    r.wait_new("udp box robot 2", n, "commands after the release")
    n = rec.count("udp box robot 2")
    r.wait_new("udp box robot 2", n, "the stale stop")
    return r.finish()


def child(dump: str | None) -> None:
    import numpy  # noqa: F401  (the relay imports it at its first seed matrix: not mid-step)

    records: dict[str, list[str]] = {}
    for name, scenario in (("sim", sim_scenario), ("grsim", grsim_scenario),
                           ("robot-box", box_scenario)):
        for stream, recs in scenario().items():
            records[f"{name} {stream}"] = recs
    h = hashlib.sha256()
    lines = []
    for stream in sorted(records):
        for i, rec in enumerate(records[stream]):
            line = f"{stream} {i} {rec}"
            lines.append(line)
            h.update(line.encode() + b"\n")
    if dump:
        Path(dump).write_text("\n".join(lines) + "\n")
    counts = {s: len(r) for s, r in sorted(records.items())}
    print(json.dumps({"digest": h.hexdigest(), "records": len(lines), "streams": counts}))


def run_variant(root: Path, dump: str | None) -> dict[str, Any]:
    env = dict(os.environ, PYTHONPATH=f"{root}{os.pathsep}{ROOT}")
    args = [sys.executable, str(Path(__file__).resolve()), "--child"]
    if dump:
        args += ["--dump", dump]
    out = subprocess.run(args, env=env, capture_output=True, text=True, cwd=root)
    if out.returncode != 0:
        raise RuntimeError(f"{root}: {out.stderr[-3000:]}")
    result: dict[str, Any] = json.loads(out.stdout.strip().splitlines()[-1])
    return result


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--before", type=Path, default=None)
    ap.add_argument("--dump", default=None, help="write the records here (before: FILE.before)")
    ap.add_argument("--child", action="store_true", help=argparse.SUPPRESS)
    a = ap.parse_args()
    if a.child:
        child(a.dump)
        return
    variants = [("after", ROOT, a.dump)]
    if a.before is not None:
        variants.insert(0, ("before", a.before.resolve(), a.dump and f"{a.dump}.before"))
    for name, root, dump in variants:
        res = run_variant(root, dump)
        print(f"{name} ({root / 'larcmacs_relay'}): {res['digest']} ({res['records']} records "
              f"in {len(res['streams'])} streams)")


if __name__ == "__main__":
    main()
