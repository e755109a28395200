"""The composition root of the backend: bus, processors and ZeroMQ, started and stopped in
mirror order. The station thread is the only writer of station state: the API reads the
immutable ``views`` it publishes and changes state only through ``call`` (the command queue)."""

from __future__ import annotations

import asyncio
import concurrent.futures
import contextlib
import logging
import sys
import threading
import time
import uuid
from collections.abc import Callable
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any, TypeVar, cast

import zmq
import zmq.asyncio

from ssllog.format import TYPE_TL_ACTION, TYPE_TL_HEALTH, TYPE_TL_PARAMS, TYPE_TRACKER_2020
from sslnet.proc import CpuMeter
from sslpb import ssl_gc_common_pb2
from sslpb.ssl_simulation_control_pb2 import SimulatorCommand

from . import contract, topics, views
from .bus import DataBus
from .config import ROOT, Settings
from .control.goto import Target
from .engine import NumpyEngine, OctaveEngine, PoolEngine
from .estop import EstopLatch
from .jsonsafe import dumps
from .messages import OperatorTarget
from .operators import Operators
from .params.model import StationParams, StrategyParams
from .params.store import ParamStore, deep_merge, diff, parse_setting
from .processor import Every, Processor, Runner
from .processors import (
    CommandPublisher,
    ControlProcessor,
    FeedbackProcessor,
    InternalRefereeProcessor,
    PlayerFeed,
    RefereeIngest,
    RelayIngest,
    StrategyProcessor,
    TrackerPublisher,
    VisionIngest,
    WorldProcessor,
)
from .recorder import SessionRecorder
from .referee.internal import InternalReferee
from .referee.watch import RefereeWatch
from .replay.logs import LogFolders, open_log_file
from .replay.player import PLAYED_TYPES, LogPlayer, LogSource, PlayerError
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
    player: contract.Player | None = None
    player_json: str = ""
    player_serial: int = -1
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


class RecordingProcessor(Processor):
    """What the recorder takes besides datagrams and commands: the station's health once a
    second, and the game stage (a new file per stage)."""

    name = "recording"

    def __init__(self, station: Station) -> None:
        super().__init__(Every(10.0))
        self.station = station
        self._next_health = 0.0

    async def tick(self) -> None:
        st = self.station
        rec = st.recorder
        if rec is None or st.player.log is not None:
            return
        ref = st.referee_topic.latest_value()
        if ref is not None and ref.stage:
            rec.stage(ref.stage)
        now = time.monotonic()
        if now >= self._next_health:
            self._next_health = now + 1.0
            rec.record(time.time_ns(), TYPE_TL_HEALTH,
                       dumps(st.health(), "health").encode())


class Station:
    def __init__(self, settings: Settings) -> None:
        self.settings = settings
        self.ctx: zmq.asyncio.Context | None = None
        self._loop: asyncio.AbstractEventLoop | None = None
        self._thread: threading.Thread | None = None
        self._stop_event: asyncio.Event | None = None
        self.runner = Runner()
        self.started_mono = time.monotonic()
        self.cpu = CpuMeter()  # this process (every thread), for the Health tab
        self.ws_clients = 0
        self.ws_dropped = 0  # websocket clients dropped for taking nothing (stalled)
        #: who is connected, who drives which team, what each operator did (issue 12)
        self.operators = Operators()
        #: who may do what and the refusals so far (the app sets it from its AccessRule)
        self.access_health: Callable[[], contract.AccessHealth] = lambda: {
            "token_required": False, "view_token": False, "estop_for_all": False,
            "refused": {}, "blocked_clients": 0}
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
        #: arming (a relay with --require-arming): the station starts disarmed, never persisted
        self._armed = False
        self.armed_by = ""
        self.armed_since = 0.0  # Unix s of the last arm or disarm (0: never)
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
        self.feedback = FeedbackProcessor(self.bus)
        self.strategy = StrategyProcessor(self.bus, prm.team.our_team, prm.strategy)
        self.control = ControlProcessor(self.bus, prm.processors.control_max_wait_s,
                                        prm.safety.vision_stale_s)
        self.publisher = CommandPublisher(self.bus)
        self.publisher.adopt_estop = self.adopt_relay_estop
        self.publisher.estop_by = lambda: self.estop_latch.state.by
        self.publisher.armed = lambda: self._armed
        self.publisher.armed_by = lambda: self.armed_by
        self.internal_referee = InternalRefereeProcessor(self.bus, self.referee_state)
        self.control.internal = self.internal_referee
        self.control.may_drive_other_team = self.drives_other_team
        # the internal referee switched off is not obeyed: its silence is no warning
        self.referee_watch.obeyed = lambda: self.control.active_referee() is not None
        self.strategy.referee_source = self.control.active_referee
        # the log player: in replay the pipeline runs on the log's time and nothing is sent
        self.player = LogPlayer(emit=self._emit_replayed, reset=self._reset_pipeline)
        self.player_feed = PlayerFeed(self.player)
        self.log_folders = LogFolders(self._recording_folder, settings.log_dirs)
        self._opening: asyncio.Task[None] | None = None
        #: in replay, the newest tracked-vision record of the log (the live estimate)
        self.recorded_tracked = b""
        self._replay_seq = 0
        self.ingest.live = lambda: self.player.log is None
        self.publisher.muted = lambda: self.player.log is not None
        # the session recorder: made in start() (it opens a file), closed in stop()
        self.recorder: SessionRecorder | None = None
        # the world estimate as tracked vision: recorded, and sent to the relay (tracker-out)
        self.tracker = TrackerPublisher(self.bus, uuid.uuid4().hex)
        self.tracker.replaying = lambda: self.player.log is not None
        self._params_recorded: dict[str, Any] | None = None
        self.views = Views()
        self._view_listeners: set[Callable[[], None]] = set()
        self.processors: tuple[Processor, ...] = (
            self.player_feed, self.ingest, self.vision, self.referee, self.world, self.feedback,
            self.strategy, self.control, self.internal_referee, self.publisher, self.tracker,
            ViewPublisher(self),
            RecordingProcessor(self))

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
        self.ingest.attach(sub_socket(self.ctx, s.relay_pub, [b"vision", b"referee", b"stats",
                                                                b"feedback"]))
        self.publisher.attach(pub_socket(self.ctx, s.relay_sub))
        prm = self.params.current
        rp = prm.recording
        self.recorder = SessionRecorder(
            self._recording_folder(), enabled=self._record_wanted(prm),
            max_bytes=rp.max_mb << 20, rotate_on_stage=rp.rotate_on_stage,
            our_team=prm.team.our_team)
        self.ingest.record = self.recorder.record
        self.publisher.record = self.recorder.record
        self.tracker.attach(self.publisher.sock)  # the one socket to the relay's SUB
        self.tracker.record = self.recorder.record
        self.apply_params(prm, self.params.version)
        # the store validates and persists in the web thread; the station applies on its loop
        self.params.subscribe(self._apply_params_soon)
        for p in self.processors:
            self.runner.add(p)
        await self.runner.start()
        if s.log is not None:  # make run LOG=...: the log instead of live input
            self._opening = asyncio.get_running_loop().create_task(
                self._open_log(str(s.log), checked=True))
        self.publish_views(force=True)
        log.info("station started: relay pub %s, relay sub %s, our team %s, parameters v%d",
                 s.relay_pub, s.relay_sub, prm.team.our_team, self.params.version)

    def apply_params(self, p: StationParams, version: int) -> None:
        """Applies a validated parameter set to every part at once (between two ticks: the
        event loop runs one thing at a time), then tells the clients."""
        for proc in self.processors:
            proc.configure(p)
        self._configure_engine(p.strategy)
        self._configure_recorder(p, version)
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

    # ---- the log player (commands run on the station thread; opening indexes in a worker
    # thread, the loop goes on meanwhile) ----

    def _recording_folder(self) -> Path:
        if self.settings.record_dir is not None:
            return self.settings.record_dir
        folder = self.params.current.recording.folder
        if folder:
            return Path(folder).expanduser()
        return (self.settings.state_dir or ROOT / "var") / "logs"

    def _emit_replayed(self, rec: Any) -> None:
        """One record of the log onto the topics the relay ingest writes, as an envelope like
        the relay's (bytes unchanged, the recorded receive time)."""
        if rec.type not in PLAYED_TYPES:
            return
        if rec.type == TYPE_TRACKER_2020:  # the live estimate of the time: shown, not used
            self.recorded_tracked = rec.payload
            return
        from sslpb import touchline_pb2 as tl
        self._replay_seq += 1
        vision = rec.type == 4
        env = tl.Envelope(stream=tl.STREAM_VISION if vision else tl.STREAM_REFEREE,
                          receive_time_ns=rec.time_ns, sequence=self._replay_seq,
                          source="log", payload=rec.payload)
        (self.ingest.vision_packets if vision else self.ingest.referee_packets).write(env)

    def _reset_pipeline(self) -> None:
        """Time jumped (a log opened or seeked, or back to live): the world model and the
        controllers start again."""
        replay = self.player.log is not None
        self.world.reset()
        self.feedback.reset()
        self.world_topic.clear()  # no world of before the jump is shown or obeyed
        self.referee_topic.clear()  # the log's own referee is heard within 0.1 s
        self.control.motion.reset_all()
        self.control.replay_clock = self.player.now_ns if replay else None
        # a referee is silent by the log's clock in replay (a paused replay is not silence)
        self.referee_watch.clock = (lambda: self.player.now_ns() / 1e9) if replay \
            else time.monotonic
        self.referee_watch.last_heard = None
        self.recorded_tracked = b""

    def player_command(self, fn: Callable[..., T], *args: Any) -> T:
        """A player command on the station thread; the feed is woken to act on it."""
        out = fn(*args)
        self.player_feed.wake.set()
        return out

    def player_view(self) -> contract.Player:
        return self.player.view()

    async def open_log(self, path: str) -> contract.Player:
        """Opens a log from the page: only files of the recording folder and of the folders
        given with --log-dir (PlayerError otherwise). Returns at once; the player's loading
        progress and then the log come in the "player" messages."""
        return await self.read(self._start_open, path, False)

    def _start_open(self, path: str, checked: bool) -> contract.Player:
        if self._opening is not None and not self._opening.done():
            raise PlayerError(f"already opening {self.player.loading_path}: wait for it")
        real = path if checked else self.log_folders.check(path)
        self.player.error = ""
        self._opening = asyncio.get_running_loop().create_task(self._open_log(real, True))
        self.player.loading, self.player.loading_path = 0.0, real
        self.player.serial += 1
        self.publish_views(force=True)
        return self.player.view()

    async def _open_log(self, path: str, checked: bool) -> None:
        loop = asyncio.get_running_loop()
        self.player.loading, self.player.loading_path = 0.0, path
        self.player.serial += 1
        last = [0.0]

        def progress(frac: float) -> None:  # in the worker thread: hand over, a step a time
            if frac - last[0] >= 0.02 or frac >= 1.0:
                if int(frac * 4) > int(last[0] * 4):  # the terminal too, every quarter
                    log.info("indexing %s: %.0f %%", path, frac * 100)
                last[0] = frac
                loop.call_soon_threadsafe(self._loading, frac)

        try:
            log_ = await asyncio.to_thread(open_log_file, path, self.log_folders.cache_dir(),
                                           progress)
        except Exception as exc:  # a bad file: said in the player, the station goes on
            self.player.loading = None
            self.player.error = f"cannot open {path}: {exc}"
            self.player.serial += 1
            log.warning("%s", self.player.error)
            self.publish_views(force=True)
            return
        self._attach(log_)

    def _loading(self, frac: float) -> None:
        if self.player.loading is not None:
            self.player.loading = frac
            self.player.serial += 1

    def _attach(self, log_: LogSource) -> None:
        self.disarm("replay")  # back to live, robots are not driven by surprise
        self.player_command(self.player.attach, log_)
        log.info("replaying %s (%.1f s): nothing is sent to robots or a simulator",
                 log_.path, self.player.duration_s())
        self.publish_views(force=True)

    # ---- the session recorder ----

    def _record_wanted(self, p: StationParams) -> bool:
        """Records live sessions unless told not to (the parameter, --no-record), when
        replaying from the command line, or for a station that keeps no state (tests)."""
        return (p.recording.enabled and self.settings.record and self.settings.log is None
                and (self.settings.state_dir is not None or bool(p.recording.folder)
                     or self.settings.record_dir is not None))

    def _configure_recorder(self, p: StationParams, version: int) -> None:
        rec = self.recorder
        if rec is None:
            return
        rec.max_bytes = p.recording.max_mb << 20
        rec.rotate_on_stage = p.recording.rotate_on_stage
        rec.our_team = p.team.our_team
        folder = self._recording_folder()
        if folder != Path(rec.status()["folder"]):
            rec.set_folder(folder)
        rec.set_enabled(self._record_wanted(p))
        values = p.model_dump(mode="json")
        changes = values if self._params_recorded is None else \
            diff(self._params_recorded, values)
        self._params_recorded = values
        if changes:
            rec.record(time.time_ns(), TYPE_TL_PARAMS, dumps(
                {"version": version, "changes": changes, "by": ""}, "params").encode())

    def operator_action(self, action: str, by: str = "",
                        details: dict[str, Any] | None = None) -> None:
        """Records an operator's action (target, e-stop, play, referee, teleport, arming,
        driving) in the session log and in the page's list, with who and when."""
        self.operators.record(action, by, details)
        if self.recorder is not None:
            body = {"action": action, "by": by, "time_unix": time.time(), **(details or {})}
            self.recorder.record(time.time_ns(), TYPE_TL_ACTION,
                                 dumps(body, "action").encode())

    def recorder_command(self, action: str) -> contract.Recording:
        """The page's recording buttons: a new file now, or recording on/off (the parameter,
        persisted, so the next start does the same)."""
        if action == "new-file":
            if self.recorder is None or not self.recorder.status()["recording"]:
                raise ValueError("not recording: start recording first")
            self.recorder.new_file("operator")
        else:
            self.params.patch({"recording": {"enabled": action == "start"}})
        return self.recording_status()

    async def stop(self) -> None:
        if self._opening is not None:
            self._opening.cancel()
        self.player.close()
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
        if self.recorder is not None:  # what is queued is written, the file gets its index
            await asyncio.to_thread(self.recorder.close)

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
        if active:
            self.disarm(f"e-stop ({by or '?'})")

    # ---- arming: a relay driving real robots or an external simulator sends nothing but
    # stops until an operator arms it (CommandPublisher repeats the state to the relay) ----

    @property
    def arming_required(self) -> bool:
        """The launcher said so (--require-arming) or the relay's stats do."""
        rs = self.relay_stats.latest_value()
        return self.settings.require_arming or (rs is not None
                                                and bool(rs.get("arming_required")))

    @property
    def armed(self) -> bool:
        """Commands may reach the robots: armed by an operator, or no arming required."""
        return self._armed or not self.arming_required

    def arm_refusal(self) -> str | None:
        """Why arming is refused now, or None."""
        if self.estop:
            return "the emergency stop is active: release it first"
        if self.player.log is not None:
            return "replaying a log: nothing is sent to robots (go back to live first)"
        age = self.control.vision_age_s(time.monotonic())
        stale = self.params.current.safety.vision_stale_s
        if age > stale:
            seen = "no vision yet" if age == float("inf") else f"no vision for {age:.1f} s"
            return f"vision is missing ({seen}, more than safety.vision_stale_s = {stale} s)"
        return None

    def set_armed(self, armed: bool, by: str = "") -> str | None:
        """Arm (refused with the reason, see ``arm_refusal``) or disarm (always)."""
        if not armed:
            self.disarm(by)
            return None
        why = self.arm_refusal()
        if why is not None:
            return why
        if not self._armed:
            log.warning("ARMED by %s: commands go to the robots", by or "?")
            self._armed, self.armed_by, self.armed_since = True, by, time.time()
        return None

    def disarm(self, by: str = "") -> None:
        if self._armed:
            log.warning("disarmed by %s: only stops go to the robots", by or "?")
            self._armed, self.armed_by, self.armed_since = False, by, time.time()

    def adopt_relay_estop(self, by: str) -> None:
        """The relay is latched although this backend is not (its file was lost, or another
        backend pressed it): the stop is the relay's, and the station says so."""
        if not self.estop:
            log.warning("the relay's emergency stop is latched (by %s): active here too", by)
            self.set_estop(True, f"relay latch ({by or '?'})")

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

    # ---- the browser's data: built by backend/views.py (on the station thread) ----

    def world_dict(self) -> contract.World:
        return views.world(self)

    def health(self) -> contract.Health:
        return views.health(self)

    def referee_view(self) -> contract.RefereeView:
        return views.referee_view(self)

    def strategy_state(self) -> contract.StrategyState:
        return views.strategy_state(self)

    def strategy_view(self) -> contract.StrategyView:
        return views.strategy_view(self)

    def estop_view(self) -> contract.EstopInfo:
        return views.estop_view(self)

    def arming_view(self) -> contract.ArmingInfo:
        return views.arming_view(self)

    def recording_status(self) -> contract.Recording:
        if self.recorder is None:
            return {"enabled": False, "recording": False, "file": "",
                    "folder": str(self._recording_folder()), "size_bytes": 0,
                    "duration_s": 0.0, "records": 0, "dropped": 0, "error": ""}
        s = self.recorder.status()
        return {"enabled": bool(s["enabled"]), "recording": bool(s["recording"]),
                "file": str(s["file"]), "folder": str(s["folder"]),
                "size_bytes": int(s["size_bytes"]), "duration_s": float(s["duration_s"]),
                "records": int(s["records"]), "dropped": int(s["dropped"]),
                "error": str(s["error"] or "")}

    def world_version(self) -> tuple[object, ...]:
        """Changes whenever the world message would: a new world, a referee message, the
        e-stop, why the robots are stopped (that changes while no world is written: vision
        lost), or the internal referee (its panel follows the world message)."""
        ir, rs = self.internal_referee, self.referee_state
        return (self.world_topic.seq, self.referee_topic.seq, self.estop, self.player.serial,
                self.armed, self.arming_required,
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
        if force or self.player.serial != v.player_serial:
            changes.update(player=self.player.view(), player_serial=self.player.serial,
                           player_json=self.player.json())
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



def _stop_all_bytes() -> bytes:
    from sslpb import touchline_pb2 as tl

    return tl.RobotCommandSet(created_time_ns=time.time_ns(), stop_all=True).SerializeToString()


__all__ = ["Station"]
