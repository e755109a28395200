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
    python bench/floor/floor.py bridge --pub EP --sub EP [--algorithms]

``--algorithms`` adds the paper's per-frame work to the bridge, written as plainly and as
tightly as Python allows (no event loop, no bus, no objects beyond one per tracked object):
for every robot and ball detection the median filter (window 5) and the weighted average
(0.05 new / 0.95 previous) on x, y and the orientation, a velocity from the filtered
positions; for each robot of our team seen, the trapezoid's V = sqrt(2aS) towards a target,
turned into the robot's frame. Not Touchline's algorithms (no camera merging, no adaptive
filters, no kick or flight estimate, no tracked vision out): the least of them, so that its
row says what any CPython station pays for the paper's algorithms at this load.
"""

from __future__ import annotations

import argparse
import json
import math
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


def _median(v: list[float]) -> float:
    s = sorted(v)
    h = len(s) // 2
    return s[h] if len(s) % 2 else 0.5 * (s[h - 1] + s[h])


class _Track:
    """One object's median (window 5) and weighted average, per coordinate."""

    __slots__ = ("fo", "fx", "fy", "os", "t", "vx", "vy", "xs", "ys")

    def __init__(self) -> None:
        self.xs: list[float] = []
        self.ys: list[float] = []
        self.os: list[float] = []
        self.fx = self.fy = self.fo = self.t = self.vx = self.vy = 0.0

    def update(self, t: float, x: float, y: float, o: float) -> None:
        xs, ys, os_ = self.xs, self.ys, self.os
        xs.append(x)
        ys.append(y)
        if os_:  # the orientation unwrapped next to the last one
            o = os_[-1] + (o - os_[-1] + math.pi) % (2 * math.pi) - math.pi
        os_.append(o)
        if len(xs) > 5:
            del xs[0], ys[0], os_[0]
        mx, my, mo = _median(xs), _median(ys), _median(os_)
        if self.t == 0.0:
            self.fx, self.fy, self.fo, self.t = mx, my, mo, t
            return
        fx = 0.05 * mx + 0.95 * self.fx
        fy = 0.05 * my + 0.95 * self.fy
        dt = t - self.t
        if dt > 0:
            self.vx, self.vy = (fx - self.fx) / dt, (fy - self.fy) / dt
        self.fx, self.fy, self.fo, self.t = fx, fy, 0.05 * mo + 0.95 * self.fo, t


def _algorithms(pkt: SSL_WrapperPacket, tracks: dict[tuple[int, int], _Track],
                cset: tl.RobotCommandSet) -> None:
    det = pkt.detection
    t = det.t_capture
    for team, robots in ((0, det.robots_blue), (1, det.robots_yellow)):
        for r in robots:
            key = (team, r.robot_id)
            tr = tracks.get(key)
            if tr is None:
                tr = tracks[key] = _Track()
            tr.update(t, r.x, r.y, r.orientation)
    for b in det.balls:
        tr = tracks.get((2, 0))
        if tr is None:
            tr = tracks[(2, 0)] = _Track()
        tr.update(t, b.x, b.y, 0.0)
    for r in det.robots_blue:
        tr = tracks[(0, r.robot_id)]
        dx, dy = 1000.0 * (r.robot_id % 4) - tr.fx, 800.0 * (r.robot_id // 4) - tr.fy
        s = math.hypot(dx, dy)
        v = min(2.0, math.sqrt(2 * 3.0 * s / 1000.0)) / s if s > 1.0 else 0.0
        c, si = math.cos(tr.fo), math.sin(tr.fo)
        cset.commands.add(team=tl.TEAM_BLUE, id=r.robot_id, forward_mps=v * (c * dx + si * dy),
                          left_mps=v * (c * dy - si * dx), angular_radps=-2.0 * tr.fo)


def bridge(a: argparse.Namespace) -> None:
    ctx = zmq.Context()
    sub = ctx.socket(zmq.SUB)
    sub.setsockopt(zmq.SUBSCRIBE, b"")
    sub.connect(a.sub)
    pub = ctx.socket(zmq.PUB)
    pub.connect(a.pub)
    seq = 0
    tracks: dict[tuple[int, int], _Track] = {}
    while True:
        body = sub.recv()
        (recv_ns,) = HEAD.unpack_from(body)
        pkt = SSL_WrapperPacket.FromString(body[HEAD.size:])
        if not pkt.HasField("detection"):
            continue
        seq += 1
        cset = tl.RobotCommandSet(created_time_ns=time.time_ns(),
                                  source_receive_time_ns=recv_ns, sequence=seq)
        if a.algorithms:
            _algorithms(pkt, tracks, cset)
        else:
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
    b.add_argument("--algorithms", action="store_true",
                   help="the paper's per-frame algorithms in plain Python (see above)")
    a = ap.parse_args()
    relay(a) if a.role == "relay" else bridge(a)


if __name__ == "__main__":
    main()
