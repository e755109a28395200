"""A mutation fuzzer for the codecs and the world model (no sockets).

Valid frames come from fieldsim (its world and cameras, as `make run` sends them). Each example
is a list of mutations (byte flips, truncation, garbage, splices, and field-level changes:
capture times, camera and robot ids, coordinates out of range, NaN, huge counts; referee
datagrams with flipped bytes and team names that are not UTF-8). Every input goes through the
relay's codecs (larcmacs_relay.codecs) and the backend's real processors on a real bus (vision
ingest, world model, referee ingest) and the station's JSON, and after every input:

* no exception escapes;
* the world keeps updating from the next valid frame;
* every object is inside the field plus the margin, with finite numbers, or absent;
* times are monotone and close to the receive clock;
* every string is valid UTF-8 and the JSON of the world, the geometry and the referee encodes
  (strict: no NaN).

`make test` runs a short derandomized pass; `make fuzz ROUNDS=N` runs fresh examples."""

from __future__ import annotations

import asyncio
import json
import math
import os
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from backend import topics
from backend.config import Settings
from backend.jsonsafe import dumps
from backend.processors import RefereeIngest, VisionIngest, WorldProcessor
from backend.referee.internal import InternalReferee
from backend.station import Station
from fieldsim.config import SimConfig
from fieldsim.vision import Vision
from fieldsim.world import Team, World
from larcmacs_relay.codecs import check_forwarded, parse_referee
from sslpb import touchline_pb2 as tl
from sslpb.ssl_vision_wrapper_pb2 import SSL_WrapperPacket

T0 = 1_790_000_000.0
#: `make test` (derandomized): a short pass; `make fuzz`: more fresh examples each round
EXAMPLES = 400 if os.environ.get("HYPOTHESIS_PROFILE") == "explore" else 60
LATENCY_S = 0.003
FRAME_DT = 1 / 240  # 4 cameras at 60 Hz


def _valid_frames(n: int = 240) -> list[bytes]:
    cfg = SimConfig(seed=5)
    world = World(cfg)
    vision = Vision(cfg, world.geometry)
    world.teleport_ball(0.5, 0.2, vx=2.0, vy=-1.0)
    for rid in range(3):
        world.set_command(Team.BLUE, rid, 1.0, 0.3, 1.0)
    out = []
    for k in range(n):
        world.step(FRAME_DT)
        out.append(vision.detect(k % len(vision.cameras), world, T0 + k * FRAME_DT)
                   .SerializeToString())
    return out


VALID = _valid_frames()
GEOMETRY = Vision(SimConfig(seed=5), World(SimConfig(seed=5)).geometry).geometry_packet() \
    .SerializeToString()
_TEAM_MARK = "TEAMNAMEMARK"


def _referee_bytes(bad_name: bool) -> bytes:
    ref = InternalReferee()
    ref.blue.name = _TEAM_MARK
    raw = ref.encode()
    if bad_name:  # the same length, not UTF-8: what a byte flip in a name does
        raw = raw.replace(_TEAM_MARK.encode(), b"\xff\xfe\xc3(\xed\xa0\x80\x80TEAM")
    return raw


# ---- mutations -----------------------------------------------------------------------------

_TIMES = [math.nan, math.inf, -math.inf, 3600.0, -3600.0, 1e300, -T0, 0.05, -0.7, 2.0]
_COORDS = [math.nan, math.inf, -math.inf, 1e30, -1e30, 7000.0, -6500.0, 1e9]
_IDS = [16, 255, 2**31 - 1, 2**32 - 1]

mutation = st.one_of(
    st.tuples(st.just("flip"), st.lists(st.tuples(st.integers(0, 10**6), st.integers(1, 255)),
                                          min_size=1, max_size=8)),
    st.tuples(st.just("truncate"), st.integers(0, 10**6)),
    st.tuples(st.just("garbage"), st.binary(max_size=300)),
    st.tuples(st.just("splice"), st.integers(0, len(VALID) - 1)),
    st.tuples(st.just("time"), st.sampled_from(_TIMES)),
    st.tuples(st.just("camera"), st.sampled_from([*_IDS, 64, 63])),
    st.tuples(st.just("robot-id"), st.sampled_from(_IDS)),
    st.tuples(st.just("coord"), st.tuples(st.sampled_from(_COORDS), st.booleans())),
    st.tuples(st.just("orientation"), st.sampled_from(_COORDS)),
    st.tuples(st.just("count"), st.tuples(st.integers(100, 3000), st.booleans())),
    st.tuples(st.just("geometry"), st.tuples(st.sampled_from([*_COORDS, 0.0, -9000.0]),
                                             st.integers(0, 6))),
    st.tuples(st.just("referee"), st.tuples(st.booleans(), st.lists(
        st.tuples(st.integers(0, 10**4), st.integers(1, 255)), max_size=4))),
)


def _flip(data: bytes, flips: list[tuple[int, int]]) -> bytes:
    b = bytearray(data)
    for pos, x in flips:
        if b:
            b[pos % len(b)] ^= x
    return bytes(b)


def mutate(kind: str, arg: Any, base: bytes) -> tuple[str, bytes]:
    """The mutated datagram and its stream ("vision" or "referee")."""
    if kind == "flip":
        return "vision", _flip(base, arg)
    if kind == "truncate":
        return "vision", base[:arg % max(1, len(base))]
    if kind == "garbage":
        return "vision", arg
    if kind == "splice":
        return "vision", base + VALID[arg]
    if kind == "referee":
        bad_name, flips = arg
        return "referee", _flip(_referee_bytes(bad_name), flips)
    pkt = SSL_WrapperPacket()
    if kind == "geometry":
        value, which = arg
        pkt.ParseFromString(GEOMETRY)
        f = pkt.geometry.field
        if which == 0:
            f.field_length = int(value) if math.isfinite(value) and abs(value) < 2**31 else 0
        elif which == 1:
            f.boundary_width = int(value) if math.isfinite(value) and abs(value) < 2**31 else -1
        elif which == 2 and f.field_lines:
            f.field_lines[0].p1.x = value
        elif which == 3 and f.field_arcs:
            f.field_arcs[0].radius = value
        elif which == 4:
            f.ball_radius = value
        elif which == 5 and f.field_lines:
            f.field_lines[0].thickness = value
        else:
            f.max_robot_radius = value
        return "vision", pkt.SerializeToString()
    pkt.ParseFromString(base)
    d = pkt.detection
    if kind == "time":
        d.t_capture = d.t_capture + arg if arg not in (1e300, -T0) else arg
    elif kind == "camera":
        d.camera_id = arg
    elif kind == "robot-id" and d.robots_blue:
        d.robots_blue[0].robot_id = arg
    elif kind == "coord":
        value, on_ball = arg
        if on_ball and d.balls:
            d.balls[0].x = value
        elif d.robots_yellow:
            d.robots_yellow[0].y = value
    elif kind == "orientation" and d.robots_blue:
        d.robots_blue[0].orientation = arg
    elif kind == "count":
        n, balls = arg
        if balls and d.balls:
            for _ in range(n):
                d.balls.add().CopyFrom(d.balls[0])
        elif d.robots_blue:
            for _ in range(n):
                d.robots_blue.add().CopyFrom(d.robots_blue[0])
    return "vision", pkt.SerializeToString()


# ---- the pipeline ----------------------------------------------------------------------------

@dataclass
class Pipeline:
    station: Station
    vision: VisionIngest
    world: WorldProcessor
    referee: RefereeIngest
    loop: asyncio.AbstractEventLoop
    recv_s: float = T0 + LATENCY_S
    last_t: float = -math.inf

    def feed(self, stream: str, data: bytes, recv_s: float) -> None:
        # the relay's checks never raise; it forwards every non-empty datagram undecoded (the
        # backend is the one decoder and must survive anything arriving on ZeroMQ)
        check_forwarded(data)
        if stream == "referee":
            parse_referee(data)  # the compat and referee-out paths re-encode a Referee
        env = tl.Envelope(stream=tl.STREAM_VISION if stream == "vision" else tl.STREAM_REFEREE,
                          receive_time_ns=int(recv_s * 1e9), payload=data)
        bus = self.station.bus
        if stream == "vision":
            bus.of(topics.VISION_PACKETS).write(env)
            self.loop.run_until_complete(self.vision.tick())
            self.loop.run_until_complete(self.world.tick())
        else:
            bus.of(topics.REFEREE_PACKETS).write(env)
            self.loop.run_until_complete(self.referee.tick())

    def check(self, recv_s: float) -> None:
        st_ = self.station
        # the world message as every websocket gets it
        out = json.loads(dumps({"type": "world", "world": st_.browser.world()}, "world"))
        _strict_json(out)
        model = self.world.model
        c = model.config
        lim_x = c.field_half_length_mm + c.field_boundary_mm + c.field_margin_mm
        lim_y = c.field_half_width_mm + c.field_boundary_mm + c.field_margin_mm
        w = st_.world_topic.latest_value()
        if w is not None:
            objs = [(r.x, r.y, f"{r.team} {r.id}") for r in w.robots]
            if w.ball is not None:
                objs.append((w.ball.x, w.ball.y, "ball"))
            for x, y, what in objs:
                assert math.isfinite(x) and math.isfinite(y), (what, x, y)
                assert abs(x) <= lim_x and abs(y) <= lim_y, (what, x, y, lim_x, lim_y)
            assert w.t_capture >= self.last_t, "world time went backwards"
            self.last_t = w.t_capture
            cc = c.clock
            assert recv_s - 1.0 <= w.t_capture <= recv_s + cc.max_ahead_s + 1e-6, \
                (w.t_capture - recv_s)
        geo = st_.browser.geometry()
        if geo is not None:
            _strict_json(geo)
        ref = st_.referee_topic.latest_value()
        if ref is not None:
            _strict_json(ref.to_dict(0.0))


def _strict_json(obj: Any) -> None:
    # raises on NaN/inf and on bytes; then on lone surrogates (what a JSONResponse does)
    json.dumps(obj, allow_nan=False, ensure_ascii=False).encode("utf-8")


@pytest.fixture
def pipeline(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Pipeline]:
    station = Station(Settings(state_dir=tmp_path_factory.mktemp("fuzz")))
    loop = asyncio.new_event_loop()
    try:
        yield Pipeline(station, VisionIngest(station.bus), WorldProcessor(station.bus),
                       RefereeIngest(station.bus), loop)
    finally:
        loop.close()


def _fresh(p: Pipeline, tmp: Path) -> Pipeline:
    station = Station(Settings(state_dir=tmp))
    return Pipeline(station, VisionIngest(station.bus), WorldProcessor(station.bus),
                    RefereeIngest(station.bus), p.loop)


@settings(max_examples=EXAMPLES, suppress_health_check=[HealthCheck.function_scoped_fixture,
                                                  HealthCheck.too_slow])
@given(st.lists(mutation, min_size=1, max_size=10), st.integers(0, len(VALID) - 40))
def test_mutated_inputs_break_no_invariant(pipeline: Pipeline, tmp_path: Path,
                                           muts: list[tuple[str, Any]], start: int) -> None:
    p = _fresh(pipeline, tmp_path)
    k = start
    recv = T0 + k * FRAME_DT + LATENCY_S
    p.feed("vision", GEOMETRY, recv)
    for kind, arg in muts:
        # a valid frame, the mutated next one, and the one after: that one must be merged
        for data, stream in ((VALID[k], "vision"), mutate(kind, arg, VALID[k + 1])[::-1]):
            p.feed(stream, data, recv)
            p.check(recv)
        k += 2
        recv = T0 + k * FRAME_DT + LATENCY_S
        seq = p.station.world_topic.seq
        p.feed("vision", VALID[k], recv)
        p.check(recv)
        assert p.station.world_topic.seq == seq + 1, \
            f"the valid frame after {kind} {arg!r} did not update the world " \
            f"({p.world.model.last_rejection})"
        w = p.station.world_topic.latest_value()
        assert w is not None and w.receive_time_ns == int(recv * 1e9)
        k += 1


def test_the_fuzzer_can_fail() -> None:
    """The invariants are real: a world object off the field and a NaN in the JSON are
    caught by the same check the fuzzer runs."""
    with pytest.raises(ValueError):
        _strict_json({"x": math.nan})
    with pytest.raises(TypeError):
        _strict_json({"name": b"\xff"})
    with pytest.raises(UnicodeEncodeError):
        _strict_json({"name": "\udcff"})
