"""The team folder watched for saves: a background thread lists it (a stat per file: mtime,
size, inode) every ``interval_s`` and hands a changed listing on. Polling needs no new
dependency and sees every way of saving (in place, write-and-rename, another machine's
editor on a shared folder); a stat of a few dozen files costs microseconds."""

from __future__ import annotations

import logging
import threading
from collections.abc import Callable
from pathlib import Path

from .discovery import Stat, list_files

log = logging.getLogger("touchline.team")

Listing = dict[str, Stat]


class FolderWatcher:
    """Calls ``changed(listing)`` from its own thread whenever the listing differs from the
    last one it reported (the first one is taken as it is at ``start``: ``initial``)."""

    def __init__(self, folder: Path, changed: Callable[[Listing], None],
                 interval_s: float = 0.1) -> None:
        self.folder = folder
        self.changed = changed
        self.interval_s = interval_s
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None
        self.last: Listing = {}
        self.polls = 0

    def start(self, initial: Listing | None = None) -> None:
        self.last = list_files(self.folder) if initial is None else dict(initial)
        self._stop.clear()
        self._thread = threading.Thread(target=self._run, name="team-watcher", daemon=True)
        self._thread.start()

    def _run(self) -> None:
        while not self._stop.wait(self.interval_s):
            self.poll()

    def poll(self) -> bool:
        """One look at the folder; True when it changed (and ``changed`` was called)."""
        self.polls += 1
        now = list_files(self.folder)
        if now == self.last:
            return False
        self.last = now
        try:
            self.changed(now)
        except Exception:  # the watcher must outlive a failing hand-over
            log.exception("team folder change not handled")
        return True

    def stop(self) -> None:
        self._stop.set()
        if self._thread is not None:
            self._thread.join(timeout=2.0)
            self._thread = None
