"""The station thread's per-frame path through real sockets, in CPU time (figures, not a test).

Between bench/pipeline_bench.py (the processors' ticks in a hot loop: no runner, no event
loop, no ZeroMQ, and a clock that runs ~10x faster than the frames' own) and
bench/loop_bench.py (the whole station beside the relay, the simulator and the strategy, on a
shared machine): the processors of the hot path (relay ingest, vision ingest, world model,
control, command publisher, tracked vision out) run in the station's Runner on an event loop
in this process's main thread, behind real ZeroMQ sockets. A child process stands in for the
relay: it publishes ``pipeline_bench``'s frames (8 cameras x 75 Hz, division A, 11 v 11) at
``--hz`` frames a second as the relay's envelopes and takes the commands and tracked vision
back. Targets for the 11 blue robots come at 20 Hz like the strategy's.

Prints the main thread's CPU time per camera frame (what the station thread spends from the
socket becoming readable to the command set sent, the event loop and the runner included),
its share of a core at 600 frames/s, the passes per frame, and the arrival -> command latency
the stand-in saw (its clock, this machine's load in it).

    PYTHONPATH=. .venv/bin/python bench/pass_bench.py [--frames 6000] [--hz 600]

Under callgrind (instruction counts, which the machine's load does not move), a lower rate
and ``--lockstep`` keep one frame a pass, and ``PASS_BENCH_CALLGRIND=1`` counts only the
measured frames: ``PASS_BENCH_CALLGRIND=1 PASS_BENCH_WARMUP=100 valgrind --tool=callgrind
--separate-threads=yes python bench/pass_bench.py --hz 20 --lockstep --frames 200``.
"""

from __future__ import annotations

import argparse
import asyncio
import json
import math
import multiprocessing
import os
import statistics
import subprocess
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

import zmq
import zmq.asyncio

from backend import topics
from backend.bus import DataBus, Reader
from backend.control.goto import LocalVelocity, Target
from backend.messages import Command, CommandSet, TargetEntry
from backend.processor import Every, OnTopic, Processor, Runner
from backend.processors import (
    CommandPublisher,
    ControlProcessor,
    RelayIngest,
    TrackerPublisher,
    VisionIngest,
    WorldProcessor,
)
from backend.zmqio import pub_socket, sub_socket
from bench.pipeline_bench import datagrams
from sslpb import touchline_pb2 as tl
from sslpb.ssl_vision_wrapper_pb2 import SSL_WrapperPacket

WARMUP = int(os.environ.get("PASS_BENCH_WARMUP", "300"))


def relay(pub_ep: str, sub_ep: str, frames: int, hz: float, lockstep: bool,
          conn: object) -> None:
    """The relay's stand-in: frames out at ``hz`` (``lockstep``: at most, each after the
    station's answer to the last one, or 0.5 s), commands in; sends the latencies back."""
    ctx = zmq.Context()
    pub, sub = ctx.socket(zmq.PUB), ctx.socket(zmq.SUB)
    pub.bind(pub_ep)
    sub.bind(sub_ep)
    sub.setsockopt(zmq.SUBSCRIBE, b"")
    raw = datagrams(frames + WARMUP, time.time())
    poller = zmq.Poller()
    poller.register(sub, zmq.POLLIN)
    first: dict[int, float] = {}  # receive time -> first command's latency
    answered: set[int] = set()  # receive times of the frames with a command set or tracks

    def take(until: float, stamp: int = 0) -> None:
        """Takes what comes back until ``until`` (or the answer to ``stamp``)."""
        while True:
            left = until - time.monotonic()
            if left <= 0 or (stamp and stamp in answered):
                return
            for sock, _ in poller.poll(max(1, round(left * 1000))):
                while True:
                    try:
                        topic, body = sock.recv_multipart(zmq.NOBLOCK)
                    except zmq.Again:
                        break
                    now = time.time_ns()
                    if topic == b"commands":
                        r = tl.RobotCommandSet.FromString(body).source_receive_time_ns
                        if r > 0 and r not in first:
                            first[r] = (now - r) / 1e6
                        answered.add(r)
                    elif topic == b"tracker-out":
                        answered.add(stamp)

    time.sleep(1.0)  # the backend's SUB joins
    due = time.monotonic()
    for i, (_, payload) in enumerate(raw):
        take(due)
        pkt = SSL_WrapperPacket.FromString(payload)  # stamped now (at any --hz)
        pkt.detection.t_capture = pkt.detection.t_sent = time.time()
        stamp = time.time_ns()
        env = tl.Envelope(stream=tl.STREAM_VISION, receive_time_ns=stamp, sequence=i,
                          source="bench", payload=pkt.SerializeToString())
        pub.send_multipart([b"vision", env.SerializeToString()])
        if i == WARMUP:
            first.clear()
        if lockstep:
            take(time.monotonic() + 0.5, stamp)
            due = max(due + 1 / hz, time.monotonic())
        else:
            due += 1 / hz
    take(time.monotonic() + 0.2)
    conn.send(json.dumps(sorted(first.values())))  # type: ignore[attr-defined]
    ctx.destroy(linger=0)


class Targets(Processor):
    """The strategy's stand-in: targets for the 11 blue robots at 20 Hz."""

    name = "targets"

    def __init__(self, bus: DataBus) -> None:
        super().__init__(Every(20.0))
        self.topic = bus.of(topics.TARGETS)
        self.k = 0

    async def tick(self) -> None:
        self.k += 1
        k = self.k
        self.topic.write({("blue", i): TargetEntry(Target(3000.0 * math.cos(i + k * 0.01),
                                                          2000.0 * math.sin(i + k * 0.01), 0.0),
                                                   "strategy") for i in range(11)})


def callgrind(op: str) -> None:
    """Zeroes (``-z``) or dumps (``-d``) the counts when run under valgrind's callgrind."""
    if os.environ.get("PASS_BENCH_CALLGRIND"):
        subprocess.run(["callgrind_control", op, str(os.getpid())], check=False,
                       stdout=subprocess.DEVNULL)


class FixedControl(Processor):
    """``--frame-only``: control's stand-in, the same 11 commands for every decoded frame
    (the world model, control and tracked vision left out: what is left is the frame's
    way in and out, the runner and the event loop, and it does not depend on the clock)."""

    name = "fixed-control"

    def __init__(self, bus: DataBus) -> None:
        detections = bus.of(topics.VISION_DETECTIONS)
        super().__init__(OnTopic(detections))
        self.reader = Reader(detections)
        self.commands = bus.of(topics.ROBOT_COMMANDS)
        self.cmds = tuple(Command("blue", i, LocalVelocity(0.5, 0.1 * i, 0.2))
                          for i in range(11))

    def step(self) -> None:
        frames = self.reader.read_new()
        if frames:
            self.commands.write(CommandSet(time.time_ns(), frames[-1].receive_time_ns,
                                           self.cmds))


async def station(pub_ep: str, sub_ep: str, frames: int, frame_only: bool
                  ) -> dict[str, float]:
    ctx = zmq.asyncio.Context()
    bus = DataBus({})
    ingest = RelayIngest(bus)
    publisher = CommandPublisher(bus)
    tracker = TrackerPublisher(bus, "uuid")
    control = ControlProcessor(bus, max_wait_s=0.1, vision_stale_s=1.0)
    procs: list[Processor] = [ingest, VisionIngest(bus), WorldProcessor(bus), Targets(bus),
                              control, publisher, tracker]
    if frame_only:
        procs = [ingest, VisionIngest(bus), FixedControl(bus), publisher]
    ingest.attach(sub_socket(ctx, pub_ep, [b"vision", b"referee", b"stats", b"feedback"]))
    publisher.attach(pub_socket(ctx, sub_ep))
    tracker.attach(publisher.sock)
    runner = Runner()
    for p in procs:
        runner.add(p)
    await runner.start()
    packets = bus.of(topics.VISION_PACKETS)
    try:
        for _ in range(60000):  # bounded: the warm-up frames arrive (60 s at most)
            if packets.seq >= WARMUP:
                break
            await asyncio.sleep(0.001)
        callgrind("-z")  # under callgrind: the counts of the measured frames only
        cpu0, seq0 = time.thread_time(), packets.seq
        runs0 = {p.name: p.stats.rate.total for p in procs}
        t_end = time.monotonic() + 600
        while packets.seq < WARMUP + frames - 1 and time.monotonic() < t_end:
            await asyncio.sleep(0.05)
        cpu, n = time.thread_time() - cpu0, packets.seq - seq0
        callgrind("-d")
        runs = {p.name: (p.stats.rate.total - runs0[p.name]) / max(1, n) for p in procs}
        ticks = {p.name: p.stats.summary()["tick_mean_ms"] * 1000 for p in procs}
    finally:
        await runner.stop()
        ctx.destroy(linger=0)
    return {"cpu_us": cpu / max(1, n) * 1e6, "frames": n,
            **{f"runs/{k}": v for k, v in runs.items()},
            **{f"tick/{k}": v for k, v in ticks.items()}}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--frames", type=int, default=6000)
    ap.add_argument("--hz", type=float, default=600.0)
    ap.add_argument("--frame-only", action="store_true",
                    help="the frame's way in and out only: relay ingest, vision ingest, a "
                    "fixed command set per frame, the command publisher (the runner and the "
                    "event loop around them; deterministic, for instruction counts)")
    ap.add_argument("--lockstep", action="store_true",
                    help="each frame after the station's answer to the last (one a pass "
                    "however slow the station runs: under callgrind)")
    a = ap.parse_args()
    base = 43000 + (int(time.time() * 1000) % 2000) * 2
    pub_ep, sub_ep = f"tcp://127.0.0.1:{base}", f"tcp://127.0.0.1:{base + 1}"
    mp = multiprocessing.get_context("spawn")
    here, there = mp.Pipe()
    child = mp.Process(target=relay, args=(pub_ep, sub_ep, a.frames, a.hz, a.lockstep, there),
                       daemon=True)
    child.start()
    r = asyncio.run(station(pub_ep, sub_ep, a.frames, a.frame_only))
    lat: list[float] = json.loads(here.recv()) if here.poll(30) else []
    child.join(10)
    us = r["cpu_us"]
    print(f"{r['frames']:.0f} frames at {a.hz:g}/s: station thread {us:.1f} us CPU a frame, "
          f"{us * 600 / 1e4:.1f} % of a core at 600 frames/s")
    print("  runs a frame: " + ", ".join(f"{k[5:]} {v:.2f}" for k, v in r.items()
                                        if k.startswith("runs/")))
    print("  tick mean (wall, the last 512): " + ", ".join(
        f"{k[5:]} {v:.1f} us" for k, v in r.items() if k.startswith("tick/")))
    if lat:
        print(f"  arrival -> command p50 {statistics.median(lat):.3f} ms, "
              f"p99 {lat[min(len(lat) - 1, int(0.99 * len(lat)))]:.3f} ms ({len(lat)} sets)")


if __name__ == "__main__":
    main()
