"""The floor of the control loop: the bare minimum of Touchline's path, from the same
libraries, as two processes like the relay and the backend (a benchmark baseline, not a
product). ``bench/loop_bench.py`` runs it beside Touchline on the same camera input.

    relay:  UDP multicast receive -> ZeroMQ PUB (receive time + bytes)
            ZeroMQ SUB (command set) -> RobotControl (SSL simulation protocol) -> UDP send
    bridge: ZeroMQ SUB -> parse SSL_WrapperPacket -> a trivial command for each robot of our
            team (zero velocity) -> ZeroMQ PUB

Each process is two plain threads with blocking sockets (no event loop, no bus, no filters,
no strategy). The relay prints the latency of vision arrival -> command datagram sent (JSON)
when it gets SIGTERM.

    python bench/floor/floor.py relay --vision GROUP:PORT --pub EP --sub EP --out HOST:PORT
    python bench/floor/floor.py bridge --pub EP --sub EP
"""

from __future__ import annotations

import argparse
import json
import signal
import socket
import struct
import sys
import threading
import time
from pathlib import Path

import zmq

sys.path.insert(0, str(Path(__file__).resolve().parents[2]))

from sslnet.multicast import open_multicast_receiver
from sslpb import touchline_pb2 as tl
from sslpb.ssl_simulation_robot_control_pb2 import RobotControl
from sslpb.ssl_vision_wrapper_pb2 import SSL_WrapperPacket

HEAD = struct.Struct("<q")


def relay(a: argparse.Namespace) -> None:
    group, port = a.vision.rsplit(":", 1)
    rx = open_multicast_receiver(group, int(port))
    rx.setblocking(True)
    out_host, out_port = a.out.rsplit(":", 1)
    tx = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    ctx = zmq.Context()
    pub = ctx.socket(zmq.PUB)
    pub.bind(a.pub)
    sub = ctx.socket(zmq.SUB)
    sub.setsockopt(zmq.SUBSCRIBE, b"")
    sub.bind(a.sub)
    latencies: list[float] = []

    def vision() -> None:
        while True:
            data = rx.recv(65536)
            pub.send(HEAD.pack(time.time_ns()) + data)

    def commands() -> None:
        while True:
            cset = tl.RobotCommandSet.FromString(sub.recv())
            msg = RobotControl()
            for c in cset.commands:
                rc = msg.robot_commands.add(id=c.id)
                v = rc.move_command.local_velocity
                v.forward, v.left, v.angular = c.forward_mps, c.left_mps, c.angular_radps
            tx.sendto(msg.SerializeToString(), (out_host, int(out_port)))
            latencies.append((time.time_ns() - cset.source_receive_time_ns) / 1e6)

    for f in (vision, commands):
        threading.Thread(target=f, daemon=True).start()
    done = threading.Event()
    signal.signal(signal.SIGTERM, lambda *_: done.set())
    done.wait()
    lat = sorted(latencies[len(latencies) // 10:])  # the first tenth is the warm-up
    print(json.dumps({"n": len(lat), "p50_ms": lat[len(lat) // 2] if lat else -1,
                      "p99_ms": lat[int(0.99 * len(lat))] if lat else -1}), flush=True)


def bridge(a: argparse.Namespace) -> None:
    ctx = zmq.Context()
    sub = ctx.socket(zmq.SUB)
    sub.setsockopt(zmq.SUBSCRIBE, b"")
    sub.connect(a.sub)
    pub = ctx.socket(zmq.PUB)
    pub.connect(a.pub)
    seq = 0
    while True:
        body = sub.recv()
        (recv_ns,) = HEAD.unpack_from(body)
        pkt = SSL_WrapperPacket.FromString(body[HEAD.size:])
        if not pkt.HasField("detection"):
            continue
        seq += 1
        cset = tl.RobotCommandSet(created_time_ns=time.time_ns(),
                                  source_receive_time_ns=recv_ns, sequence=seq)
        for r in pkt.detection.robots_blue:
            cset.commands.add(team=tl.TEAM_BLUE, id=r.robot_id)
        pub.send(cset.SerializeToString())


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    sp = ap.add_subparsers(dest="role", required=True)
    r = sp.add_parser("relay")
    r.add_argument("--vision", required=True)
    r.add_argument("--pub", required=True)
    r.add_argument("--sub", required=True)
    r.add_argument("--out", required=True)
    b = sp.add_parser("bridge")
    b.add_argument("--pub", required=True)
    b.add_argument("--sub", required=True)
    a = ap.parse_args()
    relay(a) if a.role == "relay" else bridge(a)


if __name__ == "__main__":
    main()
