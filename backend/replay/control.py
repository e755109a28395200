"""The station's side of replay: opening a log (indexed in a child process, the loop goes on
meanwhile), feeding its records onto the ingest topics like the relay would, and restarting
the pipeline when time jumps. Commands run on the station thread."""

from __future__ import annotations

import asyncio
import logging
import time
from collections.abc import Callable
from typing import TYPE_CHECKING, Any, TypeVar

from ssllog.format import TYPE_TRACKER_2020
from sslpb import touchline_pb2 as tl

from .. import contract
from .logs import LogFolders, index_log, open_indexed
from .player import PLAYED_TYPES, LogPlayer, LogSource, PlayerError

if TYPE_CHECKING:
    from ..station import Station

log = logging.getLogger("touchline.station")
T = TypeVar("T")


class ReplayControl:
    """Owns the log player for the station: ``player`` (the pure player), ``open_log``,
    ``command`` (a player command that wakes the feed), ``recorded_tracked`` (the log's own
    estimate at the playhead, drawn beside today's)."""

    def __init__(self, station: Station, folders: LogFolders) -> None:
        self.station = station
        self.folders = folders
        self.player = LogPlayer(emit=self._emit, reset=self._reset_pipeline)
        self._opening: asyncio.Task[None] | None = None
        #: in replay, the newest tracked-vision record of the log (the live estimate)
        self.recorded_tracked = b""
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
        self._seq += 1
        vision = rec.type == 4
        env = tl.Envelope(stream=tl.STREAM_VISION if vision else tl.STREAM_REFEREE,
                          receive_time_ns=rec.time_ns, sequence=self._seq,
                          source="log", payload=rec.payload)
        ingest = self.station.ingest
        (ingest.vision_packets if vision else ingest.referee_packets).write(env)

    def _reset_pipeline(self) -> None:
        """Time jumped (a log opened or seeked, or back to live): the world model and the
        controllers start again."""
        st = self.station
        replay = self.replaying
        st.world.reset()
        st.feedback.reset()
        st.world_topic.clear()  # no world of before the jump is shown or obeyed
        st.referee_topic.clear()  # the log's own referee is heard within 0.1 s
        st.control.motion.reset_all()
        # (vision is judged by what the feed delivered: one lagging the playhead is no loss)
        st.control.replay_clock = self.player.delivered_ns if replay else None
        # a referee is silent by the log's clock in replay (a paused replay is not silence)
        st.referee_watch.clock = (lambda: self.player.now_ns() / 1e9) if replay \
            else time.monotonic
        st.referee_watch.last_heard = None
        self.recorded_tracked = b""

    def command(self, fn: Callable[..., T], *args: Any) -> T:
        """A player command on the station thread; the feed is woken to act on it."""
        out = fn(*args)
        self.station.player_feed.wake.set()
        return out

    def view(self) -> contract.Player:
        return self.player.view()

    async def open_log(self, path: str) -> contract.Player:
        """Opens a log from the page: only files of the recording folder and of the folders
        given with --log-dir (PlayerError otherwise). Returns at once; the player's loading
        progress and then the log come in the "player" messages."""
        return await self.station.read(self._start_open, path, False)

    async def open_checked(self, real_path: str) -> contract.Player:
        """Opens a log the station found in one of its own folders itself (an evaluation
        run's, in the reports folder): no further check of the path."""
        return await self.station.read(self._start_open, real_path, True)

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
        self.station.publish_views(force=True)
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
            self.station.publish_views(force=True)
            return
        self._attach(log_)

    def _loading(self, frac: float) -> None:
        if self.player.loading is not None:
            self.player.loading = frac
            self.player.serial += 1

    def _attach(self, log_: LogSource) -> None:
        self.station.disarm("replay")  # back to live, robots are not driven by surprise
        self.command(self.player.attach, log_)
        log.info("replaying %s (%.1f s): nothing is sent to robots or a simulator",
                 log_.path, self.player.duration_s())
        self.station.publish_views(force=True)

    def close(self) -> None:
        if self._opening is not None:
            self._opening.cancel()
        self.player.close()
