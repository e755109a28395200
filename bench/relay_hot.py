"""The relay's hot paths in-process, per unit of work (figures, not a test).

No subprocess, no other load: a ``Relay`` that is not running gets its sockets by hand
(loopback UDP in, a ZeroMQ PUB with a SUB drained outside the timing, loopback UDP out) and
its handlers are called directly inside an event loop, so the CPU time (thread time) per
vision datagram, per command set with its output cycle, and per simulator answer read in a
cycle is measured without the machine's other work in it; and a command set as the station
sends it (about 3 robots, new values) read from a real ZeroMQ SUB by the relay's reader, with
its cycle. Run it for a before/after of a
change to the relay's per-datagram code (``--before DIR``: the larcmacs_relay package from
DIR, e.g. ``git archive main larcmacs_relay | tar -x -C DIR``), A and B alternated.

    PYTHONPATH=. .venv/bin/python bench/relay_hot.py [--rounds 5] [--n 20000] [--before DIR]
"""

from __future__ import annotations

import argparse
import asyncio
import importlib
import json
import os
import socket
import statistics
import subprocess
import sys
import time
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parent.parent


def vision_payload() -> bytes:
    from sslpb import ssl_vision_wrapper_pb2

    w = ssl_vision_wrapper_pb2.SSL_WrapperPacket()
    d = w.detection
    d.frame_number, d.camera_id, d.t_capture, d.t_sent = 1, 0, 1.0, 1.0
    for team in (d.robots_blue, d.robots_yellow):
        for i in range(11):
            r = team.add()
            r.confidence, r.x, r.y, r.orientation = 0.9, 100.0 * i, 50.0, 0.5
            r.pixel_x, r.pixel_y, r.robot_id = 1.0, 1.0, i
    b = d.balls.add()
    b.confidence, b.x, b.y, b.pixel_x, b.pixel_y = 0.9, 1.0, 2.0, 3.0, 4.0
    return w.SerializeToString()


def command_sets(n: int) -> list[bytes]:
    """Command sets for blue 0..10 as bench/relay_load's stand-in sends them (every set a new
    speed for all, ten speeds in turn) and, every other one, as the station mostly does (one
    robot's command changes, the rest repeat)."""
    from sslpb import touchline_pb2 as tl

    out = []
    for seq in range(n):
        cset = tl.RobotCommandSet(source_receive_time_ns=time.time_ns(), sequence=seq)
        for i in range(11):
            v = 0.1 * (seq % 10) if seq % 2 or i == seq % 11 else 0.5
            cset.commands.add(team=tl.TEAM_BLUE, id=i, forward_mps=v)
        out.append(cset.SerializeToString())
    return out


def live_sets(n: int) -> list[bytes]:
    """Command sets as the station sends them at full scale (bench/profile_station.py --part
    relay: about 3 commands a set, most of them with new values): blue robots 3 at a time
    out of 11 in turn, each with speeds never sent before."""
    from sslpb import touchline_pb2 as tl

    out = []
    for seq in range(n):
        cset = tl.RobotCommandSet(source_receive_time_ns=time.time_ns(), sequence=seq)
        for j in range(3):
            i = (3 * seq + j) % 11
            cset.commands.add(team=tl.TEAM_BLUE, id=i, forward_mps=1e-4 * seq,
                              left_mps=-2e-5 * seq, angular_radps=0.5)
        out.append(cset.SerializeToString())
    return out


async def measure(n: int, batch: int) -> dict[str, float]:
    import zmq

    from larcmacs_relay import Relay, RelayConfig, codecs

    ctx = zmq.Context()
    pub = ctx.socket(zmq.PUB)
    pub.setsockopt(zmq.SNDHWM, 100000)
    port = pub.bind_to_random_port("tcp://127.0.0.1")
    sub = ctx.socket(zmq.SUB)
    sub.setsockopt(zmq.SUBSCRIBE, b"")
    sub.connect(f"tcp://127.0.0.1:{port}")
    time.sleep(0.2)  # the subscription reaches the PUB

    def drain_sub() -> None:
        while sub.poll(0):
            sub.recv(zmq.NOBLOCK)

    sim = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    sim.bind(("127.0.0.1", 0))
    sim.setblocking(False)
    cfg = RelayConfig(sim_host="127.0.0.1", sim_blue_port=sim.getsockname()[1],
                      sim_yellow_port=sim.getsockname()[1] + 1)
    r = Relay(cfg)
    r._pub = pub
    out = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    out.setblocking(False)
    r._udp_out = out
    r._sim_host = "127.0.0.1"
    rx = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    rx.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 1 << 22)
    rx.bind(("127.0.0.1", 0))
    rx.setblocking(False)
    tx = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    payload = vision_payload()
    dest = rx.getsockname()

    def drain_sim() -> None:
        while True:
            try:
                sim.recv(65536)
            except BlockingIOError:
                return

    # vision: ``batch`` datagrams per wake-up (the profile at full scale: about 2)
    spent = 0.0
    done = 0
    while done < n:
        for _ in range(batch):
            tx.sendto(payload, dest)
        t0 = time.thread_time()
        r._drain_input(rx, "vision", codecs.check_forwarded)
        spent += time.thread_time() - t0
        done += batch
        if done % 512 < batch:
            drain_sub()
    drain_sub()
    vision_us = spent / done * 1e6

    # a command set received and its output cycle (the profile: one cycle per set or so)
    sets = command_sets(n)
    spent = 0.0
    for k, body in enumerate(sets):
        t0 = time.thread_time()
        r._commands_changed = False
        r._handle_native([b"commands", body])
        if r._commands_changed:
            r._kick_output()
        spent += time.thread_time() - t0
        if k % 256 == 0:
            drain_sim()
            await asyncio.sleep(0)  # the loop drops the cancelled timers
    drain_sim()
    set_us = spent / n * 1e6

    # a command set as the station sends it (live_sets), read from the relay's SUB as the
    # loop's reader does (its frames, whether another waits), handled, and its cycle
    csub = ctx.socket(zmq.SUB)
    csub.setsockopt(zmq.SUBSCRIBE, b"commands")
    cport = csub.bind_to_random_port("tcp://127.0.0.1")
    cpub = ctx.socket(zmq.PUB)
    cpub.connect(f"tcp://127.0.0.1:{cport}")
    events, pollin = int(zmq.EVENTS), int(zmq.POLLIN)
    time.sleep(0.1)
    csub.get(events)  # the SUB takes the connection and sends its subscription
    time.sleep(0.2)  # the subscription reaches the PUB
    spent = 0.0
    for k, body in enumerate(live_sets(n)):
        cpub.send_multipart([b"commands", body])
        deadline = time.monotonic() + 5.0
        while not csub.get(events) & pollin:  # arrived (outside the timing)
            if time.monotonic() > deadline:
                raise RuntimeError("a command set did not arrive in 5 s")
        t0 = time.thread_time()
        r._drain_commands(csub)
        spent += time.thread_time() - t0
        if k % 256 == 0:
            drain_sim()
            await asyncio.sleep(0)
    drain_sim()
    sub_set_us = spent / n * 1e6

    # the timer's cycle: nothing new, the same commands again
    spent = 0.0
    for k in range(n):
        t0 = time.thread_time()
        r._run_cycle(time.monotonic())
        spent += time.thread_time() - t0
        if k % 256 == 0:
            drain_sim()
            await asyncio.sleep(0)
    drain_sim()
    cycle_us = spent / n * 1e6
    # the simulator's answers, read in a cycle (two a wake-up: both teams), then the read that
    # finds nothing; the kernel stamps them as in the relay
    from sslnet.kerneltime import enable_kernel_timestamps

    r._stamped = True
    enable_kernel_timestamps(out)
    answer = b""  # a valid RobotControlResponse without errors (the common answer)
    relay_addr = ("127.0.0.1", out.getsockname()[1])
    sim_yellow = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    sim_yellow.bind(("127.0.0.1", cfg.sim_yellow_port))
    spent = 0.0
    for k in range(n // 2):
        sim.sendto(answer, relay_addr)
        sim_yellow.sendto(answer, relay_addr)
        t0 = time.thread_time()
        r._drain_responses(out)
        spent += time.thread_time() - t0
        if k % 256 == 0:
            await asyncio.sleep(0)
            drain_sub()
    answer_us = spent / n * 1e6
    sim_yellow.close()
    for timer in r._gate_timers.values():
        timer.cancel()
    if r._timer is not None:
        r._timer.cancel()
    for s in (sim, out, rx, tx):
        s.close()
    ctx.destroy(linger=0)
    return {"vision_us": vision_us, "set_and_cycle_us": set_us, "repeat_cycle_us": cycle_us,
            "answer_us": answer_us, "sub_set_us": sub_set_us}


def child(n: int, batch: int) -> None:
    res = asyncio.run(measure(n, batch))
    print(json.dumps(res))


def run_variant(root: Path, n: int, batch: int) -> dict[str, float]:
    env = dict(os.environ, PYTHONPATH=f"{root}{os.pathsep}{ROOT}")
    outp = subprocess.run([sys.executable, str(Path(__file__).resolve()), "--child",
                           "--n", str(n), "--batch", str(batch)],
                          env=env, capture_output=True, text=True, check=True, cwd=root)
    result: dict[str, float] = json.loads(outp.stdout.strip().splitlines()[-1])
    return result


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--n", type=int, default=20000)
    ap.add_argument("--batch", type=int, default=2, help="vision datagrams per wake-up")
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--before", type=Path, default=None)
    ap.add_argument("--child", action="store_true", help=argparse.SUPPRESS)
    a = ap.parse_args()
    if a.child:
        importlib.invalidate_caches()
        child(a.n, a.batch)
        return
    variants = [("after", ROOT)]
    if a.before is not None:
        variants.insert(0, ("before", a.before.resolve()))
    results: dict[str, list[dict[str, float]]] = {name: [] for name, _ in variants}
    for _ in range(a.rounds):
        for name, root in variants:
            results[name].append(run_variant(root, a.n, a.batch))
    print(f"relay in-process, CPU us per unit (thread time), {a.n} each, vision {a.batch} "
          f"datagrams per wake-up, medians of {a.rounds}")
    print("| variant | vision datagram | command set + cycle | repeat cycle | sim answer | "
          "station-like set from the SUB + cycle |")
    print("|---|---|---|---|---|---|")
    for name, rs in results.items():
        def med(k: str, rs: list[dict[str, Any]] = rs) -> float:
            return statistics.median(x[k] for x in rs)
        print(f"| {name} | {med('vision_us'):.2f} | {med('set_and_cycle_us'):.2f} | "
              f"{med('repeat_cycle_us'):.2f} | {med('answer_us'):.2f} | "
              f"{med('sub_set_us'):.2f} |")


if __name__ == "__main__":
    main()
