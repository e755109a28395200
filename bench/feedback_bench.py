"""The robot feedback path alone, CPU per answer (figures, not a test).

The relay in this process (its asyncio loop on the main thread, ``sim`` output); in a child
process a stand-in simulator thread answering every RobotControl with an 11-robot
RobotControlResponse (robot 3's ball contact flips every ``--flip`` answers), a commander
thread sending a
RobotCommandSet for blue 0..10 at ``--hz`` over ZeroMQ, and a stand-in backend thread that
does the backend's feedback work for each envelope (parse it, decode the payload, update the
FeedbackTracker). CPU time of the relay's loop thread and of the backend thread, divided by
the answers the relay got: per-answer costs hold on a busy machine where rates do not.

    PYTHONPATH=. .venv/bin/python bench/feedback_bench.py [--seconds 10] [--hz 300]
        [--feedback-interval 0.02]
    # the relay of an older commit (git archive OLD larcmacs_relay | tar -x -C DIR):
    PYTHONPATH=DIR:. .venv/bin/python bench/feedback_bench.py --old

``--micro``: only the relay's answer handling (``_drain_responses``: receive, check, forward
or hold, and the held answers' timers), ``--batch`` answers queued on a socket every 3 ms, no
other traffic: the relay's CPU per answer (with its loop's wake-ups) without the rest.
"""

from __future__ import annotations

import argparse
import asyncio
import dataclasses
import multiprocessing
import socket
import threading
import time
from multiprocessing.connection import Connection

import zmq

import larcmacs_relay
from backend.world.feedback import Decoder, FeedbackTracker, decode
from larcmacs_relay import Relay, RelayConfig
from sslpb import ssl_simulation_robot_feedback_pb2 as fb_pb
from sslpb import touchline_pb2 as tl


def two_answers() -> list[bytes]:
    """A simulator's answer for 11 robots, without and with robot 3's ball contact."""
    answers = []
    for contact in (False, True):
        resp = fb_pb.RobotControlResponse()
        for i in range(11):
            resp.feedback.add(id=i, dribbler_ball_contact=contact and i == 3)
        answers.append(resp.SerializeToString())
    return answers


def simulator(sock: socket.socket, stop: threading.Event, flip: int) -> None:
    """Answers every datagram to its sender, like a simulator's robot port."""
    answers = two_answers()
    sock.settimeout(0.2)
    n = 0
    while not stop.is_set():
        try:
            _, addr = sock.recvfrom(65536)
        except TimeoutError:
            continue
        n += 1
        sock.sendto(answers[(n // flip) % 2], addr)


def commander(endpoint: str, hz: float, stop: threading.Event) -> None:
    ctx = zmq.Context()
    pub = ctx.socket(zmq.PUB)
    pub.connect(endpoint)
    period = 1.0 / hz
    nxt = time.monotonic()
    seq = 0
    try:
        while not stop.is_set():
            seq += 1
            cset = tl.RobotCommandSet(sequence=seq)
            for i in range(11):
                cset.commands.add(team=tl.TEAM_BLUE, id=i, forward_mps=0.1 * (seq % 7))
            pub.send_multipart([b"commands", cset.SerializeToString()])
            nxt += period
            time.sleep(max(0.0, nxt - time.monotonic()))
    finally:
        ctx.destroy(linger=0)


@dataclasses.dataclass
class BackendSide:
    envelopes: int = 0
    cpu_s: float = 0.0
    measuring: bool = False


def backend(endpoint: str, stop: threading.Event, old: bool, out: BackendSide) -> None:
    """The backend's feedback work per envelope, its thread's CPU counted while measuring."""
    ctx = zmq.Context()
    sub = ctx.socket(zmq.SUB)
    sub.setsockopt(zmq.SUBSCRIBE, b"feedback")
    sub.connect(endpoint)
    tracker = FeedbackTracker()
    dec = decode if old else Decoder()
    try:
        while not stop.is_set():
            if not sub.poll(200):
                continue
            t0 = time.thread_time()
            _, body = sub.recv_multipart()
            env = tl.RobotFeedbackEnvelope.FromString(body)
            d = dec(env)
            if not isinstance(d, tuple):
                tracker.update(env, d, time.monotonic())
            if out.measuring:
                out.cpu_s += time.thread_time() - t0
                out.envelopes += 1
    finally:
        ctx.destroy(linger=0)


def stand_ins(conn: Connection, hz: float, flip: int, old: bool) -> None:
    """The child process: simulator, commander and backend threads (not in the relay's
    process: they would share its GIL)."""
    sim = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    sim.bind(("127.0.0.1", 0))
    conn.send(sim.getsockname()[1])
    sub_address, pub_address = conn.recv()
    stop = threading.Event()
    side = BackendSide()
    threads = [threading.Thread(target=simulator, args=(sim, stop, flip)),
               threading.Thread(target=commander, args=(sub_address, hz, stop)),
               threading.Thread(target=backend, args=(pub_address, stop, old, side))]
    for t in threads:
        t.start()
    conn.recv()
    side.measuring = True
    conn.recv()
    side.measuring = False
    conn.send((side.envelopes, side.cpu_s))
    stop.set()
    for t in threads:
        t.join(timeout=5)
    sim.close()


async def run(a: argparse.Namespace) -> None:
    conn, child_conn = multiprocessing.Pipe()
    child = multiprocessing.Process(target=stand_ins, args=(child_conn, a.hz, a.flip, a.old))
    child.start()
    kw = {"pub_endpoint": "tcp://127.0.0.1:*", "sub_endpoint": "tcp://127.0.0.1:*",
          "vision_port": 0, "referee_port": 0, "sim_blue_port": conn.recv(),
          "tracker_out": False, "log_interval_s": 60.0}
    if not a.old:
        kw["feedback_interval_s"] = a.feedback_interval
    relay = Relay(RelayConfig(**kw))  # type: ignore[arg-type]
    task = asyncio.create_task(relay.run())
    await relay.ready.wait()
    conn.send((relay.sub_address, relay.pub_address))
    try:
        await asyncio.sleep(a.warmup)
        answers0 = relay.streams["sim_responses"].packets
        conn.send("start")
        c0, t0 = time.thread_time(), time.monotonic()
        await asyncio.sleep(a.seconds)
        relay_cpu, dt = time.thread_time() - c0, time.monotonic() - t0
        conn.send("stop")
        answers = relay.streams["sim_responses"].packets - answers0
        envelopes, backend_cpu = conn.recv()
    finally:
        relay.stop()
        await task
        child.join(timeout=10)
    label = "old relay" if a.old else f"feedback interval {a.feedback_interval:g} s"
    print(f"{label} ({larcmacs_relay.__file__}): {answers / dt:.0f} answers/s, "
          f"{envelopes / dt:.0f} envelopes/s; relay loop thread "
          f"{relay_cpu / dt * 100:.1f} % = {relay_cpu / max(1, answers) * 1e6:.1f} us per "
          f"answer (command set + cycle + answer); backend feedback "
          f"{backend_cpu / max(1, answers) * 1e6:.1f} us per answer")


async def micro(a: argparse.Namespace) -> None:
    """The relay's answer handling alone (see the module docstring)."""
    sim = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    sim.bind(("127.0.0.1", 0))
    kw = {"sim_blue_port": sim.getsockname()[1]}
    if not a.old:
        kw["feedback_interval_s"] = a.feedback_interval
    relay = Relay(RelayConfig(**kw))  # type: ignore[arg-type]
    ctx = zmq.Context()
    pub = ctx.socket(zmq.PUB)
    pub.setsockopt(zmq.LINGER, 0)
    pub.bind("tcp://127.0.0.1:*")
    sub = ctx.socket(zmq.SUB)
    sub.setsockopt(zmq.SUBSCRIBE, b"")
    sub.connect(pub.getsockopt(zmq.LAST_ENDPOINT))
    relay._pub = pub
    relay._sent[tl.TEAM_BLUE] = {i: (1, time.time_ns()) for i in range(11)}
    rx = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    rx.bind(("127.0.0.1", 0))
    rx.setblocking(False)
    answers = two_answers()
    other = 0.0  # the stand-ins' sends and the subscriber's reads, not the relay's
    n = 0
    c0 = time.thread_time()
    for _ in range(a.rounds):
        t0 = time.thread_time()
        for k in range(a.batch):
            sim.sendto(answers[((n + k) // a.flip) % 2], rx.getsockname())
        other += time.thread_time() - t0
        relay._drain_responses(rx)
        n += a.batch
        t0 = time.thread_time()
        while sub.poll(0):
            sub.recv_multipart()
        other += time.thread_time() - t0
        await asyncio.sleep(0.003)  # answers come ~3 ms apart at 300 command sets a second
    cpu = time.thread_time() - c0 - other
    ctx.destroy(linger=0)
    label = "old relay" if a.old else f"feedback interval {a.feedback_interval:g} s"
    print(f"{label}: relay answer handling {cpu / n * 1e6:.2f} us per answer "
          f"({relay.streams['sim_responses'].packets} answers)")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--seconds", type=float, default=10.0)
    ap.add_argument("--warmup", type=float, default=2.0)
    ap.add_argument("--hz", type=float, default=300.0)
    ap.add_argument("--flip", type=int, default=100, help="answers between contact changes")
    ap.add_argument("--feedback-interval", type=float, default=0.02)
    ap.add_argument("--old", action="store_true",
                    help="the relay on PYTHONPATH predates --feedback-interval")
    ap.add_argument("--micro", action="store_true", help="the relay's answer handling alone")
    ap.add_argument("--rounds", type=int, default=3000, help="--micro: rounds, 3 ms apart")
    ap.add_argument("--batch", type=int, default=1, help="--micro: answers per round")
    a = ap.parse_args()
    asyncio.run(micro(a) if a.micro else run(a))


if __name__ == "__main__":
    main()
