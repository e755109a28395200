"""The station's processors: relay ingest, vision ingest, referee ingest, world model,
strategy (demo + operator targets), control, command publishing."""

from __future__ import annotations

import asyncio
import logging
import math
import time
from collections import deque
from collections.abc import Callable
from typing import Any

import numpy as np
import zmq
import zmq.asyncio
from google.protobuf.message import DecodeError, Message

from domain.rules import kick_allowed
from sslnet import streams
from sslnet.rate import RateCounter
from sslnet.ratelog import RateLimitedLog
from sslnet.streams import StreamCounter
from sslpb import touchline_pb2 as tl
from sslpb.ssl_gc_referee_message_pb2 import Referee
from sslpb.ssl_vision_wrapper_pb2 import SSL_WrapperPacket

from . import topics
from .bus import DataBus, Reader
from .control.goto import LocalVelocity, Target
from .control.motion import PHASE_NAMES, MotionBank, RobotMotionState
from .control.params import ALGORITHMS, ControlSettings
from .control.referee_limits import referee_limits
from .engine import EngineError, PoolEngine
from .messages import Command, CommandSet, TargetEntry
from .params.model import StrategyParams
from .processor import Every, OnTopic, Processor
from .referee.internal import InternalReferee, RefereeCommandError
from .referee.watch import RefereeWatch
from .strategy.core import Prepared, StrategyCore
from .world.decode import decode_detection, geometry_to_dict
from .world.model import WorldModel
from .world.referee import RefereeState, decode_referee
from .world.state import Team

log = logging.getLogger("touchline.processors")
_badlog = RateLimitedLog(log, interval_s=10.0)


class LatencyStage:
    """Milliseconds from a vision datagram's arrival at the relay to one point of the
    pipeline, over the last few hundred samples."""

    def __init__(self, maxlen: int = 500) -> None:
        self.samples: deque[float] = deque(maxlen=maxlen)

    def add_since(self, receive_time_ns: int) -> None:
        if receive_time_ns > 0:
            self.samples.append((time.time_ns() - receive_time_ns) / 1e6)

    def summary(self) -> dict[str, float]:
        vals = sorted(self.samples)
        if not vals:
            return {"mean_ms": 0.0, "p50_ms": 0.0, "p99_ms": 0.0, "n": 0}
        return {
            "mean_ms": sum(vals) / len(vals),
            "p50_ms": vals[len(vals) // 2],
            "p99_ms": vals[min(len(vals) - 1, int(0.99 * len(vals)))],
            "n": len(vals),
        }


class RelayIngest(Processor):
    """Source: receives everything the relay publishes and puts it on the bus unchanged."""

    name = "relay-ingest"

    def __init__(self, bus: DataBus, sock: zmq.asyncio.Socket) -> None:
        super().__init__(None)
        self.sock = sock
        self.vision_packets = bus.of(topics.VISION_PACKETS)
        self.referee_packets = bus.of(topics.REFEREE_PACKETS)
        self.relay_stats = bus.of(topics.RELAY_STATS)
        self.counters = {"zmq": StreamCounter("zmq")}

    async def wait_input(self) -> None:
        await self.sock.poll()

    async def tick(self) -> None:
        for _ in range(1000):  # drain what is there, bounded so other tasks get a turn
            try:
                frames = await self.sock.recv_multipart(flags=zmq.NOBLOCK)
            except zmq.Again:
                return
            self._handle(frames)

    def _handle(self, frames: list[bytes]) -> None:
        c = self.counters["zmq"]
        c.rate.add()
        if len(frames) != 2:
            c.error("bad frames", f"expected 2 frames, got {len(frames)}")
            _badlog.warning("zmq-frames", "relay message with %d frames ignored", len(frames))
            return
        topic, body = frames
        if topic == b"stats":
            stats = tl.RelayStats()
            try:
                stats.ParseFromString(body)
            except DecodeError as exc:
                c.error(streams.wire_problem(body), f"stats: {exc}")
                return
            self.relay_stats.write(_relay_stats_dict(stats))
            return
        env = tl.Envelope()
        try:
            env.ParseFromString(body)
        except DecodeError as exc:
            c.error(streams.wire_problem(body), f"envelope: {exc}")
            _badlog.warning("zmq-envelope", "undecodable envelope on %r: %s", topic, exc)
            return
        if topic == b"vision":
            self.vision_packets.write(env)
        elif topic == b"referee":
            self.referee_packets.write(env)


def _relay_stats_dict(s: tl.RelayStats) -> dict[str, Any]:
    return {
        "time_ns": s.time_ns,
        "received_mono": time.monotonic(),
        "output_mode": s.output_mode,
        "active_robots": s.active_robots,
        "stale_robots": s.stale_robots,
        "output_rate_hz": s.output_rate_hz,
        "command_latency_ms": s.command_latency_ms,
        "stale_stops": s.stale_stops,
        "estop_latched": s.estop_latched,
        "estop_by": s.estop_by,
        "streams": {
            st.name: {
                "packets": st.packets,
                "errors": st.errors,
                "rate_hz": st.rate_hz,
                "last_age_s": st.last_age_s,
                "last_error": st.last_error,
                "errors_by_reason": dict(sorted(st.errors_by_reason.items())),
            }
            for st in s.streams
        },
    }


def _parse(msg: Message, data: bytes) -> tuple[str, str] | None:
    """Parses ``data`` into ``msg``; on failure the reason (sslnet.streams) and the detail."""
    try:
        msg.ParseFromString(data)
    except (DecodeError, RuntimeError, ValueError) as exc:
        return streams.wire_problem(data), str(exc)
    if not msg.IsInitialized():
        errors: list[str] = msg.FindInitializationErrors()  # type: ignore[attr-defined]
        return streams.MISSING_FIELD, ", ".join(errors[:5])
    return None


class VisionIngest(Processor):
    """Decodes vision datagrams: detection frames and geometry onto their topics."""

    name = "vision-ingest"

    def __init__(self, bus: DataBus) -> None:
        packets = bus.of(topics.VISION_PACKETS)
        super().__init__(OnTopic(packets))
        self.reader = Reader(packets)
        self.detections = bus.of(topics.VISION_DETECTIONS)
        self.geometry = bus.of(topics.GEOMETRY)
        self.counter = StreamCounter("vision")
        self.latency = LatencyStage()  # relay arrival -> decoded on the bus
        self._last_geometry_bytes = b""
        self._last_geometry_bad: list[str] = []  # its names that are not UTF-8

    async def tick(self) -> None:
        for env in self.reader.read_new():
            self.counter.rate.add()
            pkt = SSL_WrapperPacket()
            reason = _parse(pkt, env.payload)
            if reason is not None:
                self.counter.error(*reason)
                _badlog.warning("vision", "bad vision packet from %s: %s", env.source,
                                self.counter.last_error)
                continue
            if not (pkt.HasField("detection") or pkt.HasField("geometry")):
                self.counter.error(streams.NO_CONTENT, "SSL_WrapperPacket has neither "
                                   "detection nor geometry")
                _badlog.warning("vision", "empty vision packet from %s", env.source)
                continue
            if pkt.HasField("detection"):
                self.detections.write(decode_detection(pkt.detection, env.receive_time_ns))
                self.latency.add_since(env.receive_time_ns)
            if pkt.HasField("geometry"):
                raw = pkt.geometry.field.SerializeToString()
                if raw != self._last_geometry_bytes:  # only a change goes on the bus
                    self._last_geometry_bytes = raw
                    self._last_geometry_bad = []
                    self.geometry.write(geometry_to_dict(pkt.geometry, self._last_geometry_bad))
                if self._last_geometry_bad:  # used all the same, counted in every packet
                    bad = ", ".join(sorted(set(self._last_geometry_bad)))
                    self.counter.error(streams.BAD_STRING, "not UTF-8: " + bad)
                    _badlog.warning("vision-string", "geometry from %s: not UTF-8 (%s); "
                                    "decoded with replacement characters", env.source, bad)


class RefereeIngest(Processor):
    """Decodes referee datagrams onto the referee topic; also runs when none arrives for
    ``SILENCE_CHECK_S``, so a silent referee is noticed (and logged) as it happens."""

    name = "referee-ingest"

    def __init__(self, bus: DataBus, watch: RefereeWatch | None = None) -> None:
        packets = bus.of(topics.REFEREE_PACKETS)
        super().__init__(OnTopic(packets, max_wait_s=SILENCE_CHECK_S))
        self.reader = Reader(packets)
        self.referee = bus.of(topics.REFEREE)
        self.counter = StreamCounter("referee")
        self.watch = watch or RefereeWatch()

    async def tick(self) -> None:
        for env in self.reader.read_new():
            self.counter.rate.add()
            msg = Referee()
            reason = _parse(msg, env.payload)
            if reason is not None:
                self.counter.error(*reason)
                _badlog.warning("referee", "bad referee packet from %s: %s", env.source,
                                self.counter.last_error)
                continue
            bad: list[str] = []
            state = decode_referee(msg, bad)
            if bad:  # used all the same, with replacement characters
                self.counter.error(streams.BAD_STRING, "not UTF-8: " + ", ".join(bad))
                _badlog.warning("referee-string", "referee message from %s: not UTF-8 (%s); "
                                "decoded with replacement characters", env.source, ", ".join(bad))
            self.watch.heard(state)
            self.referee.write(state)
        self.watch.check()


#: how often the referee ingest looks for a silent referee when nothing arrives
SILENCE_CHECK_S = 0.5


class WorldProcessor(Processor):
    """Merges camera frames into the world, on every new frame. The world is written only when
    a frame was merged: frames that are all dropped (capture time far from the receive clock,
    a camera id that cannot be) leave the world to age, so the lost-vision stop fires."""

    name = "world-model"

    def __init__(self, bus: DataBus, model: WorldModel | None = None) -> None:
        detections = bus.of(topics.VISION_DETECTIONS)
        super().__init__(OnTopic(detections))
        self.reader = Reader(detections)
        self.world = bus.of(topics.WORLD)
        self.geometry = bus.of(topics.GEOMETRY)
        self._geometry_seq = -1
        self.model = model or WorldModel()
        self.latency = LatencyStage()  # relay arrival -> world written
        self._rejected_total = 0
        # (monotonic time, counts by reason) when the counts changed, the last 10 s
        self._rejection_log: deque[tuple[float, dict[str, int]]] = deque(maxlen=32)

    def recent_rejections(self, window_s: float = 10.0) -> dict[str, int]:
        """What the world model dropped in the last ``window_s``, by reason."""
        now = time.monotonic()
        base: dict[str, int] | None = None
        for t, counts in self._rejection_log:
            if now - t > window_s:
                base = counts
        cur = self.model.rejected
        if not self._rejection_log or now - self._rejection_log[-1][0] > window_s:
            return {}
        base = base or {}
        return {k: v - base.get(k, 0) for k, v in sorted(cur.items()) if v - base.get(k, 0) > 0}

    def _field_from_geometry(self) -> None:
        if self.geometry.seq == self._geometry_seq:
            return
        self._geometry_seq = self.geometry.seq
        g = self.geometry.latest_value()
        if g is not None:
            self.model.set_field(g["field_length"] / 2, g["field_width"] / 2,
                                 g["boundary_width"])

    async def tick(self) -> None:
        frames = self.reader.read_new()
        if not frames:
            return
        self._field_from_geometry()
        merged = [f for f in frames if self.model.update(f)]
        total = sum(self.model.rejected.values())
        if total != self._rejected_total:
            self._rejected_total = total
            now, log_ = time.monotonic(), self._rejection_log
            if log_ and now - log_[-1][0] < 1.0:  # one entry a second at most
                log_[-1] = (log_[-1][0], dict(self.model.rejected))
            else:
                log_.append((now, dict(self.model.rejected)))
            _badlog.warning("world-rejected", "vision dropped by the world model (%s so far): "
                            "%s", _reasons(self.model.rejected), self.model.last_rejection)
        if not merged:
            return
        self.world.write(self.model.snapshot())
        for f in merged:
            self.latency.add_since(f.receive_time_ns)


def _reasons(counts: dict[str, int]) -> str:
    return ", ".join(f"{k} {v}" for k, v in sorted(counts.items()))


class StrategyProcessor(Processor):
    """Decides targets: operator targets first, the selected play for the rest of our team
    (roles, referee-driven behaviour, planned paths). The keeper's spot may come from the
    compute engine; a failed or late engine call falls back to the built-in code."""

    name = "strategy"

    def __init__(self, bus: DataBus, our_team: Team, params: StrategyParams | None = None,
                 hz: float = 20.0) -> None:
        super().__init__(Every(hz))
        self.world = bus.of(topics.WORLD)
        self.geometry = bus.of(topics.GEOMETRY)
        self.referee = bus.of(topics.REFEREE)
        self.operator = Reader(bus.of(topics.OPERATOR_TARGETS))
        self.targets = bus.of(topics.TARGETS)
        self.our_team: Team = our_team
        self.our_side_negative = True
        self.side_from_referee = True
        self.params = params or StrategyParams()
        self.core = StrategyCore()
        self.referee_source: Callable[[], RefereeState | None] = self.referee.latest_value
        self.operator_targets: dict[tuple[Team, int], Target] = {}
        self.engine: PoolEngine | None = None
        self.engine_fallbacks = 0
        self.engine_last_error = ""
        self._engine_task: asyncio.Task[tuple[float, float]] | None = None
        self._engine_point: tuple[float, tuple[float, float]] | None = None
        self._t0 = time.monotonic()

    async def tick(self) -> None:
        for op in self.operator.read_new():
            if op.target is None:
                self.operator_targets.pop((op.team, op.id), None)
            else:
                self.operator_targets[(op.team, op.id)] = op.target
        out: dict[tuple[Team, int], TargetEntry] = {
            k: TargetEntry(t, "operator", role="operator")
            for k, t in self.operator_targets.items()
        }
        world = self.world.latest_value()
        if world is not None and self.params.play != "idle":
            now = time.monotonic() - self._t0
            prep = self.core.prepare(world, self.geometry.latest_value(), self.referee_source(),
                                     self.params, self.our_team, self.our_side_negative,
                                     self.side_from_referee, now)
            keeper = await self._engine_keeper(prep)
            for rid, mv in self.core.decide(prep, keeper).items():
                key = (self.our_team, rid)
                if key in out:
                    continue
                out[key] = TargetEntry(
                    Target(mv.x, mv.y, mv.orientation), "strategy", role=mv.role,
                    path=mv.path, kick_speed_mps=mv.kick_speed_mps, chip=mv.chip,
                    dribbler_rpm=DRIBBLER_RPM if mv.dribbler else 0.0,
                    max_speed_mps=mv.max_speed_mps)
        self.targets.write(out)

    async def _engine_keeper(self, prep: Prepared) -> tuple[float, float] | None:
        """The keeper's spot (field frame) from the compute engine, or None (built-in code).

        The tick never waits for the engine: one call is in flight at a time, and the tick
        uses the newest answer if it is at most ``ENGINE_MAX_AGE_S`` old (the answer to the
        previous tick's ball, normally). A failed, late or malformed answer is a fallback."""
        eng = self.engine
        if eng is None or prep.ball_field is None or self.params.play in ("formation", "idle"):
            return None
        task = self._engine_task
        if task is not None and task.done():
            self._engine_task = None
            try:
                point = task.result()
                self._engine_point = (time.monotonic(), point)
            except Exception as exc:
                self.engine_fallbacks += 1
                msg = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
                self.engine_last_error = msg
                _badlog.warning("engine-keeper", "engine keeper call failed, built-in code "
                                "used: %s", msg)
                self._engine_point = None
                return None
        if self._engine_task is None:
            self._engine_task = asyncio.get_running_loop().create_task(
                self._call_keeper(eng, prep))
        got = self._engine_point
        if got is None or time.monotonic() - got[0] > ENGINE_MAX_AGE_S:
            if got is not None:
                self.engine_fallbacks += 1  # the engine is late: use the built-in code
            return None
        return got[1]

    async def _call_keeper(self, eng: PoolEngine, prep: Prepared) -> tuple[float, float]:
        p = self.params
        res = await eng.call(p.goalkeeper_function,
                             np.array([prep.ball_field], dtype=np.float64),
                             np.array([prep.ball_velocity_field], dtype=np.float64),
                             prep.goal_x_field, prep.inp.fs.goal_width,
                             45.0, p.keeper_min_speed_mmps, timeout_s=p.engine_timeout_s)
        try:
            arr = np.asarray(res, dtype=np.float64).reshape(-1)
        except (TypeError, ValueError) as exc:
            raise EngineError(f"{p.goalkeeper_function} returned {res!r}, expected [x y]") \
                from exc
        if arr.size < 2 or not np.all(np.isfinite(arr[:2])):
            raise EngineError(f"{p.goalkeeper_function} returned {res!r}, expected [x y]")
        return (float(arr[0]), float(arr[1]))

    async def engine_settled(self) -> None:
        """Waits until the engine call in flight (if any) has finished (tests, shutdown)."""
        task = self._engine_task
        if task is not None:
            await asyncio.wait([task])

    def drop_engine(self) -> None:
        """Forget the engine (being replaced): its answers no longer count."""
        self.engine = None
        self._engine_point = None
        if self._engine_task is not None:
            self._engine_task.cancel()
            self._engine_task = None


#: an engine answer older than this is not used (the built-in code is, as a fallback)
ENGINE_MAX_AGE_S = 0.25
DRIBBLER_RPM = 3000.0


class ControlProcessor(Processor):
    """Turns targets into robot commands on every world update with each robot's chosen
    controller (the paper's Algorithm 1 or 2, or the proportional baseline), then the safety
    rules: emergency stop and HALT zero every robot; a stale world zeroes every robot, a robot
    not seen gets zero; STOP and the other team's ball placement cap the speed."""

    name = "control"

    def __init__(self, bus: DataBus, max_wait_s: float, vision_stale_s: float,
                 settings: ControlSettings | None = None) -> None:
        world = bus.of(topics.WORLD)
        super().__init__(OnTopic(world, max_wait_s=max_wait_s))
        self.world = world
        self.targets = bus.of(topics.TARGETS)
        self.referee = bus.of(topics.REFEREE)
        self.estop = bus.of(topics.ESTOP)
        self.commands = bus.of(topics.ROBOT_COMMANDS)
        self.vision_stale_s = vision_stale_s
        self.strategy_stale_s = 0.5  # no targets for this long: the strategy is stuck, stop
        self.stop_speed_mps = 1.5
        self.our_team: Team = "blue"
        self.motion = MotionBank(settings or ControlSettings())
        self.last_commands: dict[tuple[Team, int], Command] = {}
        self.telemetry: dict[str, dict[str, Any]] = {}
        self.internal: InternalRefereeProcessor | None = None
        #: whether commands for the other team may go out (the station says: a simulator
        #: output and the operator's safety.other_team_in_simulator); else they never do
        self.may_drive_other_team: Callable[[], bool] = lambda: False
        self._last_tick = time.monotonic()
        self.halt_reason = ""

    def active_referee(self) -> RefereeState | None:
        """The referee the robots obey: the newest state, except the internal referee's own
        once the operator switched it off (then there is no referee until one is heard)."""
        ref = self.referee.latest_value()
        ir = self.internal
        if (ref is not None and ir is not None and not ir.enabled
                and ref.source_identifier == ir.referee.source_identifier):
            return None
        return ref

    def vision_age_s(self, now_mono: float) -> float:
        """How old the robots' view of the world is: since the world was last written, and
        since the relay received the newest frame merged into it (this machine's clock; a
        world written again and again from nothing new is as stale as one not written)."""
        rec = self.world.latest()
        if rec is None:
            return math.inf
        age = now_mono - rec.time_mono
        recv_ns = rec.value.receive_time_ns
        if recv_ns > 0:
            age = max(age, (time.time_ns() - recv_ns) / 1e9)
        return age

    def apply_settings(self, settings: ControlSettings, our_team: Team) -> None:
        self.motion.apply_settings(settings)
        self.our_team = our_team

    async def tick(self) -> None:
        now = time.monotonic()
        dt = min(0.1, now - self._last_tick)
        self._last_tick = now
        rec = self.world.latest()
        targets: dict[tuple[Team, int], TargetEntry] = self.targets.latest_value() or {}
        ref = self.active_referee()
        estop = bool(self.estop.latest_value())
        created = time.time_ns()
        if estop:
            self.halt_reason = "emergency stop"
            self.motion.reset_all()
            self.commands.write(CommandSet(created, 0, (), stop_all=True))
            self.last_commands = {}
            return
        other_ok = self.may_drive_other_team()
        keys = sorted(k for k in targets if k[0] == self.our_team or other_ok)
        zero = LocalVelocity.zero()
        targets_age = self.targets.age_s(now)
        stalled = targets_age > self.strategy_stale_s
        vision_age = self.vision_age_s(now)
        blind = vision_age > self.vision_stale_s
        if rec is None or blind or (ref and ref.halted) or stalled:
            self.halt_reason = ("HALT" if ref and ref.halted else
                                "no vision" if vision_age == math.inf else
                                f"no vision for {vision_age:.1f} s" if blind
                                else f"strategy stalled ({targets_age:.1f} s)")
            self.motion.reset_all()
            cmds = tuple(Command(t, i, zero) for t, i in keys)
            self.commands.write(CommandSet(created, 0, cmds))
            self.last_commands = {(c.team, c.id): c for c in cmds}
            return
        self.halt_reason = ""
        world = rec.value
        out: list[Command] = []
        command = ref.command if ref is not None else None
        for key in keys:
            robot = world.robot(*key)
            m = self.motion.get(key[0], key[1])
            if robot is None or not robot.visible:
                m.step(_UNSEEN, targets[key].target, dt)  # zero, and restart when seen again
                out.append(Command(key[0], key[1], zero))
                continue
            entry = targets[key]
            vel = m.step(RobotMotionState(robot.x, robot.y, robot.orientation),
                         next_waypoint(entry, robot.x, robot.y), dt)
            vel = referee_limits(
                vel, command, our_team=self.our_team, stop_speed_mps=self.stop_speed_mps,
                max_speed_mps=math.inf if entry.max_speed_mps is None else entry.max_speed_mps)
            kick_ok = kick_allowed(command)
            out.append(Command(key[0], key[1], vel,
                               kick_speed_mps=entry.kick_speed_mps if kick_ok else 0.0,
                               chip=entry.chip and kick_ok,
                               dribbler_rpm=entry.dribbler_rpm))
        cmds = tuple(out)
        self.last_commands = {(c.team, c.id): c for c in cmds}
        self.telemetry = self._telemetry()
        self.commands.write(CommandSet(created, world.receive_time_ns, cmds))

    def _telemetry(self) -> dict[str, dict[str, Any]]:
        out: dict[str, dict[str, Any]] = {}
        for key, tel in self.motion.telemetry().items():
            entry: dict[str, Any] = dict(tel)
            entry["algorithm"] = ALGORITHMS[int(tel["algorithm"])]
            entry["phase"] = PHASE_NAMES[int(tel["phase"])]
            out[key] = entry
        return out


_UNSEEN = RobotMotionState(0.0, 0.0, 0.0, visible=False)


#: a waypoint closer than this counts as passed: the robot heads for the next one
WAYPOINT_REACHED_MM = 120.0


def next_waypoint(entry: TargetEntry, x_mm: float, y_mm: float) -> Target:
    """Where the controller steers now: the first waypoint of the planned path not yet
    reached (with the final heading), or the target itself."""
    path = entry.path
    if len(path) <= 1:
        return entry.target
    # the nearest waypoint; the next one once it is reached or already passed (the path
    # was planned a strategy tick ago, the robot has moved along it since)
    k = min(range(len(path)), key=lambda i: math.hypot(path[i][0] - x_mm, path[i][1] - y_mm))
    if k < len(path) - 1:
        px, py = path[k]
        nx, ny = path[k + 1]
        passed = (x_mm - px) * (nx - px) + (y_mm - py) * (ny - py) > 0.0
        if passed or math.hypot(px - x_mm, py - y_mm) <= WAYPOINT_REACHED_MM:
            k += 1
    if k == len(path) - 1:
        return entry.target
    return _carry_through(path, k, x_mm, y_mm, entry.target.orientation)


#: how far past an intermediate waypoint the controller is aimed at most (mm)
CARRY_MAX_MM = 600.0


def _carry_through(path: tuple[tuple[float, float], ...], k: int, x_mm: float, y_mm: float,
                   orientation: float | None) -> Target:
    """The controller's target for intermediate waypoint ``k``: the waypoint itself pushed on
    along the robot's line to it, by up to the path still left after it (at most
    ``CARRY_MAX_MM``), scaled by cos^2 of the turn there. The speed controllers brake to
    stop at their target; aimed past a waypoint the robot keeps its speed through a gentle
    turn and still stops at a sharp one (90 deg or more: no carry at all)."""
    px, py = path[k]
    nx, ny = path[k + 1]
    ix, iy = px - x_mm, py - y_mm
    ox, oy = nx - px, ny - py
    li, lo = math.hypot(ix, iy), math.hypot(ox, oy)
    if li < 1e-6 or lo < 1e-6:
        return Target(px, py, orientation)
    cos_turn = (ix * ox + iy * oy) / (li * lo)
    if cos_turn <= 0.0:
        return Target(px, py, orientation)
    rest = lo + sum(math.dist(path[i], path[i + 1]) for i in range(k + 1, len(path) - 1))
    ext = min(rest, CARRY_MAX_MM) * cos_turn * cos_turn
    return Target(px + ix / li * ext, py + iy / li * ext, orientation)


class InternalRefereeProcessor(Processor):
    """Sends the internal referee's state at 20 Hz while it is on; steps aside as soon as
    another referee source (the official game controller) is heard."""

    name = "internal-referee"
    foreign_hold_s = 3.0

    def __init__(self, bus: DataBus, referee: InternalReferee, hz: float = 20.0) -> None:
        super().__init__(Every(hz))
        self.referee = referee
        self.enabled = False
        self.disabled_reason = ""
        self.last_foreign: tuple[float, str] | None = None
        self.out = bus.of(topics.REFEREE_OUT)
        self.reader = Reader(bus.of(topics.REFEREE))

    def foreign_active(self) -> str | None:
        """The source id of another referee heard recently, if any."""
        if self.last_foreign and time.monotonic() - self.last_foreign[0] < self.foreign_hold_s:
            return self.last_foreign[1] or "(no source identifier)"
        return None

    def enable(self, on: bool) -> None:
        if on:
            other = self.foreign_active()
            if other is not None:
                raise RefereeCommandError(
                    f"a game controller is active ({other}): the internal referee stays off")
            self.disabled_reason = ""
        self.enabled = on

    async def tick(self) -> None:
        for r in self.reader.read_new():
            if r.source_identifier != self.referee.source_identifier:
                self.last_foreign = (time.monotonic(), r.source_identifier)
                if self.enabled:
                    self.enabled = False
                    self.disabled_reason = (f"switched off: a game controller is active "
                                            f"({r.source_identifier or 'no source identifier'})")
                    log.warning("internal referee %s", self.disabled_reason)
        if self.enabled:
            self.out.write(self.referee.encode())


class CommandPublisher(Processor):
    """Sends each command set and simulator command to the relay."""

    name = "command-publisher"

    def __init__(self, bus: DataBus, sock: zmq.asyncio.Socket) -> None:
        cmds = bus.of(topics.ROBOT_COMMANDS)
        super().__init__(OnTopic(cmds, max_wait_s=0.05))
        self.sock = sock
        self.reader = Reader(cmds)
        self.sim_reader = Reader(bus.of(topics.SIM_COMMANDS))
        self.referee_out_reader = Reader(bus.of(topics.REFEREE_OUT))
        self.seq = 0
        self.latency = LatencyStage()  # relay arrival -> command set sent to the relay
        self.sent = RateCounter()
        self.estop = bus.of(topics.ESTOP)
        self.relay_stats = bus.of(topics.RELAY_STATS)
        #: called when the relay reports a latch this backend does not have
        self.adopt_estop: Callable[[str], None] = lambda by: None
        self.estop_by: Callable[[], str] = lambda: ""
        self._estop_sent = (False, -1e9)  # (active, monotonic time) of the last latch message
        self._release_until = -1e9  # a release is being repeated until the relay confirms

    async def tick(self) -> None:
        for cs in self.reader.read_new():
            self.seq += 1
            msg = tl.RobotCommandSet(
                created_time_ns=cs.created_time_ns,
                source_receive_time_ns=cs.source_receive_time_ns,
                sequence=self.seq,
                stop_all=cs.stop_all,
            )
            for c in cs.commands:
                msg.commands.add(
                    team=tl.TEAM_BLUE if c.team == "blue" else tl.TEAM_YELLOW,
                    id=c.id,
                    forward_mps=c.velocity.forward_mps,
                    left_mps=c.velocity.left_mps,
                    angular_radps=c.velocity.angular_radps,
                    kick_speed_mps=c.kick_speed_mps,
                    chip=c.chip,
                    dribbler_rpm=c.dribbler_rpm,
                )
            await self.sock.send_multipart([b"commands", msg.SerializeToString()])
            self.sent.add()
            self.latency.add_since(cs.source_receive_time_ns)
        for raw in self.sim_reader.read_new():
            await self.sock.send_multipart([b"sim", raw])
        for raw in self.referee_out_reader.read_new():
            await self.sock.send_multipart([b"referee-out", raw])
        await self._estop_latch()

    async def _estop_latch(self) -> None:
        """Keeps the relay's latch in step: PRESS on a press and every 0.5 s while active
        (a relay that restarts, or a slow ZeroMQ join, gets it again); RELEASE only after an
        operator's release, repeated until the relay's stats say it is released (3 s at
        most). A latch the relay reports and this backend does not have is adopted."""
        now = time.monotonic()
        active = bool(self.estop.latest_value())
        was, when = self._estop_sent
        if active and (not was or now - when >= 0.5):
            await self._send_estop(tl.EmergencyStop.PRESS)
            self._estop_sent = (True, now)
            self._release_until = -1e9
            return
        if not active and was:  # the operator released it
            await self._send_estop(tl.EmergencyStop.RELEASE)
            self._estop_sent = (False, now)
            self._release_until = now + 3.0
            return
        rs = self.relay_stats.latest_value()
        if active or rs is None or not rs.get("estop_latched"):
            return
        if now < self._release_until:  # not confirmed yet: say it again
            if now - when >= 0.1:
                await self._send_estop(tl.EmergencyStop.RELEASE)
                self._estop_sent = (False, now)
        elif now - rs["received_mono"] < 1.5:  # fresh stats: the relay holds a latch we lack
            self.adopt_estop(str(rs.get("estop_by", "")))

    async def _send_estop(self, action: int) -> None:
        msg = tl.EmergencyStop(action=action, time_ns=time.time_ns(),  # type: ignore[arg-type]
                               by=self.estop_by())
        await self.sock.send_multipart([b"estop", msg.SerializeToString()])

    def latency_summary(self) -> dict[str, float]:
        return self.latency.summary()
