"""The composition root of the backend: bus, processors and ZeroMQ, started and stopped in
mirror order. The station thread is the only writer of station state: the API reads the
immutable ``views`` it publishes and changes state only through ``call`` (the command queue)."""

from __future__ import annotations

import asyncio
import concurrent.futures
import contextlib
import logging
import threading
import time
import uuid
from collections.abc import Callable
from typing import Any, TypeVar

import zmq
import zmq.asyncio

from sslnet.proc import CpuMeter

from . import stalldump, topics
from .bus import DataBus
from .config import Settings
from .engine.switch import EngineSwitch
from .evaluation import Evaluation
from .operators import Operators
from .params.model import PLAYS, StationParams
from .params.store import ParamStore, deep_merge, parse_setting
from .processor import Processor, Runner
from .processors import (
    CommandPublisher,
    ControlProcessor,
    FeedbackProcessor,
    InternalRefereeProcessor,
    RefereeIngest,
    RelayIngest,
    StrategyProcessor,
    TrackerPublisher,
    VisionIngest,
    WorldProcessor,
)
from .recording import RecordingControl, RecordingProcessor
from .referee.internal import InternalReferee
from .referee.watch import RefereeWatch
from .replay.control import ReplayControl
from .replay.logs import LogFolders
from .safety import Safety
from .startup import StartupTimeline, process_start_mono
from .station_loop import StationLoop, freeze_start_up
from .teamcode.plays import TeamPlays
from .teamcode.processors import TeamProcessors
from .teamcode.registry import TeamRegistry
from .teamcode.watcher import FolderWatcher
from .viewhub import ViewHub, ViewPublisher, Views, WebStats
from .views import BrowserData, ViewParts
from .zmqio import pub_socket, sub_socket

log = logging.getLogger("touchline.station")
T = TypeVar("T")


class Station:
    def __init__(self, settings: Settings, startup: StartupTimeline | None = None) -> None:
        self.settings = settings
        #: when each step of the start was done (health's ``startup``)
        self.startup = startup or StartupTimeline(process_start_mono())
        self.startup.restarted = settings.restarted
        #: set once the parts the first command does not need have been started
        #: (``start_late``): the web side starts after it (``python -m backend``)
        self.late_started = threading.Event()
        self._late_timer: asyncio.TimerHandle | None = None
        self.ctx: zmq.asyncio.Context | None = None
        #: the station thread and its event loop (the command queue)
        self.loop = StationLoop(self.start, self.stop, self._after_command)
        self.runner = Runner()
        self.started_mono = time.monotonic()
        self.cpu = CpuMeter()  # this process (every thread), for the Health tab
        #: the websocket clients and the access rule's refusals (counted by the web side)
        self.web = WebStats()
        #: who is connected, who drives which team, what each operator did (issue 12)
        self.operators = Operators()
        # the team's own code (issue 27): found now (read, never run here), watched from start
        self.team = TeamRegistry(settings.team_dir, PLAYS)
        self.team.rescan()
        self.team_watcher = FolderWatcher(settings.team_dir, self._team_folder_changed)
        self.team_plays = TeamPlays(self.team, settings.team_memory_mb)
        self.params = ParamStore(settings.state_dir)
        # a play is chosen among the built-in ones and the team folder's (known now)
        self.params.play_names = lambda: [*PLAYS, *sorted(self.team.plays())]
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
        # from here on changes come on the station thread; their file is written by a thread
        # of its own, in order (an fsync takes milliseconds: not on the control loop)
        self.params.writer = concurrent.futures.ThreadPoolExecutor(
            1, thread_name_prefix="params-writer")
        self.bus = DataBus(self.params.current.bus.sizes())
        # topics the API writes to
        self.operator_targets = self.bus.of(topics.OPERATOR_TARGETS)
        self.sim_commands = self.bus.of(topics.SIM_COMMANDS)
        # topics the web side's checks and the tests read and write
        self.world_topic = self.bus.of(topics.WORLD)
        self.geometry_topic = self.bus.of(topics.GEOMETRY)
        self.referee_topic = self.bus.of(topics.REFEREE)
        self.relay_stats = self.bus.of(topics.RELAY_STATS)
        self.params_topic = self.bus.of(topics.PARAMS)
        self.referee_state = InternalReferee()
        self.referee_watch = RefereeWatch()
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
        self.internal_referee = InternalRefereeProcessor(self.bus, self.referee_state)
        # the e-stop, the arming and the other-team rule (backend/safety.py): a persisted
        # stop is on the bus from the first tick on
        self.safety = Safety(
            self.bus, self.params, settings.state_dir, restarted=settings.restarted,
            require_arming=settings.require_arming, relay_output=settings.relay_output,
            replaying=lambda: self.replay.replaying, vision_age_s=self.control.vision_age_s)
        # their files are written on the parameters' writer thread, in order with them: the
        # press is on the bus at once and the control pass that stops every robot does not
        # wait for an fsync (behind the recorder's writes it can take tens of ms)
        self.safety.latch.writer = self.safety.arming_store.writer = self._persist
        self.publisher.adopt_estop = self.safety.adopt_relay_estop
        self.publisher.estop_by = self.safety.estop_by
        self.publisher.armed = self.safety.operator_armed
        self.publisher.armed_by = lambda: self.safety.armed_by
        self.control.internal = self.internal_referee
        self.control.silence = self.world.silence
        self.publisher.arrivals = self.world.arrivals
        self.control.may_drive_other_team = self.safety.drives_other_team
        # the internal referee switched off is not obeyed: its silence is no warning
        self.referee_watch.obeyed = lambda: self.control.active_referee() is not None
        self.strategy.referee_source = self.control.active_referee
        self.strategy.team = self.team_plays
        # the compute engine for the strategy (started and replaced in the background)
        self.engine = EngineSwitch(self.strategy, settings.scripts_dir)
        # the session recorder (made in start(): it opens a file; closed in stop())
        self.recording = RecordingControl(settings, self.params)
        # the log player: in replay the pipeline runs on the log's time and nothing is sent
        self.replay = ReplayControl(
            self.bus, LogFolders(self.recording.folder, settings.log_dirs), world=self.world,
            feedback=self.feedback, control=self.control, referee_watch=self.referee_watch,
            disarm=self.safety.disarm, publish=lambda: self.publish_views(force=True))
        self.ingest.live = lambda: not self.replay.replaying
        self.publisher.muted = lambda: self.replay.replaying
        # the world estimate as tracked vision: recorded, and sent to the relay (tracker-out)
        self.tracker = TrackerPublisher(self.bus, uuid.uuid4().hex)
        self.tracker.replaying = lambda: self.replay.replaying
        # the start's milestones (each hook is called once, then removed)
        self.world.on_world = self._first_frame
        self.strategy.on_first_targets = lambda: self.startup.mark("first targets")
        self.publisher.on_first_command = self._first_command
        self.strategy.replaying = lambda: self.replay.replaying
        # the team's processors (their topics team/<name>; the plays read them as topics)
        self.team_processors = TeamProcessors(self.bus, self.team, settings.team_memory_mb)
        self.team_processors.referee_source = self.control.active_referee
        self.team_processors.contacts = self.strategy.contacts
        self.team_processors.replaying = lambda: self.replay.replaying
        self.strategy.team_topics = lambda: self.team_processors.outputs
        stalls = stalldump.from_env()
        if stalls is not None:
            self.tracker.after_send = stalls.beat
        # the Evaluate tab's jobs: a pool of processes driven from a thread of its own
        self.evaluation = Evaluation(settings, self.params.diff_from_defaults,
                                     lambda: self.params.current, settings.eval_workers)
        # the browser's data (backend/views.py), built from the parts named here
        self.browser = BrowserData(ViewParts(
            params=self.params, bus=self.bus, runner=self.runner, safety=self.safety,
            ingest=self.ingest, vision=self.vision, referee=self.referee, world=self.world,
            feedback=self.feedback, strategy=self.strategy, control=self.control,
            publisher=self.publisher, internal_referee=self.internal_referee,
            referee_state=self.referee_state, referee_watch=self.referee_watch,
            team=self.team, team_processors=self.team_processors, engine=self.engine,
            replay=self.replay, recording=self.recording, operators=self.operators,
            startup=self.startup, web=self.web, cpu=self.cpu, state_dir=settings.state_dir,
            started_mono=self.started_mono, evaluation=self.evaluation))
        # what the web side reads, published at most at the rate a page can show
        self.hub = ViewHub(self.browser, self.replay.player)
        # in pipeline order: a topic-triggered processor runs in the pass of what wrote it
        self.processors: tuple[Processor, ...] = (
            self.replay.feed, self.ingest, self.vision, self.referee, self.world, self.feedback,
            self.strategy, self.control, self.internal_referee, self.publisher, self.tracker,
            self.team_processors, ViewPublisher(self.hub),
            RecordingProcessor(self.recording, self.bus, lambda: self.replay.replaying,
                               self.browser.health))

    # ---- the station thread (backend/station_loop.py): the web side changes station state
    # only through ``call`` (the command queue) and reads the published views ----

    def start_thread(self) -> None:
        self.loop.start_thread()

    def stop_thread(self) -> None:
        self.loop.stop_thread()

    def _persist(self, write: Callable[[], None]) -> None:
        """Runs a state file's ``write`` on the writer thread (in order); what it did not
        catch itself is logged, not lost."""
        writer = self.params.writer
        if writer is None:
            write()
            return

        def said(fut: concurrent.futures.Future[None]) -> None:
            exc = fut.exception()
            if exc is not None:
                log.error("a state file was not written: %s: %s", type(exc).__name__, exc)
        writer.submit(write).add_done_callback(said)

    async def call(self, fn: Callable[..., T], *args: Any) -> T:
        """Runs ``fn(*args)`` on the station loop; fresh views are published after it."""
        return await self.loop.call(fn, *args)

    async def read(self, fn: Callable[..., T], *args: Any) -> T:
        """Runs ``fn(*args)`` on the station loop for an answer that must be current."""
        return await self.loop.read(fn, *args)

    def call_sync(self, fn: Callable[..., T], *args: Any, timeout_s: float = 5.0) -> T:
        """``call`` for a thread without an event loop (tests, scripts)."""
        return self.loop.call_sync(fn, *args, timeout_s=timeout_s)

    def _after_command(self) -> None:
        if self.hub.listening:
            self.publish_views(force=True)

    async def start(self) -> None:
        """What the first command needs: the ZeroMQ sockets, the parameters applied and the
        processors running (the e-stop and the arming were loaded when the station was
        built). The rest (``start_late``) follows the first command set sent to the relay,
        or ``settings.late_start_max_s`` without one (no vision); at once with 0."""
        s = self.settings
        self.ctx = zmq.asyncio.Context()
        self.ingest.attach(sub_socket(self.ctx, s.relay_pub, [b"vision", b"referee", b"stats",
                                                                b"feedback"]))
        self.publisher.attach(pub_socket(self.ctx, s.relay_sub))
        prm = self.params.current
        self.tracker.attach(self.publisher.sock)  # the one socket to the relay's SUB
        self.apply_params(prm, self.params.version)
        # every change is made on the station thread (the routes submit it): applied at once
        self.params.subscribe(self._apply_params_soon)
        for p in self.processors:
            self.runner.add(p)
        await self.runner.start()
        # the emergency stop is never held behind the rest of a burst of camera frames
        self.runner.end_hold_on(self.bus.of(topics.ESTOP))
        self.team_watcher.start(self.team_watcher_listing())
        if s.log is not None:  # make run LOG=...: the log instead of live input
            self.replay.open_at_start(str(s.log))
        self.publish_views(force=True)
        self.startup.mark("station running")
        if s.freeze_gc:
            freeze_start_up(asyncio.get_running_loop())
        log.info("station started: relay pub %s, relay sub %s, our team %s, parameters v%d",
                 s.relay_pub, s.relay_sub, prm.team.our_team, self.params.version)
        if s.late_start_max_s <= 0 or self.startup.done("first command"):
            self.start_late()
        else:
            self._late_timer = asyncio.get_running_loop().call_later(
                s.late_start_max_s, self.start_late)

    def _first_frame(self, _world: object) -> None:
        self.world.on_world = _no_world_hook
        self.startup.mark("first frame")

    def _first_command(self) -> None:
        """The first command set for robots went to the relay: the rest starts now (after
        this pass: the pass that sent it is not delayed by it)."""
        self.startup.mark("first command")
        if self.loop.loop is not None:
            self.loop.loop.call_soon(self.start_late)

    def start_late(self) -> None:
        """On the station loop, once: what the first command does not need. The session
        recorder opens its file (what came before is not in it), the compute engine starts
        (the strategy uses the built-in code until it runs), and the web side may start."""
        if self.late_started.is_set():
            return
        if self._late_timer is not None:
            self._late_timer.cancel()
            self._late_timer = None
        prm = self.params.current
        rec = self.recording.open(prm)
        self.ingest.record = self.publisher.record = self.tracker.record = rec.record
        self.team_processors.record = rec.record
        self.recording.configure(prm, self.params.version)  # the parameters, recorded
        self.startup.mark("recorder open")
        self.engine.started = lambda: self.startup.mark("engine started")
        self.engine.configure(prm.strategy)
        self.late_started.set()

    def apply_params(self, p: StationParams, version: int) -> None:
        """Applies a validated parameter set to every part at once (between two ticks: the
        event loop runs one thing at a time), then tells the clients."""
        for proc in self.processors:
            proc.configure(p)
        if self.late_started.is_set():  # else start_late starts them with these parameters
            self.engine.configure(p.strategy)
            self.recording.configure(p, version)
        self.referee_state.blue_team_on_positive_half = (
            (p.team.our_team == "blue") == (p.team.our_side == "positive-x"))
        sized = {s.name: s for s in topics.ALL}
        for name, size in p.bus.sizes().items():
            self.bus.of(sized[name]).resize(size)
        self.params_topic.write(version)
        self.hub.notify()

    def _apply_params_soon(self, p: StationParams, version: int) -> None:
        self.loop.schedule(self.apply_params, p, version)

    # ---- operator actions: the page's list (backend/operators.py) and the session log
    # (backend/recording.py) ----

    def operator_action(self, action: str, by: str = "",
                        details: dict[str, Any] | None = None) -> None:
        """Records an operator's action (target, e-stop, play, referee, teleport, arming,
        driving) in the session log and in the page's list, with who and when."""
        self.operators.record(action, by, details)
        self.recording.operator_action(action, by, details)

    # ---- the team folder (backend/teamcode): a save is seen by the watcher's thread and
    # handled here, on the station loop ----

    def team_watcher_listing(self) -> dict[str, Any]:
        return {f.name: f.stat for f in self.team.found.values()}

    def _team_folder_changed(self, listing: dict[str, Any]) -> None:
        self.loop.schedule(self.team.rescan, listing)

    def team_rescan(self) -> set[str]:
        """Looks at the team folder at once (after a save from the page)."""
        return self.team.rescan()

    async def stop(self) -> None:
        if self._late_timer is not None:
            self._late_timer.cancel()
            self._late_timer = None
        self.team_watcher.stop()
        self.replay.close()
        await asyncio.to_thread(self.evaluation.close)
        # a last stop to every robot we drive, then shut down
        if self.ctx is not None and self.publisher.attached:
            with contextlib.suppress(zmq.ZMQError):
                await self.publisher.sock.send_multipart([b"commands", _stop_all_bytes()])
        await self.runner.stop()
        await self.team_plays.close()
        await self.engine.close()
        if self.ctx is not None:
            self.ctx.destroy(linger=0)
            self.ctx = None
        rec = self.recording.recorder
        if rec is not None:  # what is queued is written, the file gets its index
            await asyncio.to_thread(rec.close)
        if self.params.writer is not None:  # the last parameter change, e-stop and arming on disk
            await asyncio.wrap_future(self.params.writer.submit(lambda: None))

    # ---- the views the web side reads (backend/viewhub.py) ----

    @property
    def views(self) -> Views:
        return self.hub.views

    def publish_views(self, force: bool = False) -> None:
        """Builds what changed of the web side's views and tells the websocket clients."""
        self.hub.publish(force)

    def subscribe_views(self, listener: Callable[[], None]) -> Callable[[], None]:
        return self.hub.subscribe(listener)


def _no_world_hook(_world: object) -> None:
    pass


def _stop_all_bytes() -> bytes:
    from sslpb import touchline_pb2 as tl

    return tl.RobotCommandSet(created_time_ns=time.time_ns(), stop_all=True).SerializeToString()


__all__ = ["Station"]
