"""The composition root of the backend: bus, processors and ZeroMQ, started and stopped in
mirror order. The station thread is the only writer of station state: the API reads the
immutable ``views`` it publishes and changes state only through ``call`` (the command queue)."""

from __future__ import annotations

import asyncio
import concurrent.futures
import contextlib
import logging
import math
import sys
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any, TypeVar, cast

import zmq
import zmq.asyncio

from sslpb import ssl_gc_common_pb2
from sslpb.ssl_simulation_control_pb2 import SimulatorCommand

from . import contract, topics
from .bus import DataBus
from .config import ROOT, Settings
from .control.goto import Target
from .engine import NumpyEngine, OctaveEngine, PoolEngine
from .estop import EstopLatch
from .jsonsafe import dumps
from .messages import OperatorTarget, TargetEntry
from .params.model import PLAYS, StationParams, StrategyParams
from .params.store import ParamStore, deep_merge, parse_setting
from .processor import Every, OnTopic, Processor, Runner
from .processors import (
    CommandPublisher,
    ControlProcessor,
    InternalRefereeProcessor,
    RefereeIngest,
    RelayIngest,
    StrategyProcessor,
    VisionIngest,
    WorldProcessor,
)
from .referee.internal import OPERATOR_COMMANDS, InternalReferee
from .referee.watch import RefereeWatch
from .strategy.plays import PLAY_INFO
from .world.state import Team
from .zmqio import pub_socket, sub_socket

log = logging.getLogger("touchline.station")
T = TypeVar("T")


@dataclass(frozen=True)
class Views:
    """What the web side reads: built on the station thread (the only writer of station
    state) and replaced whole, never changed, so a web thread never sees a half-made one."""

    world_key: tuple[object, ...] = ()
    world: contract.World | None = None
    world_json: str = ""
    health: contract.Health | None = None
    health_json: str = ""
    health_mono: float = -1e9
    geometry: contract.Geometry | None = None
    geometry_seq: int = -1
    #: counts every publication that changed something (websocket clients wait on it)
    serial: int = 0


class ViewPublisher(Processor):
    """Publishes the station's views for the websocket clients at ``stream.ws_max_hz`` (what
    changed only, and nothing while no client listens), health at most every 0.25 s. Eight
    cameras merge hundreds of frames a second; a page needs no more than it can show."""

    name = "views"
    health_period_s = 0.25

    def __init__(self, station: Station) -> None:
        super().__init__(Every(60.0))
        self.station = station

    def configure(self, params: StationParams) -> None:
        self.set_rate(params.stream.ws_max_hz)

    async def tick(self) -> None:
        self.station.publish_views()


class Station:
    def __init__(self, settings: Settings) -> None:
        self.settings = settings
        self.ctx: zmq.asyncio.Context | None = None
        self._loop: asyncio.AbstractEventLoop | None = None
        self._thread: threading.Thread | None = None
        self._stop_event: asyncio.Event | None = None
        self.runner = Runner()
        self.started_mono = time.monotonic()
        self.ws_clients = 0
        self.params = ParamStore(settings.state_dir)
        overrides: dict[str, Any] = {}
        if settings.our_team is not None:
            overrides["our_team"] = settings.our_team
        if settings.our_side is not None:
            overrides["our_side"] = "negative-x" if settings.our_side < 0 else "positive-x"
        changes: dict[str, Any] = {"team": overrides} if overrides else {}
        if settings.play is not None:
            changes["strategy"] = {"play": settings.play}
        for item in settings.set_params:
            changes = deep_merge(changes, parse_setting(item))
        if changes:
            self.params.patch(changes)
        self.bus = DataBus(self.params.current.bus.sizes())
        # topics the API writes to
        self.operator_targets = self.bus.of(topics.OPERATOR_TARGETS)
        self.estop_topic = self.bus.of(topics.ESTOP)
        # the latched emergency stop: a persisted one is active from the first tick on
        self.estop_latch = EstopLatch(settings.state_dir)
        #: monotonic time of the last press (or of start-up with a persisted stop)
        self._estop_mono = time.monotonic()
        if self.estop_latch.active:
            self.estop_topic.write(True)
        self.sim_commands = self.bus.of(topics.SIM_COMMANDS)
        self.world_topic = self.bus.of(topics.WORLD)
        self.geometry_topic = self.bus.of(topics.GEOMETRY)
        self.referee_topic = self.bus.of(topics.REFEREE)
        self.targets_topic = self.bus.of(topics.TARGETS)
        self.relay_stats = self.bus.of(topics.RELAY_STATS)
        self.params_topic = self.bus.of(topics.PARAMS)
        self.referee_state = InternalReferee()
        self.referee_watch = RefereeWatch()
        self._engine_key: tuple[str, str] | None = None
        self._engine_gen = 0
        self._engine_tasks: set[asyncio.Task[None]] = set()
        self.engine_error = ""
        for spec in topics.ALL:  # every topic exists (and shows in health) from the start
            self.bus.of(spec)
        # the processors, built here and configured from the parameters; start() only gives
        # the two ZeroMQ ones their sockets and runs them
        prm = self.params.current
        self.ingest = RelayIngest(self.bus)
        self.vision = VisionIngest(self.bus)
        self.referee = RefereeIngest(self.bus, self.referee_watch)
        self.world = WorldProcessor(self.bus)
        self.strategy = StrategyProcessor(self.bus, prm.team.our_team, prm.strategy)
        self.control = ControlProcessor(self.bus, prm.processors.control_max_wait_s,
                                        prm.safety.vision_stale_s)
        self.publisher = CommandPublisher(self.bus)
        self.publisher.adopt_estop = self.adopt_relay_estop
        self.publisher.estop_by = lambda: self.estop_latch.state.by
        self.internal_referee = InternalRefereeProcessor(self.bus, self.referee_state)
        self.control.internal = self.internal_referee
        self.control.may_drive_other_team = self.drives_other_team
        # the internal referee switched off is not obeyed: its silence is no warning
        self.referee_watch.obeyed = lambda: self.control.active_referee() is not None
        self.strategy.referee_source = self.control.active_referee
        self.views = Views()
        self._view_listeners: set[Callable[[], None]] = set()
        self.processors: tuple[Processor, ...] = (
            self.ingest, self.vision, self.referee, self.world, self.strategy, self.control,
            self.internal_referee, self.publisher, ViewPublisher(self))

    # ---- the station thread: the bus and every processor run on their own event loop, so
    # web traffic (JSON encoding, websocket sends) never delays control ----

    def start_thread(self) -> None:
        """Starts the station loop in its own thread and returns once it runs."""
        ready = threading.Event()
        errors: list[BaseException] = []

        def main() -> None:
            loop = asyncio.new_event_loop()
            asyncio.set_event_loop(loop)
            stop_event = asyncio.Event()
            self._stop_event = stop_event

            async def run() -> None:
                try:
                    await self.start()
                except BaseException as exc:
                    errors.append(exc)
                    ready.set()
                    raise
                self._loop = loop
                ready.set()
                await stop_event.wait()
                await self.stop()

            try:
                loop.run_until_complete(run())
            except BaseException:
                log.exception("station loop ended with an error")
            finally:
                self._loop = None
                loop.close()

        # control latency: let the station thread take the GIL back quickly from web work
        sys.setswitchinterval(0.0005)
        self._thread = threading.Thread(target=main, name="station", daemon=True)
        self._thread.start()
        if not ready.wait(30):
            raise RuntimeError("station did not start within 30 s")
        if errors:
            raise RuntimeError(f"station failed to start: {errors[0]}") from errors[0]

    def stop_thread(self) -> None:
        loop, ev = self._loop, self._stop_event
        if loop is not None and ev is not None:
            loop.call_soon_threadsafe(ev.set)
        if self._thread is not None:
            self._thread.join(timeout=10)
            self._thread = None

    def _schedule(self, fn: Callable[..., T], *args: Any) -> concurrent.futures.Future[T]:
        fut: concurrent.futures.Future[T] = concurrent.futures.Future()

        def run() -> None:
            try:
                fut.set_result(fn(*args))
            except BaseException as exc:  # handed to the caller
                fut.set_exception(exc)

        loop = self._loop
        if loop is None or threading.current_thread() is self._thread:
            run()
        else:
            loop.call_soon_threadsafe(run)
        return fut

    def _apply_params_soon(self, p: StationParams, version: int) -> None:
        self._schedule(self.apply_params, p, version)

    def _command(self, fn: Callable[..., T], *args: Any) -> concurrent.futures.Future[T]:
        """Queues ``fn(*args)`` for the station loop (between two ticks); once it ran, fresh
        views are published, so the next read sees the change."""
        def command() -> T:
            try:
                return fn(*args)
            finally:
                if self._loop is not None and self._view_listeners:
                    self.publish_views(force=True)
        return self._schedule(command)

    async def call(self, fn: Callable[..., T], *args: Any) -> T:
        """The one way the web side changes station state (the command queue): runs
        ``fn(*args)`` on the station loop and returns its result."""
        return await asyncio.wrap_future(self._command(fn, *args))

    async def read(self, fn: Callable[..., T], *args: Any) -> T:
        """Runs ``fn(*args)`` on the station loop for an answer that must be current (not the
        published views): the station thread reads its own state."""
        return await asyncio.wrap_future(self._schedule(fn, *args))

    def call_sync(self, fn: Callable[..., T], *args: Any, timeout_s: float = 5.0) -> T:
        """``call`` for a thread without an event loop (tests, scripts)."""
        return self._command(fn, *args).result(timeout=timeout_s)

    async def start(self) -> None:
        s = self.settings
        self.ctx = zmq.asyncio.Context()
        self.ingest.attach(sub_socket(self.ctx, s.relay_pub, [b"vision", b"referee", b"stats"]))
        self.publisher.attach(pub_socket(self.ctx, s.relay_sub))
        prm = self.params.current
        self.apply_params(prm, self.params.version)
        # the store validates and persists in the web thread; the station applies on its loop
        self.params.subscribe(self._apply_params_soon)
        for p in self.processors:
            self.runner.add(p)
        await self.runner.start()
        self.publish_views(force=True)
        log.info("station started: relay pub %s, relay sub %s, our team %s, parameters v%d",
                 s.relay_pub, s.relay_sub, prm.team.our_team, self.params.version)

    def apply_params(self, p: StationParams, version: int) -> None:
        """Applies a validated parameter set to every part at once (between two ticks: the
        event loop runs one thing at a time), then tells the clients."""
        for proc in self.processors:
            proc.configure(p)
        self._configure_engine(p.strategy)
        self.referee_state.blue_team_on_positive_half = (
            (p.team.our_team == "blue") == (p.team.our_side == "positive-x"))
        sized = {s.name: s for s in topics.ALL}
        for name, size in p.bus.sizes().items():
            self.bus.of(sized[name]).resize(size)
        self.params_topic.write(version)
        self._notify_views()

    # ---- the compute engine (started and replaced in the background; strategy uses it
    # once it runs and falls back to the built-in code meanwhile) ----

    def _configure_engine(self, sp: StrategyParams) -> None:
        key = (sp.engine, sp.scripts_dir)
        if key == self._engine_key:
            return
        self._engine_key = key
        self._engine_gen += 1
        old = self.strategy.engine
        self.strategy.drop_engine()
        self.engine_error = ""
        loop = asyncio.get_running_loop()
        task = loop.create_task(self._swap_engine(old, sp, self._engine_gen))
        self._engine_tasks.add(task)
        task.add_done_callback(self._engine_tasks.discard)

    async def _swap_engine(self, old: PoolEngine | None, sp: StrategyParams, gen: int) -> None:
        if old is not None:
            await old.close()
        if sp.engine == "off":
            return
        eng: PoolEngine
        if sp.engine == "numpy":
            # the keeper's rule under the same name as the shipped .m example
            eng = NumpyEngine(functions={"goalkeeper": "backend.geometry.fit:goalkeeper_target"},
                              preload=["backend.geometry.fit"], workers=1,
                              default_timeout_s=sp.engine_timeout_s)
        else:
            scripts = Path(sp.scripts_dir)
            if not scripts.is_absolute():
                scripts = ROOT / scripts
            eng = OctaveEngine(str(scripts), workers=1, default_timeout_s=sp.engine_timeout_s)
        try:
            await eng.start()
        except Exception as exc:
            self.engine_error = f"{sp.engine} engine did not start: {exc}"
            log.error("%s", self.engine_error)
            await eng.close()
            return
        if gen != self._engine_gen:  # configured again meanwhile
            await eng.close()
            return
        self.strategy.engine = eng
        log.info("compute engine %s started for the goalkeeper (%s)", sp.engine,
                 sp.goalkeeper_function)

    def engine_health(self) -> contract.EngineHealth | None:
        sp = self.strategy.params
        if sp.engine == "off":
            return None
        eng = self.strategy.engine
        out: dict[str, Any] = dict(eng.health()) if eng is not None else {
            "kind": sp.engine, "workers": 0, "busy": 0, "idle": 0, "calls": 0,
            "calls_per_s": 0.0, "latency_mean_ms": 0.0, "latency_p99_ms": 0.0, "ok": 0,
            "errors": 0, "timeouts": 0, "crashes": 0, "restarts": 0, "start_failures": 0,
            "last_error": self.engine_error or "starting"}
        out["function"] = sp.goalkeeper_function
        out["fallbacks"] = self.strategy.engine_fallbacks
        out["running"] = eng is not None
        if not out.get("last_error") and self.strategy.engine_last_error:
            out["last_error"] = self.strategy.engine_last_error
        return cast(contract.EngineHealth, out)

    def strategy_state(self) -> contract.StrategyState:
        """What the strategy is doing now (sent with every world update: kept small)."""
        core = self.strategy.core
        sit = core.situation if core is not None else None
        return {
            "play": self.params.current.strategy.play,
            "situation": sit.key if sit is not None else "running",
            "situation_text": sit.text() if sit is not None else "",
            "our_team": self.params.current.team.our_team,
            "our_side": "negative-x" if core is None or core.frame.sign > 0 else "positive-x",
            "side_from_referee": bool(core and core.side_from_referee),
            "tick_ms": core.last_tick_ms if core is not None else 0.0,
        }

    def strategy_view(self) -> contract.StrategyView:
        """``strategy_state`` plus the plays to choose from and the roles (GET /api/strategy)."""
        core = self.strategy.core
        team = self.params.current.team.our_team
        return {
            **self.strategy_state(),
            "plays": [{"name": n, "title": PLAY_INFO[n][0], "description": PLAY_INFO[n][1]}
                      for n in PLAYS],
            "roles": {f"{team}/{rid}": role
                      for rid, role in (core.strategy.roles.items() if core else [])},
        }

    async def stop(self) -> None:
        # a last stop to every robot we drive, then shut down
        if self.ctx is not None and self.publisher.attached:
            with contextlib.suppress(zmq.ZMQError):
                await self.publisher.sock.send_multipart([b"commands", _stop_all_bytes()])
        await self.runner.stop()
        for task in list(self._engine_tasks):
            task.cancel()
            with contextlib.suppress(asyncio.CancelledError, Exception):
                await task
        eng = self.strategy.engine
        self.strategy.drop_engine()
        if eng is not None:
            await eng.close()
        if self.ctx is not None:
            self.ctx.destroy(linger=0)
            self.ctx = None

    # ---- commands from the API (written onto the bus; processors apply them) ----

    def relay_output(self) -> str | None:
        """The relay's output: what its stats say, else what the launcher said; when they
        differ, robot-box (the one that cannot address a team) wins."""
        rs = self.relay_stats.latest_value()
        said = rs.get("output_mode") or None if rs is not None else None
        flag = self.settings.relay_output
        if said and flag and said != flag:
            return "robot-box" if "robot-box" in (said, flag) else said
        return said or flag

    def other_team_refusal(self, team: Team, rid: int) -> str | None:
        """Why robot ``team``/``rid`` must not be commanded, or None. Our team always may be;
        the other team only on a simulator output and with safety.other_team_in_simulator
        (robot-box datagrams have no team field: their robot 3 would be our robot 3)."""
        our = self.params.current.team.our_team
        if team == our:
            return None
        out = self.relay_output()
        if out == "robot-box":
            return (f"the relay drives real robots (robot-box), whose datagrams have no team "
                    f"field: a command for {team} {rid} would drive our ({our}) robot {rid}; "
                    f"only {our} robots can be commanded")
        if out is None:
            return (f"{team} is the other team and the relay's output is not known yet: only "
                    f"{our} robots can be commanded")
        if not self.params.current.safety.other_team_in_simulator:
            return (f"{team} is the other team: set safety.other_team_in_simulator to drive it "
                    f"in the simulator ({out})")
        return None

    def drives_other_team(self) -> bool:
        """The control loop may command the other team (a simulator, and the operator said)."""
        other: Team = "yellow" if self.params.current.team.our_team == "blue" else "blue"
        return self.other_team_refusal(other, 0) is None

    def set_target(self, team: Team, rid: int, x: float, y: float,
                   orientation: float | None) -> None:
        self.operator_targets.write(OperatorTarget(team, rid, Target(x, y, orientation)))

    def clear_target(self, team: Team, rid: int) -> None:
        self.operator_targets.write(OperatorTarget(team, rid, None))

    def set_estop(self, active: bool, by: str = "") -> None:
        """Press (``active``) or release the emergency stop: persisted, on the bus (control
        stops every robot), and latched in or released from the relay (CommandPublisher)."""
        self.estop_latch.set(active, by)
        self._estop_mono = time.monotonic()
        self.estop_topic.write(active)

    def adopt_relay_estop(self, by: str) -> None:
        """The relay is latched although this backend is not (its file was lost, or another
        backend pressed it): the stop is the relay's, and the station says so."""
        if not self.estop:
            log.warning("the relay's emergency stop is latched (by %s): active here too", by)
            self.set_estop(True, f"relay latch ({by or '?'})")

    def estop_view(self) -> contract.EstopInfo:
        s = self.estop_latch.state
        rs = self.relay_stats.latest_value()
        return {"active": self.estop, "since": s.since, "by": s.by,
                "relay_latched": None if rs is None else bool(rs.get("estop_latched"))}

    def _estop_warnings(self) -> list[str]:
        """Health lines: an active stop (every page says so), a relay that has not latched it
        a few seconds after the press, and a latch file that could not be read or written."""
        out: list[str] = []
        s = self.estop_latch.state
        if self.estop:
            when = time.strftime("%H:%M:%S", time.localtime(s.since)) if s.since > 0 else "?"
            out.append(f"emergency stop active since {when} ({s.by or '?'}): every robot is "
                       f"held at zero until an operator releases it")
            rs = self.relay_stats.latest_value()
            if rs is not None and time.monotonic() - rs["received_mono"] < 3.0 \
                    and not rs.get("estop_latched") and time.monotonic() - self._estop_mono > 3.0:
                out.append("the relay has not latched the emergency stop (the backend holds "
                           "every robot at zero; a backend restart would rely on estop.json)")
        if self.estop_latch.warning:
            out.append(self.estop_latch.warning)
        return out

    def teleport_ball(self, x_mm: float, y_mm: float, vx_mps: float = 0.0,
                      vy_mps: float = 0.0) -> None:
        """Through the simulator (SSL simulation protocol, metres)."""
        cmd = SimulatorCommand()
        b = cmd.control.teleport_ball
        b.x, b.y, b.z = x_mm / 1000.0, y_mm / 1000.0, 0.0
        b.vx, b.vy, b.vz = vx_mps, vy_mps, 0.0
        self.sim_commands.write(cmd.SerializeToString())

    def teleport_robot(self, team: Team, rid: int, x_mm: float, y_mm: float,
                       orientation: float | None, present: bool = True) -> None:
        cmd = SimulatorCommand()
        t = cmd.control.teleport_robot.add()
        t.id.id = rid
        t.id.team = ssl_gc_common_pb2.BLUE if team == "blue" else ssl_gc_common_pb2.YELLOW
        t.x, t.y = x_mm / 1000.0, y_mm / 1000.0
        if orientation is not None:
            t.orientation = orientation
        t.v_x = t.v_y = t.v_angular = 0.0
        t.present = present
        self.sim_commands.write(cmd.SerializeToString())

    def referee_view(self) -> contract.RefereeView:
        ir = self.internal_referee
        st = self.referee_state
        return {
            "internal": {
                "enabled": ir.enabled,
                "disabled_reason": ir.disabled_reason,
                "foreign_source": ir.foreign_active(),
                "command": st.command,
                "stage": st.stage,
                "command_counter": st.command_counter,
                "designated_position": None if st.designated_position is None else {
                    "x": st.designated_position[0], "y": st.designated_position[1]},
                "score": {"blue": st.blue.score, "yellow": st.yellow.score},
                "max_allowed_bots": {"blue": st.max_allowed_bots("blue"),
                                     "yellow": st.max_allowed_bots("yellow")},
                "commands": list(OPERATOR_COMMANDS),
            },
        }

    def give_card(self, team: Team, card: str) -> None:
        """A card from the internal referee; the division's robots per team come from the
        field size (A: 12 m x 9 m, 11 robots)."""
        geo = self.geometry()
        self.referee_state.robots_per_team = \
            11 if geo is not None and geo["field_length"] >= 11000 else 6
        self.referee_state.card(team, card)

    @property
    def estop(self) -> bool:
        return bool(self.estop_topic.latest_value())

    # ---- views ----

    def world_dict(self) -> contract.World:
        world = self.world_topic.latest_value()
        targets: dict[tuple[Team, int], TargetEntry] = self.targets_topic.latest_value() or {}
        ref = self.referee_topic.latest()
        if ref is not None and self.control.active_referee() is None:
            ref = None  # the internal referee's own state after it was switched off
        commands = self.control.last_commands
        telemetry = self.control.telemetry
        now_unix = time.time()
        out: contract.World = {
            "seq": self.world_topic.seq,
            "t_capture": world.t_capture if world else 0.0,
            "ball": None,
            "robots": [],
            "cameras": [],
            "referee": None,
            "estop": self.estop,
            "estop_info": self.estop_view(),
            "halt_reason": self.control.halt_reason,
            "strategy": None,
            "internal_referee": self.referee_view()["internal"],
        }
        out["strategy"] = self.strategy_state()
        if ref is not None:
            internal = ref.value.source_identifier == self.referee_state.source_identifier
            out["referee"] = ref.value.to_dict(time.monotonic() - ref.time_mono,
                                               "internal" if internal else None)
        if world is None:
            return out
        t_ref = world.t_capture
        if world.ball is not None:
            b = world.ball
            ball: contract.Ball = {
                "x": b.x, "y": b.y, "vx": b.vx, "vy": b.vy, "visible": b.visible,
                "age_s": t_ref - b.t_seen, "cameras": list(b.cameras), "raw_x": b.raw_x,
                "raw_y": b.raw_y, "predicted": b.predicted, "lost": b.lost, "filter": b.filter}
            out["ball"] = ball
        robots: list[contract.Robot] = []
        for r in world.robots:
            entry = targets.get((r.team, r.id))
            cmd = commands.get((r.team, r.id))
            robots.append({
                "team": r.team, "id": r.id, "x": r.x, "y": r.y, "orientation": r.orientation,
                "vx": r.vx, "vy": r.vy, "omega": r.omega, "visible": r.visible,
                "age_s": t_ref - r.t_seen, "cameras": list(r.cameras),
                "target": None if entry is None else {
                    "x": entry.target.x, "y": entry.target.y,
                    "orientation": entry.target.orientation, "source": entry.source,
                },
                "role": entry.role if entry is not None and entry.role else None,
                "path": None if entry is None or not entry.path else [
                    {"x": px, "y": py} for px, py in entry.path],
                "kick": None if entry is None or entry.kick_speed_mps <= 0 else {
                    "speed_mps": entry.kick_speed_mps, "chip": entry.chip},
                "dribbler": bool(entry is not None and entry.dribbler_rpm > 0),
                "controlled": entry is not None,
                "raw_x": r.raw_x, "raw_y": r.raw_y, "raw_orientation": r.raw_orientation,
                "predicted": r.predicted, "lost": r.lost, "filter": r.filter,
                "control": (cast(contract.RobotControl, telemetry.get(f"{r.team}/{r.id}"))
                            if entry is not None else None),
                "command": None if cmd is None else {
                    "forward_mps": cmd.velocity.forward_mps,
                    "left_mps": cmd.velocity.left_mps,
                    "angular_radps": cmd.velocity.angular_radps,
                },
            })
        out["robots"] = robots
        out["cameras"] = [{
            "camera_id": c.camera_id, "frame_number": c.frame_number, "t_capture": c.t_capture,
            "age_s": now_unix - c.t_capture,
            "balls": [{"x": b.x, "y": b.y} for b in c.balls],
            "robots": [{"team": rr.team, "id": rr.id, "x": rr.x, "y": rr.y,
                        "orientation": rr.orientation} for rr in c.robots],
        } for c in world.cameras]
        return out

    def _world_health(self) -> contract.WorldHealth | None:
        """The world model's view: its age by the receive clock, what it dropped and why,
        each camera's clock offset."""
        model = self.world.model
        age = self.control.vision_age_s(time.monotonic())
        return {
            "age_s": age if math.isfinite(age) else None,
            "stale": age > self.control.vision_stale_s,
            "rejected": dict(model.rejected),
            "recent_rejections": self.world.recent_rejections(),
            "last_rejection": model.last_rejection,
            "clock_resyncs": model.clocks.resyncs,
            "camera_clock_offsets_s": {str(c): o for c, o in model.clocks.offsets().items()},
        }

    def _latency_stages(self) -> list[contract.LatencyStage]:
        """Each stage from a vision datagram's arrival at the relay, in pipeline order."""
        stages = [cast(contract.LatencyStage, {"stage": name, **stage.summary()})
                  for name, stage in (("decoded (vision ingest)", self.vision.latency),
                                      ("world model written", self.world.latency),
                                      ("commands sent to relay", self.publisher.latency))]
        rs = self.relay_stats.latest_value()
        if rs is not None and rs.get("command_latency_ms", -1) >= 0:
            stages.append({"stage": "sent to robots (relay)", "mean_ms": rs["command_latency_ms"],
                           "p50_ms": None, "p99_ms": None, "n": None})
        return stages

    def world_version(self) -> tuple[object, ...]:
        """Changes whenever the world message would: a new world, a referee message, the
        e-stop, why the robots are stopped (that changes while no world is written: vision
        lost), or the internal referee (its panel follows the world message)."""
        ir, rs = self.internal_referee, self.referee_state
        return (self.world_topic.seq, self.referee_topic.seq, self.estop,
                self.control.halt_reason, rs.command_counter,
                ir.enabled, ir.foreign_active(), rs.max_allowed_bots("blue"),
                rs.max_allowed_bots("yellow"), rs.blue.score, rs.yellow.score)

    def world_json(self) -> str:
        """The world message as JSON (what every websocket client gets)."""
        return dumps({"type": "world", "world": self.world_dict()}, "world")

    def publish_views(self, force: bool = False) -> None:
        """Builds what changed of the web side's views (on the station thread) and tells the
        websocket clients. The web side only ever reads ``self.views``."""
        if not force and not self._view_listeners:
            return  # no websocket client: HTTP answers are built when asked
        v = self.views
        changes: dict[str, Any] = {}
        key = self.world_version()
        if force or key != v.world_key:
            world = self.world_dict()
            changes.update(world_key=key, world=world,
                           world_json=dumps({"type": "world", "world": world}, "world"))
        now = time.monotonic()
        if force or now - v.health_mono >= ViewPublisher.health_period_s:
            health = self.health()
            changes.update(health=health, health_mono=now,
                           health_json=dumps({"type": "health", "health": health}, "health"))
        if force or self.geometry_topic.seq != v.geometry_seq:
            changes.update(geometry=self.geometry(), geometry_seq=self.geometry_topic.seq)
        if changes:
            self.views = replace(v, serial=v.serial + 1, **changes)
            self._notify_views()

    def subscribe_views(self, listener: Callable[[], None]) -> Callable[[], None]:
        """``listener()`` is called (on the station thread: it must only hand over, e.g. with
        ``loop.call_soon_threadsafe``) after every publication; returns the unsubscribe."""
        self._view_listeners.add(listener)
        return lambda: self._view_listeners.discard(listener)

    def _notify_views(self) -> None:
        for listener in list(self._view_listeners):
            try:
                listener()
            except RuntimeError:  # its web loop has closed
                self._view_listeners.discard(listener)

    def geometry(self) -> contract.Geometry | None:
        """The field as decoded (cleaned at decode time; non-finite numbers, should any get
        through, become null here rather than break the JSON)."""
        g = self.geometry_topic.latest_value()
        return None if g is None else cast(contract.Geometry, g)

    def health(self) -> contract.Health:
        procs: list[contract.ProcessorHealth] = []
        for p in self.runner.processors:
            trig = p.trigger
            timing = p.stats.summary()
            procs.append({
                "name": p.name,
                "trigger": ("rate" if isinstance(trig, Every) else
                            f"topic:{trig.topic.name}" if isinstance(trig, OnTopic) else "source"),
                "configured_hz": trig.hz if isinstance(trig, Every) else None,
                "measured_hz": timing["measured_hz"], "tick_mean_ms": timing["tick_mean_ms"],
                "tick_p99_ms": timing["tick_p99_ms"],
                "overruns": p.stats.overruns,
                "runs": p.stats.rate.total,
                "errors": p.stats.errors,
                "last_error": p.stats.last_error,
            })
        topics: list[contract.TopicHealth] = [
            {"name": t.name, "size": len(t), "capacity": t.capacity, "seq": t.seq,
             "age_s": t.age_s()} for t in self.bus.topics()]
        streams: dict[str, Any] = {}
        vis = self.vision.counter.to_dict()
        # what the world model dropped, by the same reasons ("time out of range", ...)
        for reason, n in self.world.model.rejected.items():
            vis["errors_by_reason"][reason] = vis["errors_by_reason"].get(reason, 0) + n
            vis["errors"] += n
        streams["vision"] = vis
        streams["referee"] = self.referee.counter.to_dict()
        streams["zmq"] = self.ingest.counters["zmq"].to_dict()
        relay = None
        rs = self.relay_stats.latest_value()
        if rs is not None:
            age = time.monotonic() - rs["received_mono"]
            relay = {k: v for k, v in rs.items() if k not in ("streams", "received_mono")}
            relay["alive"] = age < 3.0
            relay["age_s"] = age
            for name, st in rs["streams"].items():
                streams[f"relay.{name}"] = st
        vision = streams.get("vision", {})
        # ok: the loop works (fresh vision, relay alive). A silent referee leaves it true: the
        # station then does what the rules expect of a team (it keeps obeying the last
        # command); it is a warning about a system outside the station, in `warnings`.
        ok = bool(vision) and 0 <= vision.get("last_age_s", -1) < 1.0 and \
            relay is not None and relay["alive"]
        world = self._world_health()
        if world is not None and world["stale"]:
            ok = False
        referee = self.referee_watch.status()
        if referee is not None:
            referee["source"] = ("internal" if referee["source_identifier"]
                                 == self.referee_state.source_identifier else "game-controller")
        out: contract.Health = {
            "ok": ok,
            "warnings": [*self._estop_warnings(), *_warnings(vision, relay, referee, world),
                         *self.params.warnings],
            "estop": self.estop_view(),
            "world": world,
            "referee": cast(contract.RefereeHealth | None, referee),
            "uptime_s": time.monotonic() - self.started_mono,
            "streams": streams,
            "processors": procs,
            "topics": topics,
            "relay": cast(contract.RelayHealth | None, relay),
            "latency": cast(contract.LatencyHealth, self.publisher.latency_summary()),
            "latency_stages": self._latency_stages(),
            "websocket_clients": self.ws_clients,
            "engine": self.engine_health(),
        }
        return out


def _warnings(vision: dict[str, Any], relay: dict[str, Any] | None,
              referee: dict[str, Any] | None,
              world: contract.WorldHealth | None = None) -> list[str]:
    """One line per problem: why ``ok`` is false, and a silent referee."""
    out: list[str] = []
    if world is not None:
        if world["stale"] and vision.get("last_age_s", -1) >= 0 \
                and vision.get("last_age_s", -1) < 1.0:
            # vision arrives but nothing of it reaches the world: say why
            since = ("no frame merged yet" if world["age_s"] is None
                     else f"world not updated for {world['age_s']:.1f} s")
            out.append(f"{since} although vision arrives: robots stopped "
                       f"({world['last_rejection'] or 'no detection frame merged'})")
        if world["recent_rejections"]:
            out.append("vision dropped by the world model in the last 10 s: "
                       + ", ".join(f"{k} {v}" for k, v in world["recent_rejections"].items()))
    age = vision.get("last_age_s", -1)
    if not vision or age < 0:
        out.append("no vision received")
    elif age >= 1.0:
        out.append(f"no vision for {age:.1f} s")
    if relay is None:
        out.append("no relay statistics received")
    elif not relay["alive"]:
        out.append(f"relay silent for {relay['age_s']:.1f} s")
    line = RefereeWatch.warning(referee)
    if line is not None:
        out.append(line)
    return out


def _stop_all_bytes() -> bytes:
    from sslpb import touchline_pb2 as tl

    return tl.RobotCommandSet(created_time_ns=time.time_ns(), stop_all=True).SerializeToString()


__all__ = ["Station"]
