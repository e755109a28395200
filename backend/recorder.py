"""The station's session recorder: every live session into SSL log files (docs/logformat.md).

The station's event loop calls :meth:`SessionRecorder.record` for every datagram, command set
and operator action (up to ~1000 a second); that call only appends to a deque (no lock, no
thread wake-up per record), so a slow or full disk never stalls the station. One writer thread
owns the file: it wakes every 20 ms (at once for a control), writes what is queued with
:class:`ssllog.writer.LogWriter`, flushes at least once a second (a killed station loses at most
about a second; its file has no index, which the reader tolerates), and rotates files (size,
game stage, on request). Controls (stage, new file, enable, folder, close) travel through the
same queue as the records, so they apply exactly between the records around them.

A write error (a full disk) stops recording and is reported in :meth:`status`; the station
keeps running. Enabling again, a new file or a new folder tries again.
"""

from __future__ import annotations

import contextlib
import errno
import json
import logging
import math
import threading
import time
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any, BinaryIO

from domain.wallclock import file_stamp
from ssllog.format import TYPE_TL_SESSION
from ssllog.writer import LogWriter

log = logging.getLogger(__name__)

FLUSH_INTERVAL_S = 0.5  # well inside the promised second
#: a stage change starts a new file only if the last stage change that did is this old
MIN_STAGE_FILE_S = 10.0
_POLL_S = 0.02  # the writer drains the queue this often: one wake-up per batch, not per record


@dataclass(frozen=True, slots=True)
class _Control:
    """An order for the writer thread, queued in line with the records."""

    op: str  # "rotate", "enable", "disable", "folder", "stop"
    reason: str = ""
    folder: Path | None = None


_Item = tuple[int, int, bytes] | _Control


class SessionRecorder:
    """Records into ``folder``/``<prefix>-YYYYmmdd-HHMMSS[-n].log``; never overwrites a file."""

    def __init__(
        self,
        folder: Path,
        *,
        enabled: bool = True,
        max_bytes: int = 1 << 30,
        rotate_on_stage: bool = True,
        prefix: str = "touchline",
        opener: Callable[[str], BinaryIO] | None = None,
        our_team: str = "",
        queue_size: int = 20000,
        flush_interval_s: float = FLUSH_INTERVAL_S,
        min_stage_file_s: float = MIN_STAGE_FILE_S,
        clock: Callable[[], float] = time.monotonic,
    ) -> None:
        self.max_bytes = max_bytes
        self.rotate_on_stage = rotate_on_stage
        self.prefix = prefix
        self.our_team = our_team
        self._opener = opener
        self._queue_size = queue_size
        self._flush_interval_s = flush_interval_s
        # deque.append and popleft are atomic: the queue needs no lock; unbounded so that
        # controls always get in, record() bounds the records itself
        self._q: deque[_Item] = deque()
        self._wake = threading.Event()  # a control or close: the writer drains at once
        # event loop side (only written by the caller's thread)
        self._enabled = enabled
        self._folder = Path(folder)
        self._stage: str | None = None
        self._min_stage_file_s = min_stage_file_s
        self._clock = clock
        self._stage_rotated = -math.inf  # when a stage change last started a file
        self._closed = False
        self.dropped = 0  # records dropped because the queue was full
        self.not_recorded = 0  # records ignored while disabled, stopped by an error, closed
        # writer side (only written by the writer thread; read by status() without locks)
        self._writer: LogWriter | None = None
        self._file = ""
        self._file_folder = self._folder
        self._size = 0
        self._records = 0
        self._records_total = 0
        self._files = 0
        self._started = 0.0  # monotonic time the current file began
        self._last_flush = 0.0
        self._dirty = False
        self._w_enabled = enabled  # the writer's view, in line with the queued records
        # the session record, written just before the file's first record (with its time, so
        # that times never go back in the file) or when the file is finished
        self._session: bytes | None = None
        self._next_reason: str | None = None  # a file to open at the next record (size)
        self.bad = 0  # records that could not be encoded (not bytes, time out of int64)
        self.error: str | None = None
        self._thread = threading.Thread(target=self._run, name="session-recorder", daemon=True)
        if enabled:
            self._control_put(_Control("rotate", "start", self._folder))
        self._thread.start()

    # -- the station's side (event loop thread): never blocks, never raises ------------------

    def record(self, time_ns: int, rtype: int, payload: bytes) -> None:
        """Queues one record; drops and counts it when the queue is full."""
        if not self._enabled or self._closed or self.error is not None:
            self.not_recorded += 1
            return
        if len(self._q) >= self._queue_size:
            self.dropped += 1
            return
        self._q.append((time_ns, rtype, payload))

    def _control_put(self, c: _Control) -> None:
        self._q.append(c)
        self._wake.set()

    def stage(self, stage_name: str) -> None:
        """The game stage now; a change starts a new file (one file per half, break, ...)."""
        previous, self._stage = self._stage, stage_name
        if (previous is not None and stage_name != previous and self.rotate_on_stage
                and self._enabled and not self._closed):
            now = self._clock()
            if now - self._stage_rotated < self._min_stage_file_s:
                return  # a stage that flips (a spoofed or broken referee): one file, not 10/s
            self._stage_rotated = now
            self._control_put(_Control("rotate", f"stage {stage_name}"))

    def new_file(self, reason: str) -> None:
        """Finishes the current file and starts the next (the page's "new file" button)."""
        if self._enabled and not self._closed:
            self._control_put(_Control("rotate", reason))

    def set_enabled(self, enabled: bool) -> None:
        """Off finishes the current file (with its index); on starts a new one."""
        if self._closed or enabled == self._enabled:
            return
        self._enabled = enabled
        self._control_put(_Control("enable" if enabled else "disable", "enabled"))

    def set_folder(self, folder: Path) -> None:
        """Records into ``folder`` from now on (a new file there, if recording)."""
        if self._closed:
            return
        self._folder = Path(folder)
        self._control_put(_Control("folder", "folder", self._folder))

    def status(self) -> dict[str, Any]:
        """What the page shows; reads plain attributes, holds no lock."""
        writing = self._writer is not None  # a file is open (not between two files)
        return {
            "enabled": self._enabled,
            "recording": writing or self._next_reason is not None,
            "file": self._file if writing else "",
            "folder": str(self._folder),
            "size_bytes": self._size if writing else 0,
            "duration_s": round(time.monotonic() - self._started, 3) if writing else 0.0,
            "records": self._records if writing else 0,
            "records_total": self._records_total,
            "files": self._files,
            "queued": len(self._q),
            "dropped": self.dropped,
            "not_recorded": self.not_recorded,
            "bad": self.bad,
            "error": self.error,
        }

    def close(self, timeout_s: float = 10.0) -> None:
        """Writes what is queued, finishes the file with its index, joins the thread."""
        if self._closed:
            return
        self._closed = True
        self._control_put(_Control("stop"))
        self._thread.join(timeout_s)
        if self._thread.is_alive():
            log.error("recorder: the writer thread did not finish within %.1f s", timeout_s)

    # -- the writer thread ------------------------------------------------------------------

    def _run(self) -> None:
        q = self._q
        while True:
            self._wake.wait(_POLL_S)
            self._wake.clear()
            while q:
                item = q.popleft()
                try:
                    if isinstance(item, _Control):
                        if item.op == "stop":
                            self._finish()
                            return
                        self._control(item)
                    else:
                        self._write(*item)
                except Exception as e:  # a bug must not end the thread (close() would hang)
                    log.exception("recorder: unexpected error")
                    self._stop_on_error(OSError(0, f"unexpected {type(e).__name__}: {e}"))
            if self._dirty and time.monotonic() - self._last_flush >= self._flush_interval_s:
                self._guard(self._flush)

    def _control(self, c: _Control) -> None:
        if c.folder is not None:
            self._file_folder = c.folder
        self._next_reason = None
        if c.op == "disable":
            self._w_enabled = False
            self._finish()
            return
        if c.op == "enable":
            self._w_enabled = True
        if not self._w_enabled:
            return  # a new folder is used when recording starts again
        # rotate, enable, folder: a new file; a request after an error tries again
        self._finish()
        self.error = None
        self._guard(lambda: self._open(c.reason))

    def _write(self, time_ns: int, rtype: int, payload: bytes) -> None:
        if (not isinstance(payload, bytes | bytearray) or not -(1 << 63) <= time_ns < 1 << 63
                or not -(1 << 31) <= rtype < 1 << 31):
            self._bad(f"record type {rtype}: payload {type(payload).__name__}, time {time_ns}")
            return
        if self._writer is None and self._next_reason is not None:
            reason, self._next_reason = self._next_reason, None
            self._guard(lambda: self._open(reason))
        w = self._writer
        if w is None:
            return  # disabled or stopped by an error; the records still queued are lost
        if self._session is not None:
            session, self._session = self._session, None
            self._write(time_ns, TYPE_TL_SESSION, session)
        if not self._guard(lambda: w.write(time_ns, rtype, payload)):
            return
        self._size += 16 + len(payload)
        self._records += 1
        self._records_total += 1
        self._dirty = True
        if self._size >= self.max_bytes and self._records > 1:  # never a file of a session only
            self._finish()
            self._next_reason = "size"  # the next file begins with the next record

    def _open(self, reason: str) -> None:
        folder = self._file_folder
        folder.mkdir(parents=True, exist_ok=True)
        stamp = file_stamp()
        for n in range(10000):
            name = f"{self.prefix}-{stamp}{f'-{n}' if n else ''}.log"
            path = folder / name
            if path.exists():
                continue
            try:
                f = self._opener(str(path)) if self._opener else open(path, "xb")  # noqa: SIM115
            except FileExistsError:
                continue
            break
        else:
            raise FileExistsError(errno.EEXIST, "no free file name", str(folder))
        self._file = name
        self._size = 16
        self._records = 0
        self._started = time.monotonic()
        try:
            w = LogWriter(str(path), int(self._flush_interval_s * 1e9), file=f)
        except BaseException:
            f.close()
            raise
        self._writer = w
        self._files += 1
        log.info("recorder: writing %s (%s)", path, reason)
        session = {"touchline": 1, "started_unix": time.time(), "our_team": self.our_team,
                   "reason": reason}
        self._session = json.dumps(session).encode()
        self._flush()

    def _bad(self, what: str) -> None:
        if not self.bad:
            log.error("recorder: a record that cannot be written, skipped (%s)", what)
        self.bad += 1

    def _flush(self) -> None:
        if self._writer is not None:
            self._writer.flush()
        self._dirty = False
        self._last_flush = time.monotonic()

    def _finish(self) -> None:
        """Ends the current file with its index (if any)."""
        if self._writer is not None and self._session is not None:
            session, self._session = self._session, None
            self._write(time.time_ns(), TYPE_TL_SESSION, session)  # a file without records
        w = self._writer
        if w is not None and self._guard(w.finish):
            self._writer = None

    def _guard(self, action: Callable[[], object]) -> bool:
        """Runs a file operation; an OSError stops recording with a clear reason."""
        try:
            action()
            return True
        except OSError as e:
            self._stop_on_error(e)
            return False

    def _stop_on_error(self, e: OSError) -> None:
        where = e.filename or str(self._file_folder / self._file)
        if e.errno == errno.ENOSPC:
            reason = f"disk full: {e.strerror} ({where}); recording stopped"
        else:
            reason = f"cannot write the log: {e.strerror or e} ({where}); recording stopped"
        if self.error is None:
            log.error("recorder: %s", reason)
        self.error = reason
        w, self._writer = self._writer, None
        if w is not None:
            with contextlib.suppress(Exception):  # the buffered bytes cannot be written either
                w.close_unfinished()
