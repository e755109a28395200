"""The composition root of the backend: bus, processors and ZeroMQ, started and stopped in
mirror order. The station thread is the only writer of station state: the API reads the
immutable ``views`` it publishes and changes state only through ``call`` (the command queue)."""

from __future__ import annotations

import asyncio
import contextlib
import logging
import threading
import time
import uuid
from collections.abc import Callable
from typing import Any, TypeVar, cast

import zmq
import zmq.asyncio

from domain.wallclock import clock
from sslnet.proc import CpuMeter
from sslpb import ssl_gc_common_pb2
from sslpb.ssl_simulation_control_pb2 import SimulatorCommand

from . import contract, stalldump, topics, views
from .arming import ArmingStore
from .bus import DataBus
from .config import Settings
from .control.goto import Target
from .engine.switch import EngineSwitch
from .estop import EstopLatch
from .evaluation import Evaluation
from .jsonsafe import dumps
from .messages import OperatorTarget
from .operators import Operators
from .params.model import PLAYS, StationParams
from .params.store import ParamStore, deep_merge, parse_setting
from .processor import Processor, Runner
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
from .recording import RecordingControl, RecordingProcessor
from .referee.internal import InternalReferee
from .referee.watch import RefereeWatch
from .replay.control import ReplayControl
from .replay.logs import LogFolders
from .replay.player import LogPlayer
from .startup import StartupTimeline, process_start_mono
from .station_loop import StationLoop, freeze_start_up
from .teamcode.plays import TeamPlays
from .teamcode.processors import TeamProcessors
from .teamcode.registry import TeamRegistry
from .teamcode.watcher import FolderWatcher
from .viewhub import ViewHub, ViewPublisher, Views
from .world.state import Team
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
        self.ws_clients = 0
        self.ws_dropped = 0  # websocket clients dropped for taking nothing (stalled)
        #: who is connected, who drives which team, what each operator did (issue 12)
        self.operators = Operators()
        #: who may do what and the refusals so far (the app sets it from its AccessRule)
        self.access_health: Callable[[], contract.AccessHealth] = lambda: {
            "token_required": False, "view_token": False, "estop_for_all": False,
            "refused": {}, "blocked_clients": 0}
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
        #: arming (a relay with --require-arming): the operator's, persisted; a start
        #: disarmed, a restart by the supervisor as the operator left it (backend/arming.py)
        self.arming_store = ArmingStore(settings.state_dir, settings.restarted)
        armed = self.arming_store.state
        if armed.armed and self.estop_latch.active:  # the stop wins: disarmed
            armed = self.arming_store.set(False, "e-stop active at start")
        self._armed = armed.armed
        self.armed_by = armed.by
        self.armed_since = armed.since  # Unix s of the last arm or disarm (0: never)
        if self.arming_store.restored and self._armed:
            log.warning("restarted after a crash: ARMED as the operator left it (by %s at %s)",
                        armed.by or "?", clock(armed.since))
        self.sim_commands = self.bus.of(topics.SIM_COMMANDS)
        self.world_topic = self.bus.of(topics.WORLD)
        self.geometry_topic = self.bus.of(topics.GEOMETRY)
        self.referee_topic = self.bus.of(topics.REFEREE)
        self.targets_topic = self.bus.of(topics.TARGETS)
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
        self.publisher.adopt_estop = self.adopt_relay_estop
        self.publisher.estop_by = lambda: self.estop_latch.state.by
        self.publisher.armed = lambda: self._armed
        self.publisher.armed_by = lambda: self.armed_by
        self.internal_referee = InternalRefereeProcessor(self.bus, self.referee_state)
        self.control.internal = self.internal_referee
        self.control.silence = self.world.silence
        self.control.may_drive_other_team = self.drives_other_team
        # the internal referee switched off is not obeyed: its silence is no warning
        self.referee_watch.obeyed = lambda: self.control.active_referee() is not None
        self.strategy.referee_source = self.control.active_referee
        self.strategy.team = self.team_plays
        # the compute engine for the strategy (started and replaced in the background)
        self.engine = EngineSwitch(self.strategy, settings.scripts_dir)
        # the session recorder (made in start(): it opens a file; closed in stop())
        self.recording = RecordingControl(self)
        # the log player: in replay the pipeline runs on the log's time and nothing is sent
        self.replay = ReplayControl(self, LogFolders(self.recording.folder, settings.log_dirs))
        self.player_feed = PlayerFeed(self.player)
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
        # what the web side reads, published at most at the rate a page can show
        self.hub = ViewHub(self)
        # in pipeline order: a topic-triggered processor runs in the pass of what wrote it
        self.processors: tuple[Processor, ...] = (
            self.player_feed, self.ingest, self.vision, self.referee, self.world, self.feedback,
            self.strategy, self.control, self.internal_referee, self.publisher, self.tracker,
            self.team_processors, ViewPublisher(self.hub),
            RecordingProcessor(self))

    # ---- the station thread (backend/station_loop.py): the web side changes station state
    # only through ``call`` (the command queue) and reads the published views ----

    def start_thread(self) -> None:
        self.loop.start_thread()

    def stop_thread(self) -> None:
        self.loop.stop_thread()

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
        # the store validates and persists in the web thread; the station applies on its loop
        self.params.subscribe(self._apply_params_soon)
        for p in self.processors:
            self.runner.add(p)
        await self.runner.start()
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

    # ---- replay (backend/replay/control.py) and the recorder (backend/recording.py) ----

    @property
    def player(self) -> LogPlayer:
        return self.replay.player

    @property
    def log_folders(self) -> LogFolders:
        return self.replay.folders

    @property
    def recorded_tracked(self) -> bytes:
        return self.replay.recorded_tracked

    def player_command(self, fn: Callable[..., T], *args: Any) -> T:
        return self.replay.command(fn, *args)

    def player_view(self) -> contract.Player:
        return self.replay.view()

    async def open_log(self, path: str) -> contract.Player:
        return await self.replay.open_log(path)

    async def open_evaluation_log(self, report: str, run: str) -> contract.Player:
        """A run's log from the Evaluate tab (by names; the evaluation finds it in the
        reports folder) in the player."""
        real = await asyncio.to_thread(self.evaluation.run_log, report, run)
        return await self.replay.open_checked(real)

    @property
    def recorder(self) -> SessionRecorder | None:
        return self.recording.recorder

    def operator_action(self, action: str, by: str = "",
                        details: dict[str, Any] | None = None) -> None:
        """Records an operator's action (target, e-stop, play, referee, teleport, arming,
        driving) in the session log and in the page's list, with who and when."""
        self.operators.record(action, by, details)
        self.recording.operator_action(action, by, details)

    def recorder_command(self, action: str) -> contract.Recording:
        return self.recording.command(action)

    def recording_status(self) -> contract.Recording:
        return self.recording.status()

    @property
    def engine_error(self) -> str:
        return self.engine.error

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
        """The control loop may command the other team (a simulator, and the operator said).
        Asked in every control tick: the operator's switch first (off: no refusal message
        is built), then ``other_team_refusal``."""
        if not self.params.current.safety.other_team_in_simulator:
            return False
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
            state = self.arming_store.set(True, by)
            self._armed, self.armed_by, self.armed_since = True, by, state.since
        return None

    def disarm(self, by: str = "") -> None:
        if self._armed:
            log.warning("disarmed by %s: only stops go to the robots", by or "?")
            state = self.arming_store.set(False, by)
            self._armed, self.armed_by, self.armed_since = False, by, state.since

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

    @property
    def views(self) -> Views:
        return self.hub.views

    def world_version(self) -> tuple[object, ...]:
        return self.hub.world_version()

    def world_json(self) -> str:
        """The world message as JSON (what every websocket client gets)."""
        return dumps({"type": "world", "world": self.world_dict()}, "world")

    def publish_views(self, force: bool = False) -> None:
        """Builds what changed of the web side's views and tells the websocket clients."""
        self.hub.publish(force)

    def subscribe_views(self, listener: Callable[[], None]) -> Callable[[], None]:
        return self.hub.subscribe(listener)

    def geometry(self) -> contract.Geometry | None:
        """The field as decoded (cleaned at decode time; non-finite numbers, should any get
        through, become null here rather than break the JSON)."""
        g = self.geometry_topic.latest_value()
        return None if g is None else cast(contract.Geometry, g)



def _no_world_hook(_world: object) -> None:
    pass


def _stop_all_bytes() -> bytes:
    from sslpb import touchline_pb2 as tl

    return tl.RobotCommandSet(created_time_ns=time.time_ns(), stop_all=True).SerializeToString()


__all__ = ["Station"]
