"""The station's side of replay: opening a log (indexed in a child process, the loop goes on
meanwhile), feeding its records onto the ingest topics like the relay would, and restarting
the pipeline when time jumps. Commands run on the station thread."""

from __future__ import annotations

import asyncio
import logging
import time
from collections.abc import Callable
from typing import Any, TypeVar

from google.protobuf.message import DecodeError

from domain.teams import Team
from ssllog.format import TYPE_TL_COMMANDS, TYPE_TRACKER_2020
from sslpb import touchline_pb2 as tl

from .. import contract, topics
from ..bus import DataBus
from ..processors import ControlProcessor, FeedbackProcessor, PlayerFeed, WorldProcessor
from ..referee.watch import RefereeWatch
from .logs import LogFolders, index_log, open_indexed
from .player import PLAYED_TYPES, LogPlayer, LogSource, PlayerError

log = logging.getLogger("touchline.station")
T = TypeVar("T")

#: the relay's default --command-timeout (larcmacs_relay/config.py): a robot the log sent
#: nothing newer than this before the playhead was being sent zero by the relay
RECORDED_COMMAND_TTL_S = 0.100
_TEAMS: dict[int, Team] = {tl.TEAM_BLUE: "blue", tl.TEAM_YELLOW: "yellow"}
_ZERO = tl.RobotCommand()


class ReplayControl:
    """Owns the log player for the station: ``player`` (the pure player), ``feed`` (the
    processor that emits its records), ``open_log``, ``command`` (a player command that wakes
    the feed), ``recorded_tracked`` (the log's own estimate at the playhead, drawn beside
    today's), ``recorded_commands`` (the commands the log sent each robot, beside those
    computed now).

    It writes the log's datagrams onto the topics the relay ingest writes (``bus``) and, when
    time jumps, restarts what keeps state across frames: the world model, the feedback, the
    controllers and the referee's silence clock (``world``, ``feedback``, ``control``,
    ``referee_watch``). ``disarm``: a log attached disarms (back to live, robots are not
    driven by surprise); ``publish``: fresh views for the pages now."""

    def __init__(self, bus: DataBus, folders: LogFolders, *, world: WorldProcessor,
                 feedback: FeedbackProcessor, control: ControlProcessor,
                 referee_watch: RefereeWatch, disarm: Callable[[str], None],
                 publish: Callable[[], None]) -> None:
        self.folders = folders
        self.vision_packets = bus.of(topics.VISION_PACKETS)
        self.referee_packets = bus.of(topics.REFEREE_PACKETS)
        self.world_topic = bus.of(topics.WORLD)
        self.referee_topic = bus.of(topics.REFEREE)
        self.world = world
        self.feedback = feedback
        self.control = control
        self.referee_watch = referee_watch
        self.disarm = disarm
        self.publish = publish
        self.player = LogPlayer(emit=self._emit, reset=self._reset_pipeline)
        self.feed = PlayerFeed(self.player)
        self._opening: asyncio.Task[None] | None = None
        #: in replay, the newest tracked-vision record of the log (the live estimate)
        self.recorded_tracked = b""
        #: in replay, the newest command the log sent each robot and its log time (ns)
        self.recorded_commands: dict[tuple[Team, int], tuple[int, tl.RobotCommand]] = {}
        self._seq = 0

    @property
    def replaying(self) -> bool:
        return self.player.log is not None

    def _emit(self, rec: Any) -> None:
        """One record of the log onto the topics the relay ingest writes, as an envelope like
        the relay's (bytes unchanged, the recorded receive time)."""
        if rec.type not in PLAYED_TYPES:
            return
        if rec.type == TYPE_TRACKER_2020:  # the live estimate of the time: shown, not used
            self.recorded_tracked = rec.payload
            return
        if rec.type == TYPE_TL_COMMANDS:  # what the live station sent then: shown, not sent
            self._recorded_commands(rec.time_ns, rec.payload)
            return
        self._seq += 1
        vision = rec.type == 4
        env = tl.Envelope(stream=tl.STREAM_VISION if vision else tl.STREAM_REFEREE,
                          receive_time_ns=rec.time_ns, sequence=self._seq,
                          source="log", payload=rec.payload)
        (self.vision_packets if vision else self.referee_packets).write(env)

    def _recorded_commands(self, t_ns: int, payload: bytes) -> None:
        cs = tl.RobotCommandSet()
        try:
            cs.ParseFromString(payload)
        except DecodeError:
            return  # a damaged record: the commands before it stand until they expire
        if cs.stop_all:  # the e-stop or the way into replay: every robot zero
            for key in self.recorded_commands:
                self.recorded_commands[key] = (t_ns, _ZERO)
        for c in cs.commands:
            team = _TEAMS.get(c.team)
            if team is not None:
                self.recorded_commands[(team, c.id)] = (t_ns, c)

    def commands_view(self) -> list[contract.RecordedCommand]:
        """The recorded commands in force at the playhead (the relay would still repeat
        them): those not older than its command timeout."""
        now = self.player.delivered_ns()
        out: list[contract.RecordedCommand] = []
        for (team, rid), (t_ns, c) in sorted(self.recorded_commands.items()):
            age = (now - t_ns) / 1e9
            if age > RECORDED_COMMAND_TTL_S:
                continue
            out.append({"team": team, "id": rid,
                        "forward_mps": c.forward_mps, "left_mps": c.left_mps,
                        "angular_radps": c.angular_radps, "kick_speed_mps": c.kick_speed_mps,
                        "chip": c.chip, "dribbler_rpm": c.dribbler_rpm,
                        "age_s": max(0.0, age)})
        return out

    def _reset_pipeline(self) -> None:
        """Time jumped (a log opened or seeked, or back to live): the world model and the
        controllers start again."""
        replay = self.replaying
        self.world.reset()
        self.feedback.reset()
        self.world_topic.clear()  # no world of before the jump is shown or obeyed
        self.referee_topic.clear()  # the log's own referee is heard within 0.1 s
        self.control.motion.reset_all()
        # (vision is judged by what the feed delivered: one lagging the playhead is no loss)
        self.control.replay_clock = self.player.delivered_ns if replay else None
        # a referee is silent by the log's clock in replay (a paused replay is not silence)
        self.referee_watch.clock = (lambda: self.player.now_ns() / 1e9) if replay \
            else time.monotonic
        self.referee_watch.last_heard = None
        self.recorded_tracked = b""
        self.recorded_commands.clear()

    def command(self, fn: Callable[..., T], *args: Any) -> T:
        """A player command on the station thread; the feed is woken to act on it."""
        out = fn(*args)
        self.feed.wake.set()
        return out

    def view(self) -> contract.Player:
        return self.player.view()

    def open_log(self, path: str) -> contract.Player:
        """Opens a log from the page (on the station thread): only files of the recording
        folder and of the folders given with --log-dir (PlayerError otherwise). Returns at
        once; the player's loading progress and then the log come in the "player" messages."""
        return self._start_open(path, False)

    def open_checked(self, real_path: str) -> contract.Player:
        """Opens a log the station found in one of its own folders itself (an evaluation
        run's, in the reports folder), on the station thread: no further check of the
        path."""
        return self._start_open(real_path, True)

    def open_at_start(self, path: str) -> None:
        """``make run LOG=...``: the log instead of live input, from the start."""
        self._opening = asyncio.get_running_loop().create_task(self._open_log(path))

    def _start_open(self, path: str, checked: bool) -> contract.Player:
        if self._opening is not None and not self._opening.done():
            raise PlayerError(f"already opening {self.player.loading_path}: wait for it")
        real = path if checked else self.folders.check(path)
        self.player.error = ""
        self._opening = asyncio.get_running_loop().create_task(self._open_log(real))
        self.player.loading, self.player.loading_path = 0.0, real
        self.player.serial += 1
        self.publish()
        return self.player.view()

    async def _open_log(self, path: str) -> None:
        self.player.loading, self.player.loading_path = 0.0, path
        self.player.serial += 1
        last = [0.0]

        def progress(frac: float) -> None:  # from the indexing process, a step a time
            if frac - last[0] >= 0.02 or frac >= 1.0:
                if int(frac * 4) > int(last[0] * 4):  # the terminal too, every quarter
                    log.info("indexing %s: %.0f %%", path, frac * 100)
                last[0] = frac
                self._loading(frac)

        cache = self.folders.cache_dir()
        try:
            # the slow pass in a process of its own, then its result read in a thread
            await index_log(path, cache, progress)
            log_ = await asyncio.to_thread(open_indexed, path, cache)
        except Exception as exc:  # a bad file: said in the player, the station goes on
            self.player.loading = None
            self.player.error = f"cannot open {path}: {exc}"
            self.player.serial += 1
            log.warning("%s", self.player.error)
            self.publish()
            return
        self._attach(log_)

    def _loading(self, frac: float) -> None:
        if self.player.loading is not None:
            self.player.loading = frac
            self.player.serial += 1

    def _attach(self, log_: LogSource) -> None:
        self.disarm("replay")  # back to live, robots are not driven by surprise
        self.command(self.player.attach, log_)
        log.info("replaying %s (%.1f s): nothing is sent to robots or a simulator",
                 log_.path, self.player.duration_s())
        self.publish()

    def close(self) -> None:
        if self._opening is not None:
            self._opening.cancel()
        self.player.close()
