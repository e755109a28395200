"""The log player: a recorded session (an SSL log file) fed into the station's pipeline as if
the relay had just received it, at any speed, with seek, frame steps and jumps to events.

The player owns the replay clock: while a log is open the station's "now" is the log's time
at the playhead (``now_ns``), so the world model, the lost-vision check and the plots run on
recorded time whatever the speed, and a paused replay is not "vision lost". Records go onto the
same topics the relay ingest writes (vision and referee envelopes, bytes unchanged), so every
processor works on replayed data as it does live; the station mutes every output meanwhile.

Pure of sockets and of the event loop: the feed processor (``PlayerFeed``) asks ``due`` what
to emit and ``wait_s`` how long to sleep; the station calls the commands on its own thread.
"""

from __future__ import annotations

import math
import time
from collections import deque
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass
from typing import Literal, Protocol

from ssllog.format import (
    TYPE_REFEREE_2013,
    TYPE_TL_COMMANDS,
    TYPE_TRACKER_2020,
    TYPE_VISION_2014,
)
from ssllog.reader import Record

from .. import contract
from ..jsonsafe import dumps

#: after a seek the pipeline is re-run over this much of the log before the playhead, so the
#: filters have settled and the field shows the robots where the log has them
PREROLL_S = 0.3
#: records emitted per feed tick while catching up (the topics hold 64 vision packets; each
#: tick lets every processor that waits on them run before the next batch)
BATCH = 32
#: later than any record's time
_END_OF_TIME = 2**63 - 1
#: the speeds a page may choose (0 = as fast as possible)
MIN_SPEED, MAX_SPEED = 0.1, 10.0
#: step back: how far back one camera frame may be looked for (a gap in the log is longer)
STEP_BACK_SEARCH_S = 2.0
#: recent vision record times kept for stepping back without a scan
HISTORY = 512
#: a "previous event" jump skips events this close behind the playhead (press twice = further)
PREV_EVENT_SLACK_S = 0.5


class LogEventLike(Protocol):
    @property
    def time_ns(self) -> int: ...
    @property
    def kind(self) -> str: ...
    @property
    def label(self) -> str: ...


class LogSource(Protocol):
    """A log opened for random access (``ssllog.logfile.LogFile``)."""

    @property
    def path(self) -> str: ...
    @property
    def t_first_ns(self) -> int: ...
    @property
    def t_last_ns(self) -> int: ...
    @property
    def warning(self) -> str | None: ...
    @property
    def events(self) -> Sequence[LogEventLike]: ...

    def offset_at(self, time_ns: int) -> int: ...

    def records(self, from_offset: int | None = None,
                include_unknown: bool = False) -> Iterator[Record]: ...

    def close(self) -> None: ...


class PlayerError(ValueError):
    """An action that cannot be done now (no log open, bad speed): a 409/422 with the reason."""


@dataclass
class _Feed:
    """Where the reading is: the iterator and the record read ahead."""

    records: Iterator[Record]
    ahead: Record | None


class LogPlayer:
    """The player's state and its commands (called on the station thread)."""

    def __init__(self, emit: Callable[[Record], None], reset: Callable[[], None],
                 clock: Callable[[], float] = time.monotonic) -> None:
        #: puts one record onto the bus (the station: an envelope on the ingest topics)
        self._emit = emit
        #: restarts the pipeline's state (world model, controllers) when time jumps
        self._reset = reset
        self._mono = clock
        self.log: LogSource | None = None
        self.playing = False
        self.speed = 1.0
        self.epoch = 0
        self.loading: float | None = None
        self.loading_path: str | None = None
        self.error = ""
        #: log time (ns) at the playhead when last anchored, and the monotonic time then
        self._anchor_ns = 0
        self._anchor_mono = 0.0
        #: while catching up (after a seek, a step) the playhead is held here
        self._target_ns: int | None = None
        self._feed: _Feed | None = None
        self._last_emitted_ns = 0
        self._vision_times: deque[int] = deque(maxlen=HISTORY)
        #: bumped on every state change a page should hear of (not the playhead moving)
        self.serial = 0
        #: the open log's events as the page gets them, and as JSON: made once per log (a
        #: long session has thousands; the player's state changes on every seek)
        self._events: list[contract.PlayerEvent] = []
        self.events_json = "[]"
        self.emitted = 0

    # ---- state ----

    @property
    def source(self) -> Literal["live", "log"]:
        return "live" if self.log is None else "log"

    def position_ns(self) -> int:
        """The log's time at the playhead."""
        if self.log is None:
            return 0
        if self._target_ns is not None:
            return self._target_ns
        if self.playing and self.speed > 0:
            t = self._anchor_ns + int((self._mono() - self._anchor_mono) * self.speed * 1e9)
            return min(t, self.log.t_last_ns)
        if self.playing:  # as fast as possible: where the feed is
            return max(self._anchor_ns, self._last_emitted_ns)
        return self._anchor_ns

    def now_ns(self) -> int:
        """The station's clock: the wall clock live, the playhead's log time in replay."""
        return time.time_ns() if self.log is None else self.position_ns()

    def delivered_ns(self) -> int:
        """The log's time up to which every record has been emitted: the playhead, or just
        before the next record to emit while the feed lags it (a seek's pre-roll, a batch at
        a time; a fast replay on a busy station). Vision is as old as this clock says: frames
        the feed has not emitted yet are no silence of the cameras."""
        pos = self.position_ns()
        feed = self._feed
        if feed is not None and feed.ahead is not None and feed.ahead.time_ns <= pos:
            return feed.ahead.time_ns - 1
        return pos

    def duration_s(self) -> float:
        return 0.0 if self.log is None else (self.log.t_last_ns - self.log.t_first_ns) / 1e9

    def position_s(self) -> float:
        return 0.0 if self.log is None else (self.position_ns() - self.log.t_first_ns) / 1e9

    def view(self) -> contract.Player:
        lg = self.log
        return {
            "source": self.source,
            "file": lg.path if lg is not None else self.loading_path,
            "duration_s": self.duration_s(),
            "position_s": self.position_s(),
            "playing": self.playing,
            "speed": self.speed,
            "start_unix": lg.t_first_ns / 1e9 if lg is not None else 0.0,
            "loading": self.loading,
            "error": self.error,
            "warning": lg.warning if lg is not None else None,
            "epoch": self.epoch,
            "events": self._events,
        }

    def json(self) -> str:
        """``{"type": "player", "player": view()}`` as JSON, the events' JSON made once."""
        head = dumps({"type": "player", "player": {**self.view(), "events": []}}, "player")
        return head[:-len('[]}}')] + self.events_json + "}}"

    def clock(self) -> contract.ReplayClock | None:
        """What every world message carries while a log is open."""
        lg = self.log
        if lg is None:
            return None
        pos = self.position_ns()
        return {"file": lg.path, "position_s": (pos - lg.t_first_ns) / 1e9, "t_unix": pos / 1e9,
                "duration_s": self.duration_s(), "playing": self.playing, "speed": self.speed,
                "epoch": self.epoch}

    def _changed(self) -> None:
        self.serial += 1

    # ---- commands ----

    def attach(self, log: LogSource) -> None:
        """Opens ``log`` (already indexed): paused at its start, the first frames shown."""
        self.close()
        self.log = log
        self._events = [{"t_s": (e.time_ns - log.t_first_ns) / 1e9, "kind": _kind(e.kind),
                         "label": e.label} for e in log.events]
        self.events_json = dumps(self._events, "events")
        self.loading = None
        self.loading_path = None
        self.error = ""
        self.playing = False
        self.speed = 1.0
        self._seek_ns(log.t_first_ns)

    def live(self) -> None:
        """Back to live input."""
        self.close()
        self.epoch += 1
        self._reset()
        self._changed()

    def close(self) -> None:
        if self.log is not None:
            self.log.close()
        self.log = None
        self._events = []
        self.events_json = "[]"
        self._feed = None
        self._target_ns = None
        self.playing = False
        self._vision_times.clear()

    def play(self, speed: float) -> None:
        lg = self._need_log()
        if not math.isfinite(speed) or not (speed == 0 or MIN_SPEED <= speed <= MAX_SPEED):
            raise PlayerError(f"speed must be 0 (as fast as possible) or {MIN_SPEED} .. "
                              f"{MAX_SPEED}, got {speed}")
        pos = self.position_ns()
        if pos >= lg.t_last_ns:  # at the end: play again from the start
            self._seek_ns(lg.t_first_ns)
            pos = self.position_ns()
        self._anchor(pos)
        self.speed = speed
        self.playing = True
        self._changed()

    def pause(self) -> None:
        self._need_log()
        pos = self.position_ns()
        self._anchor(pos)
        if self.playing and self._target_ns is None:
            # the feed may lag the playhead by a few records: it catches up to where it stopped
            self._target_ns = pos
        self.playing = False
        self._changed()

    def seek(self, position_s: float) -> None:
        lg = self._need_log()
        if not math.isfinite(position_s) or position_s < 0:
            raise PlayerError(f"position_s must be a number >= 0, got {position_s}")
        if position_s > self.duration_s():
            raise PlayerError(f"position_s {position_s:.3f} is past the end of the log "
                              f"({self.duration_s():.3f} s)")
        self._seek_ns(lg.t_first_ns + round(position_s * 1e9))

    def step(self, frames: int) -> None:
        """``frames`` camera frames (vision datagrams) forward or back; pauses."""
        lg = self._need_log()
        if frames == 0:
            raise PlayerError("frames must not be 0")
        self._anchor(self.position_ns())
        self.playing = False
        if frames > 0:
            self._target_ns = None
            self._step_forward(frames)
        else:
            t = self._vision_time_back(-frames)
            self._seek_ns(max(lg.t_first_ns, t))
        self._changed()

    def jump(self, kind: str, direction: Literal["next", "prev"]) -> float:
        """To the next or previous event of ``kind`` ("any" for every kind); returns its
        position. Playing goes on from there."""
        lg = self._need_log()
        pos = self.position_ns()
        events = [e for e in lg.events if kind == "any" or _kind(e.kind) == kind]
        if direction == "next":
            after = [e for e in events if e.time_ns > pos + 1_000_000]
            target = after[0] if after else None
        else:
            before = [e for e in events if e.time_ns < pos - int(PREV_EVENT_SLACK_S * 1e9)]
            target = before[-1] if before else None
        if target is None:
            what = "event" if kind == "any" else f"{kind} event"
            raise PlayerError(f"no {direction} {what} in this log")
        playing = self.playing
        self._seek_ns(target.time_ns)
        if playing:
            self._anchor(target.time_ns)
            self.playing = True
        return (target.time_ns - lg.t_first_ns) / 1e9

    # ---- the feed (PlayerFeed calls these on every wake-up) ----

    def due(self) -> list[Record]:
        """The records to emit now (at most BATCH); emitting them is the caller's."""
        lg, feed = self.log, self._feed
        if lg is None or feed is None:
            return []
        if self._target_ns is not None:
            until = self._target_ns
        elif self.playing:
            until = lg.t_last_ns if self.speed == 0 else self.position_ns()
        else:
            return []
        if until >= lg.t_last_ns:
            # at the end: all the rest, a record stamped a little after the one that follows it
            # too (the commands are stamped when sent, up to ms after the next vision record)
            until = _END_OF_TIME
        out: list[Record] = []
        while len(out) < BATCH and feed.ahead is not None and feed.ahead.time_ns <= until:
            out.append(feed.ahead)
            feed.ahead = next(feed.records, None)
        if feed.ahead is None or feed.ahead.time_ns > until:
            if self._target_ns is not None:  # caught up with a seek or a step
                self._anchor(self._target_ns)
                self._target_ns = None
            elif self.playing and feed.ahead is None:
                self._end()
        return out

    def emit(self, records: list[Record]) -> None:
        for rec in records:
            self._last_emitted_ns = rec.time_ns
            if rec.type == TYPE_VISION_2014:
                self._vision_times.append(rec.time_ns)
            self._emit(rec)
            self.emitted += 1

    def wait_s(self) -> float | None:
        """How long the feed may sleep: 0 with records due, the time to the next record while
        playing, None (until woken) when paused or live."""
        lg, feed = self.log, self._feed
        if lg is None or feed is None or feed.ahead is None:
            return None
        if self._target_ns is not None:
            return 0.0
        if not self.playing:
            return None
        if self.speed == 0:
            return 0.0
        ahead_s = (feed.ahead.time_ns - self.position_ns()) / 1e9 / self.speed
        return max(0.0, ahead_s)

    # ---- internals ----

    def _need_log(self) -> LogSource:
        if self.log is None:
            raise PlayerError("no log is open: open one first (action 'open')")
        return self.log

    def _anchor(self, t_ns: int) -> None:
        self._anchor_ns = t_ns
        self._anchor_mono = self._mono()

    def _seek_ns(self, t_ns: int) -> None:
        """Restarts the pipeline and re-runs it over the pre-roll, the playhead held at
        ``t_ns`` until the feed has caught up."""
        lg = self._need_log()
        t_ns = min(max(t_ns, lg.t_first_ns), lg.t_last_ns)
        start = max(lg.t_first_ns, t_ns - int(PREROLL_S * 1e9))
        # Touchline's own types too (the commands sent, drawn beside the what-if's)
        records = _played(lg.records(lg.offset_at(start), include_unknown=True))
        self._feed = _Feed(records, next(records, None))
        self._vision_times.clear()
        self._last_emitted_ns = start
        self._target_ns = t_ns
        self._anchor(t_ns)
        self.epoch += 1
        self._reset()
        self._changed()

    def _step_forward(self, frames: int) -> None:
        """Holds the playhead at the ``frames``-th vision record ahead (the feed emits up to
        it: referee records between come too)."""
        feed = self._feed
        lg = self._need_log()
        if feed is None:
            return
        # read ahead without emitting: the records are replayed by due() up to the target.
        # Frames at or before the playhead do not count (the feed may lag it: they are due)
        pos = self._anchor_ns
        buffered: list[Record] = []
        seen = 0
        rec = feed.ahead
        target = None
        while rec is not None:
            buffered.append(rec)
            if rec.type == TYPE_VISION_2014 and rec.time_ns > pos:
                seen += 1
                if seen == frames:
                    target = rec.time_ns
                    break
            rec = next(feed.records, None)
        if target is None:
            target = lg.t_last_ns
        feed.records = _chain(buffered[1:], feed.records)
        self._target_ns = target

    def _vision_time_back(self, frames: int) -> int:
        """The receive time of the vision record ``frames`` back from the playhead (the one
        at the playhead, after a step, not counted)."""
        pos = self.position_ns()
        times = [t for t in self._vision_times if t < pos]
        if len(times) >= frames:
            return times[-frames]
        lg = self._need_log()
        # not in the history: scan a window before the oldest known
        end = times[0] if times else pos
        start = max(lg.t_first_ns, end - int(STEP_BACK_SEARCH_S * 1e9))
        found: list[int] = []
        for rec in lg.records(lg.offset_at(start)):
            if rec.time_ns >= end:
                break
            if rec.type == TYPE_VISION_2014:
                found.append(rec.time_ns)
        need = frames - len(times)
        if len(found) >= need:
            return found[-need]
        return found[0] if found else lg.t_first_ns

    def _end(self) -> None:
        lg = self._need_log()
        self._anchor(lg.t_last_ns)
        self.playing = False
        self._changed()


def _chain(first: list[Record], rest: Iterator[Record]) -> Iterator[Record]:
    yield from first
    yield from rest


def _kind(kind: str) -> contract.PlayerEventKind:
    if kind in ("command", "stage", "goal", "card", "operator"):
        return kind  # type: ignore[return-value]
    return "operator"


#: the record types the feed emits (the rest of a log is skipped): vision and referee go onto
#: the bus; the log's tracked vision and commands are kept to be drawn beside today's
PLAYED_TYPES = frozenset({TYPE_VISION_2014, TYPE_REFEREE_2013, TYPE_TRACKER_2020,
                          TYPE_TL_COMMANDS})


def _played(records: Iterator[Record]) -> Iterator[Record]:
    return (r for r in records if r.type in PLAYED_TYPES)
