"""By-hand check of Touchline's tracked vision against the league's own tools (docs/tracker.md,
"Checked by hand"): what ssl-vision-client serves on its websocket compared with the multicast
frames Touchline sent, a chip sent to fieldsim and the tracked ball's height while it flies,
and which tracker source the game controller took.

The tools are not part of the project; start them yourself (docs/tracker.md has the commands),
then, e.g. for a station started with ``launcher --isolated`` (its ``TOUCHLINE_PORTS`` line):

    python -m bench.league_tools_check --vision-client 127.0.0.1:58083 --tracker-port P \\
        --sim-control-port S --chip --gc 127.0.0.1:58081
"""

from __future__ import annotations

import argparse
import asyncio
import json
import socket
import time
from dataclasses import dataclass, field

import websockets

from sslnet.multicast import open_multicast_receiver
from sslpb import ssl_simulation_control_pb2 as control_pb
from sslpb import ssl_vision_detection_tracked_pb2 as tracked_pb
from sslpb import ssl_vision_wrapper_tracked_pb2 as wrapper_pb

# The Go servers never read from their websockets, so a close handshake is never answered.
CLOSE_TIMEOUT_S = 0.2


@dataclass
class Seen:
    direct: dict[int, tracked_pb.TrackedFrame] = field(default_factory=dict)
    uuids: set[str] = field(default_factory=set)
    via_client: list[tuple[float, tracked_pb.TrackedFrame]] = field(default_factory=list)


async def receive_multicast(seen: Seen, group: str, port: int, until: float) -> None:
    sock = open_multicast_receiver(group, port)
    loop = asyncio.get_running_loop()
    try:
        while time.monotonic() < until:
            try:
                data = await asyncio.wait_for(loop.sock_recv(sock, 65536), 0.5)
            except TimeoutError:
                continue
            packet = wrapper_pb.TrackerWrapperPacket()
            packet.ParseFromString(data)
            seen.uuids.add(packet.uuid)
            seen.direct[packet.tracked_frame.frame_number] = packet.tracked_frame
    finally:
        sock.close()


async def send_chip(sim_port: int, x: float, y: float, vx: float, vz: float) -> None:
    """Ball at rest at (x, y) for 1 s (the flight fit starts where a resting ball moved), then
    the same place with (vx, 0, vz)."""
    sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)

    def teleport(**values: float) -> None:
        cmd = control_pb.SimulatorCommand()
        for name, value in values.items():
            setattr(cmd.control.teleport_ball, name, value)
        sock.sendto(cmd.SerializeToString(), ("127.0.0.1", sim_port))

    try:
        teleport(x=x, y=y)
        await asyncio.sleep(1.0)
        teleport(x=x, y=y, vx=vx, vz=vz)
        print(f"chip sent: vx {vx} m/s, vz {vz} m/s (apex {vz * vz / 19.62:.3f} m without drag)")
    finally:
        sock.close()


async def gc_tracker_source(address: str) -> None:
    async with websockets.connect(f"ws://{address}/api/control",
                                  close_timeout=CLOSE_TIMEOUT_S) as ws:
        trackers = active = None
        end = time.monotonic() + 3.0
        while time.monotonic() < end and (trackers is None or active is None):
            try:
                message = json.loads(await asyncio.wait_for(ws.recv(), 1.0))
            except TimeoutError:
                continue
            trackers = (message.get("gcState") or {}).get("trackers", trackers)
            active = (message.get("config") or {}).get("activeTrackerSource", active)
    print(f"game controller: trackers {trackers}, active tracker source {active}")


async def check(a: argparse.Namespace) -> None:
    async with websockets.connect(f"ws://{a.vision_client}/api/tracker/sources",
                                  close_timeout=CLOSE_TIMEOUT_S) as ws:
        sources = json.loads(await asyncio.wait_for(ws.recv(), 5.0))["tracker_sources"]
    print(f"ssl-vision-client tracker sources: {sources}")
    uuid = next(u for u, name in sources.items() if name == "Touchline")
    seen = Seen()
    until = time.monotonic() + a.seconds
    direct = asyncio.create_task(receive_multicast(seen, a.group, a.tracker_port, until + 0.5))
    chip = asyncio.create_task(send_chip(a.sim_control_port, -2.0, 1.5, 2.828, 2.828)) \
        if a.chip else None
    async with websockets.connect(f"ws://{a.vision_client}/api/tracker?source={uuid}",
                                  close_timeout=CLOSE_TIMEOUT_S) as ws:
        while time.monotonic() < until:
            data = await asyncio.wait_for(ws.recv(), 5.0)
            frame = tracked_pb.TrackedFrame()
            frame.ParseFromString(data if isinstance(data, bytes) else data.encode())
            seen.via_client.append((time.time(), frame))
    await direct
    if chip is not None:
        await chip
    report(seen, a.seconds)
    if a.gc:
        await gc_tracker_source(a.gc)


def report(seen: Seen, seconds: float) -> None:
    frames = [f for _, f in seen.via_client]
    heard = [f for f in frames if f.frame_number in seen.direct]
    same = sum(1 for f in heard if seen.direct[f.frame_number] == f)
    print(f"multicast: {len(seen.direct)} frames, uuids {sorted(seen.uuids)}")
    print(f"websocket: {len(frames)} frames ({len(frames) / seconds:.1f}/s); of the "
          f"{len(heard)} whose frame_number was also received directly, {same} identical")
    if frames:
        last = frames[-1]
        print(f"last frame: {len(last.robots)} robots, {len(last.balls)} balls, "
              f"capabilities {list(last.capabilities)}")
    flying = [(t, f) for t, f in seen.via_client if f.balls and f.balls[0].pos.z > 0]
    if not flying:
        return
    top = max(flying, key=lambda tf: tf[1].balls[0].pos.z)[1].balls[0].pos.z
    direct_top = max(f.balls[0].pos.z for f in seen.direct.values() if f.balls)
    print(f"ball height: max {top:.3f} m on the websocket, {direct_top:.3f} m in the multicast")
    print("t s, x m, z m, vz m/s, kicked_ball vel.z m/s, capabilities")
    t0 = flying[0][0]
    for t, f in flying:
        b = f.balls[0]
        kick = f"{f.kicked_ball.vel.z:.2f}" if f.HasField("kicked_ball") else "-"
        print(f"{t - t0:5.2f} {b.pos.x:6.2f} {b.pos.z:6.3f} {b.vel.z:6.2f} {kick:>6} "
              f"{list(f.capabilities)}")


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--vision-client", required=True, help="ssl-vision-client's HOST:PORT")
    p.add_argument("--group", default="224.5.23.2")
    p.add_argument("--tracker-port", type=int, required=True)
    p.add_argument("--seconds", type=float, default=4.0)
    p.add_argument("--chip", action="store_true", help="send a 4 m/s 45 degree chip to fieldsim")
    p.add_argument("--sim-control-port", type=int, default=10300)
    p.add_argument("--gc", help="the game controller's HOST:PORT (its /api/control)")
    asyncio.run(check(p.parse_args()))


if __name__ == "__main__":
    main()
