"""Digests of what the world model and the hot path put out, to compare two versions of the code
(a speed change must not change a bit of it). Not a test: prints one line per scenario; run it
before and after a change and diff the output.

Every world state (its repr: every float exactly) and its tracked-vision packet, of:
- ``a1``/``a2``: bench/world_bench.py's frames (8 cameras, 22 robots and the ball in every frame,
  false balls), each filter kind, a snapshot after every frame / every second frame;
- ``b``: bench/pipeline_bench.py's frames (each camera its part of the field), two a snapshot;
- ``c1``/``c3``/``cf``: fieldsim 11 v 11, division A, 8 cameras x 75 Hz, false detections,
  robots driving, a chip (``cf``: a flat kick) and robots leaving the field; the camera
  positions known (flight estimate); a snapshot after every frame / every third / every second;
- ``d``: the recorded session of tests/data (the regression test's log), after every frame;
  ``d=FILE``: the same over another recording (a station's, full scale: ``--record-dir``);
- ``e``: the pipeline (vision ingest, world, control, command publisher, tracked vision) on
  pipeline_bench's datagrams with a clock of its own: every world written, every command set,
  every message sent to the relay, every tracked packet recorded;
- ``g``/``gf``: fieldsim's cameras triggered together, a chip (``gf``: a flat kick): the
  robots, the ball and the kick estimate at the end of each burst of eight, merged one frame a
  pass and one burst a pass (issue 29), side by side.

    PYTHONPATH=. .venv/bin/python bench/world_digest.py [a1 a2 b c1 c3 cf d e g gf d=FILE]
"""

from __future__ import annotations

import asyncio
import hashlib
import math
import sys
import tempfile
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path
from types import ModuleType
from typing import Any

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

import bench.pipeline_bench as pb
import bench.world_bench as wb
from backend.filters import FilterSettings
from backend.world.decode import decode_detection, geometry_to_dict
from backend.world.model import WorldModel
from backend.world.state import CameraFrame, WorldState
from backend.world.tracked import tracked_packet
from sslpb.ssl_vision_wrapper_pb2 import SSL_WrapperPacket

ROOT = Path(__file__).resolve().parents[1]


class Digest:
    def __init__(self) -> None:
        self.h = hashlib.sha256()
        self.n = 0

    def add(self, b: bytes) -> None:
        self.h.update(b)
        self.n += 1

    def world(self, w: WorldState, n: int) -> None:
        self.add(repr(w).encode())
        self.add(tracked_packet(w, "u", n))

    def __str__(self) -> str:
        return f"{self.h.hexdigest()[:16]} ({self.n})"


def decoded(datagrams: list[tuple[int, bytes]]) -> list[CameraFrame]:
    out = []
    for ns, raw in datagrams:
        p = SSL_WrapperPacket()
        p.ParseFromString(raw)
        out.append(decode_detection(p.detection, ns))
    return out


def all_objects(every: int) -> str:
    fs = wb.frames(3000)
    out = {}
    for kind in ("adaptive", "kalman", "raw", "median", "paper"):
        d = Digest()
        m = WorldModel(filters=FilterSettings(ball=kind, robot=kind))
        for i, f in enumerate(fs):
            m.update(f)
            if i % every == 0:
                d.world(m.snapshot(), i)
        out[kind] = str(d)
    return " ".join(f"{k} {v}" for k, v in out.items())


def parts() -> str:
    fs = decoded(pb.datagrams(4000, 1.7e9))
    d, m = Digest(), WorldModel()
    for i in range(0, len(fs), 2):
        for f in fs[i:i + 2]:
            m.update(f)
        d.world(m.snapshot(), i)
    return str(d)


def _kick_scene(camera_phases: str) -> tuple[Any, Any, Any]:
    """fieldsim 11 v 11 on division A's field, 8 cameras at 75 Hz: (config, world, vision),
    blue 0 with the ball at its kicker."""
    from fieldsim.config import SimConfig
    from fieldsim.vision import Vision
    from fieldsim.world import Team, World

    cfg = SimConfig(blue=11, yellow=11, seed=3, cameras=8, division="A", camera_hz=75.0,
                    false_prob=0.05, camera_phases=camera_phases)
    w = World(cfg)
    v = Vision(cfg, w.geometry)
    w.teleport_robot(Team.BLUE, 0, -2.0, 0.5, 0.0)
    w.teleport_ball(-2.0 + cfg.robot_radius_m + cfg.ball_radius_m + 0.004, 0.5)
    return cfg, w, v


def _kick_script(w: Any, chip: bool) -> None:
    """The commands of one simulator step: blue 0 kicks (or chips) at 0.5 s, blue 1-5 drive
    curves turning back and forth."""
    from fieldsim.world import Team

    if 0.5 <= w.t < 0.52:
        w.set_command(Team.BLUE, 0, 0.0, 0.0, 0.0, kick_speed=4.0,
                      kick_angle=math.radians(50.0 if chip else 0.0))
    for rid in range(1, 6):
        w.set_command(Team.BLUE, rid, 1.0, 0.3, 1.0 if w.t % 2 < 1 else -1.0)


def fieldsim(every: int, chip: bool) -> str:
    from fieldsim.vision import WorldClockFrames
    from fieldsim.world import Team

    t0 = 1_700_000_000.0
    _, w, v = _kick_scene("spread")
    m = WorldModel()
    m.set_cameras({c.camera_id: (c.cx, c.cy, c.height) for c in v.cameras})
    d = Digest()
    frames = WorldClockFrames(v, w, t0)
    n = 0
    while w.t < 6.0:
        _kick_script(w, chip)
        if 4.0 <= w.t < 4.5:  # two robots lifted off the field
            for rid in (6, 7):
                w.robots.pop((Team.YELLOW, rid), None)
        w.step()
        for _, tc, packet in frames.due():
            m.update(decode_detection(packet.detection, int((t0 + tc + 0.002) * 1e9)))
            n += 1
            if n % every == 0:
                d.world(m.snapshot(), n)
    return f"{d} kicks {m.kicks.kicks} chips {m.flight.chips}"


def bursts(chip: bool = True) -> str:
    """fieldsim's cameras triggered together (``--camera-phases together``, as grSim): the
    world after each burst of eight frames, merged one frame a pass (a snapshot after every
    frame, as the station did when each frame had its pass) and one burst a pass (a snapshot
    after the eighth only). Digests of the robots, the ball and the kick estimate at the
    bursts' ends, per way: equal digests are bit-identical worlds. (At 2902664: the robots
    are; the ball is until a chip flies: the flight estimate, refitted at each snapshot, maps
    a burst's later detections to under the ball one burst later; the kick estimate, fed at
    each snapshot, is fitted over other batches.)"""
    t0 = 1_700_000_000.0
    cfg, w, v = _kick_scene("together")
    frames: list[list[CameraFrame]] = []  # per instant, its eight frames in camera order
    period, nxt = 1.0 / cfg.camera_hz, 0.0
    while w.t < 6.0:
        _kick_script(w, chip)
        w.step()
        while nxt <= w.t:
            tc, nxt = nxt, nxt + period
            frames.append([decode_detection(v.detect(k, w, t0 + tc, t0 + tc + 0.001,
                                                     tc - w.t).detection,
                                            int((t0 + tc + 0.002) * 1e9) + 30_000 * k)
                           for k in range(8)])
    out = []
    for per_frame in (True, False):
        m = WorldModel()
        m.set_cameras({c.camera_id: (c.cx, c.cy, c.height) for c in v.cameras})
        robots, ball, kick = Digest(), Digest(), Digest()
        for burst in frames:
            for f in burst:
                m.update(f)
                if per_frame:
                    world = m.snapshot()
            if not per_frame:
                world = m.snapshot()
            robots.add(repr(world.robots).encode())
            ball.add(repr(world.ball).encode())
            kick.add(repr(world.kicked_ball).encode())
        out.append(f"{'frame' if per_frame else 'burst'} a pass: robots {robots} ball {ball} "
                   f"kick {kick} kicks {m.kicks.kicks} chips {m.flight.chips}")
    return " | ".join(out)


def recorded(path: str = str(ROOT / "tests" / "data" / "fieldsim-2s.log.gz")) -> str:
    from ssllog.format import TYPE_VISION_2014
    from ssllog.logfile import LogFile

    log = LogFile.open(path, Path(tempfile.mkdtemp()))
    d, m = Digest(), WorldModel()
    for rec in log.records():
        if rec.type != TYPE_VISION_2014:
            continue
        pkt = SSL_WrapperPacket()
        pkt.ParseFromString(rec.payload)
        if pkt.HasField("geometry"):
            g = geometry_to_dict(pkt.geometry)
            m.set_field(g["field_length"] / 2, g["field_width"] / 2, g["boundary_width"])
        if pkt.HasField("detection"):
            m.update(decode_detection(pkt.detection, rec.time_ns))
            d.world(m.snapshot(), 1)
    return str(d)


class _Clock:
    """``time`` for the modules of the pipeline: a monotonic and a wall clock of its own."""

    def __init__(self) -> None:
        self.t = 1000.0

    def monotonic(self) -> float:
        return self.t

    def time_ns(self) -> int:
        return int(self.t * 1e9)


@contextmanager
def _clock(clock: _Clock, *modules: ModuleType) -> Iterator[None]:
    real = [m.time for m in modules]  # type: ignore[attr-defined]
    for m in modules:
        m.time = clock  # type: ignore[attr-defined]
    try:
        yield
    finally:
        for m, t in zip(modules, real, strict=True):
            m.time = t  # type: ignore[attr-defined]


def pipeline() -> str:
    import backend.bus as busmod
    import backend.processors.control as ctl
    import backend.processors.publisher as pubmod
    from backend import topics
    from backend.bus import DataBus
    from backend.processors import (
        CommandPublisher,
        ControlProcessor,
        TrackerPublisher,
        VisionIngest,
        WorldProcessor,
    )
    from sslpb import touchline_pb2 as tl

    clock = _Clock()
    frames = pb.datagrams(3000, 1.7e9)
    sent, rec, worlds, cmds = Digest(), Digest(), Digest(), Digest()
    with _clock(clock, ctl, busmod, pubmod):
        bus = DataBus({})
        wire = pb.Wire()
        wire.send_multipart = lambda fr, flags=0: sent.add(b"|".join(fr))  # type: ignore
        vision, world = VisionIngest(bus), WorldProcessor(bus)
        # (its clock given: the default is bound to the real time.monotonic at import, which
        # made the commands differ from run to run)
        control = ControlProcessor(bus, max_wait_s=10.0, vision_stale_s=1e9,
                                   clock=clock.monotonic)
        control.strategy_stale_s = 1e9
        publisher = CommandPublisher(bus)
        publisher.attach(wire)  # type: ignore[arg-type]
        tracker = TrackerPublisher(bus, "uuid")
        tracker.attach(wire)  # type: ignore[arg-type]
        tracker.record = lambda t, k, b: rec.add(repr((t, k)).encode() + b)
        wt, ct = bus.of(topics.WORLD), bus.of(topics.ROBOT_COMMANDS)
        packets, target_topic = bus.of(topics.VISION_PACKETS), bus.of(topics.TARGETS)

        async def run() -> None:
            wseq = cseq = 0
            for i in range(0, len(frames), 2):
                clock.t += 1 / 300.0 if i % 6 else 1 / 450.0
                if i % 30 < 2:
                    target_topic.write(pb.targets(i))
                for recv_ns, raw in frames[i:i + 2]:
                    packets.write(tl.Envelope(stream=tl.STREAM_VISION, receive_time_ns=recv_ns,
                                              sequence=i, source="bench", payload=raw))
                for p in (vision, world, control, publisher, tracker):
                    await p.tick()
                for r in wt.records_after(wseq):
                    worlds.add(repr(r.value).encode())
                    wseq = r.seq
                for c in ct.records_after(cseq):
                    cs = c.value
                    cmds.add(repr((cs.source_receive_time_ns, cs.commands, cs.stop_all)).encode())
                    cseq = c.seq
                cmds.add(repr(sorted(control.last_commands.items())).encode())

        asyncio.run(run())
    return f"worlds {worlds} commands {cmds} wire {sent} tracker-records {rec}"


SCENARIOS: dict[str, Callable[[], Any]] = {
    "a1": lambda: all_objects(1), "a2": lambda: all_objects(2), "b": parts,
    "c1": lambda: fieldsim(1, True), "c3": lambda: fieldsim(3, True),
    "cf": lambda: fieldsim(2, False), "d": recorded, "e": pipeline, "g": bursts,
    "gf": lambda: bursts(False),
}


def main() -> None:
    for name in sys.argv[1:] or list(SCENARIOS):
        t0 = time.monotonic()
        out = recorded(name[2:]) if name.startswith("d=") else SCENARIOS[name]()
        print(f"{name} {out}", file=sys.stdout, flush=True)
        print(f"  ({time.monotonic() - t0:.0f} s)", file=sys.stderr)


if __name__ == "__main__":
    main()
