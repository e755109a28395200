"""Relay latency benchmark (not a test): runs ``python -m larcmacs_relay`` as a subprocess.

1. Vision path: 4 cameras x 60 Hz multicast for 5 s; latency from the relay's datagram
   arrival (Envelope.receive_time_ns) to receipt by a ZeroMQ subscriber, and from the
   sender's sendto to receipt.
2. Command path: RobotCommandSet on ZeroMQ at 60 Hz for 5 s; latency from the PUB send to
   the first RobotControl datagram carrying it on a UDP socket standing in for the simulator
   (kernel arrival timestamp). It includes the wait for the next output cycle (<= 1/rate).

Usage: .venv/bin/python bench/relay_bench.py [--seconds 5] [--cameras 4] [--fps 60]
"""

from __future__ import annotations

import argparse
import asyncio
import contextlib
import os
import random
import signal
import socket
import statistics
import subprocess
import sys
import time

import zmq
import zmq.asyncio

from sslnet.kerneltime import enable_kernel_timestamps, kernel_time
from sslnet.multicast import open_multicast_sender
from sslpb import ssl_simulation_robot_control_pb2, ssl_vision_wrapper_pb2, touchline_pb2
from tests.ports import free_port


def wrapper(frame: int, camera: int) -> bytes:
    w = ssl_vision_wrapper_pb2.SSL_WrapperPacket()
    d = w.detection
    d.frame_number, d.camera_id = frame, camera
    d.t_capture = d.t_sent = time.time()
    for i in range(11):
        r = d.robots_blue.add()
        r.confidence, r.x, r.y, r.pixel_x, r.pixel_y = 0.9, 100.0 * i, 50.0, 1.0, 1.0
        r.robot_id = i
    b = d.balls.add()
    b.confidence, b.x, b.y, b.pixel_x, b.pixel_y = 0.9, 1.0, 2.0, 3.0, 4.0
    return w.SerializeToString()


def summary(name: str, values_ms: list[float]) -> str:
    if not values_ms:
        return f"{name}: no samples"
    v = sorted(values_ms)
    p99 = v[min(len(v) - 1, int(0.99 * len(v)))]
    return (
        f"{name}: n={len(v)} median={statistics.median(v):.3f} ms p99={p99:.3f} ms "
        f"max={v[-1]:.3f} ms"
    )


async def bench(seconds: float, cameras: int, fps: float) -> None:
    vport = random.randint(20000, 40000)
    pub_ep = f"tcp://127.0.0.1:{free_port(socket.SOCK_STREAM)}"
    sub_ep = f"tcp://127.0.0.1:{free_port(socket.SOCK_STREAM)}"
    sim = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    sim.bind(("127.0.0.1", 0))
    enable_kernel_timestamps(sim)
    sim_port = sim.getsockname()[1]
    cmd = [
        sys.executable, "-m", "larcmacs_relay",
        "--vision", f"224.5.23.2:{vport}",
        "--referee", f"224.5.23.1:{random.randint(20000, 40000)}",
        "--pub", pub_ep, "--sub", sub_ep,
        "--sim-blue-port", str(sim_port), "--sim-yellow-port", str(free_port(socket.SOCK_DGRAM)),
        "--sim-control-port", str(free_port(socket.SOCK_DGRAM)),
        "--log-level", "WARNING",
    ]  # fmt: skip
    env = dict(os.environ, PYTHONPATH=os.getcwd())
    proc = subprocess.Popen(cmd, env=env)
    ctx = zmq.asyncio.Context()
    try:
        sub = ctx.socket(zmq.SUB)
        sub.setsockopt(zmq.LINGER, 0)
        sub.setsockopt(zmq.SUBSCRIBE, b"vision")
        sub.connect(pub_ep)
        tx = open_multicast_sender("127.0.0.1")
        # wait for the relay to forward a probe
        deadline = time.monotonic() + 10
        while True:
            assert time.monotonic() < deadline, "relay did not come up"
            tx.sendto(wrapper(0, 0), ("224.5.23.2", vport))
            if await sub.poll(100):
                await sub.recv_multipart()
                break
        while await sub.poll(50):
            await sub.recv_multipart()

        # ---------------- vision path
        sent: dict[bytes, int] = {}
        relay_ms: list[float] = []
        total_ms: list[float] = []
        n_frames = int(seconds * fps)

        async def sender() -> None:
            t0 = time.monotonic()
            for f in range(1, n_frames + 1):
                for cam in range(cameras):  # cameras are not synchronised: spread them
                    target = t0 + (f + cam / cameras) / fps
                    delay = target - time.monotonic()
                    if delay > 0:
                        await asyncio.sleep(delay)
                    data = wrapper(f, cam)
                    sent[data] = time.time_ns()
                    tx.sendto(data, ("224.5.23.2", vport))

        async def receiver() -> None:
            while len(relay_ms) < n_frames * cameras:
                if not await sub.poll(1000):
                    return
                _, body = await sub.recv_multipart()
                now = time.time_ns()
                env_ = touchline_pb2.Envelope.FromString(body)
                relay_ms.append((now - env_.receive_time_ns) / 1e6)
                if env_.payload in sent:
                    total_ms.append((now - sent[env_.payload]) / 1e6)

        await asyncio.gather(sender(), receiver())
        print(f"vision: {cameras} cameras x {fps:.0f} Hz for {seconds:.0f} s")
        print("  " + summary("relay arrival -> ZMQ subscriber", relay_ms))
        print("  " + summary("sendto -> ZMQ subscriber       ", total_ms))
        print(f"  lost: {n_frames * cameras - len(relay_ms)}")

        # ---------------- command path
        pub = ctx.socket(zmq.PUB)
        pub.setsockopt(zmq.LINGER, 0)
        pub.connect(sub_ep)
        await asyncio.sleep(0.3)  # slow joiner (bench only)
        sim.setblocking(False)
        pending: dict[float, float] = {}
        cmd_ms: list[float] = []
        stop = asyncio.Event()

        async def commander() -> None:
            for i in range(1, int(seconds * 60) + 1):
                value = float(i % 1000) / 100.0 + 0.005
                c = touchline_pb2.RobotCommand(
                    team=touchline_pb2.TEAM_BLUE, id=1, forward_mps=value
                )
                s = touchline_pb2.RobotCommandSet(
                    commands=[c], source_receive_time_ns=time.time_ns()
                )
                pending[round(value, 3)] = time.time()
                await pub.send_multipart([b"commands", s.SerializeToString()])
                await asyncio.sleep(1 / 60)
            await asyncio.sleep(0.1)
            stop.set()

        async def sim_reader() -> None:
            loop = asyncio.get_running_loop()
            while not stop.is_set():
                try:
                    data, anc, _, _ = sim.recvmsg(65536, 64)
                except BlockingIOError:
                    fut: asyncio.Future[None] = loop.create_future()
                    loop.add_reader(sim.fileno(), lambda f=fut: f.done() or f.set_result(None))
                    with contextlib.suppress(TimeoutError):
                        await asyncio.wait_for(fut, 0.1)
                    loop.remove_reader(sim.fileno())
                    continue
                stamp = kernel_time(anc)
                t = time.time() if stamp is None else stamp
                rc = ssl_simulation_robot_control_pb2.RobotControl.FromString(data)
                for r in rc.robot_commands:
                    key = round(r.move_command.local_velocity.forward, 3)
                    if key in pending:
                        cmd_ms.append((t - pending.pop(key)) * 1e3)

        await asyncio.gather(commander(), sim_reader())
        print("commands: 60 Hz RobotCommandSet, relay output 120 Hz")
        print("  " + summary("ZMQ send -> first UDP datagram", cmd_ms))
    finally:
        proc.send_signal(signal.SIGINT)
        try:
            proc.wait(5)
        except subprocess.TimeoutExpired:
            proc.kill()
        ctx.destroy(linger=0)
        sim.close()


def main() -> None:
    p = argparse.ArgumentParser()
    p.add_argument("--seconds", type=float, default=5.0)
    p.add_argument("--cameras", type=int, default=4)
    p.add_argument("--fps", type=float, default=60.0)
    a = p.parse_args()
    asyncio.run(bench(a.seconds, a.cameras, a.fps))


if __name__ == "__main__":
    main()
