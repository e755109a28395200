"""The emergency stop, latched: it survives a backend restart (persisted in the state folder,
written atomically) and is latched in the relay too (``EmergencyStop`` on ZeroMQ), so a
restarting backend cannot drive until an operator releases it. Pressing is one click; a
release is an explicit, confirmed action, logged with who released it."""

from __future__ import annotations

import json
import logging
import time
from collections.abc import Callable
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

from domain.wallclock import date_clock

from .params.store import atomic_write_json, run_now

log = logging.getLogger("touchline.estop")


@dataclass(frozen=True)
class EstopState:
    active: bool = False
    since: float = 0.0  # Unix s of the last press or release
    by: str = ""  # who pressed (or released) it


class EstopLatch:
    """The latched state and its file (``estop.json``); no file: released."""

    def __init__(self, state_dir: Path | None) -> None:
        self.file = None if state_dir is None else state_dir / "estop.json"
        self.state = EstopState()
        self.warning = ""
        #: runs a file write (the station: its ordered writer thread); inline by default
        self.writer: Callable[[Callable[[], None]], None] = run_now
        if self.file is not None and self.file.exists():
            try:
                data: Any = json.loads(self.file.read_text())
                active = data["active"]
                if not isinstance(active, bool):  # null, "false", 0: not a released stop
                    raise TypeError(f"active is {active!r}, not true or false")
                self.state = EstopState(active=active, since=float(data.get("since", 0.0)),
                                        by=str(data.get("by", "")))
            except (ValueError, KeyError, TypeError, AttributeError, OSError) as exc:
                # an unreadable latch is a pressed latch: the safe side
                self.state = EstopState(True, time.time(), "estop.json unreadable")
                self.warning = (f"estop.json is not readable ({exc}): the emergency stop is "
                                f"active until an operator releases it")
                log.error("%s", self.warning)
        if self.state.active:
            log.warning("emergency stop ACTIVE (latched since %s by %s): the robots stay "
                        "stopped until an operator releases it",
                        date_clock(self.state.since),
                        self.state.by or "?")

    @property
    def active(self) -> bool:
        return self.state.active

    def set(self, active: bool, by: str) -> EstopState:
        """The state at once; its file written by ``writer`` (in order, off the caller's
        thread when the station gives one: an fsync behind a recorder's writes can take tens
        of milliseconds, and the stop must not wait for the disk)."""
        self.state = state = EstopState(active, time.time(), by)
        self.warning = ""
        file = self.file
        if file is not None:
            def write() -> None:
                try:
                    atomic_write_json(file, asdict(state))
                except OSError as exc:  # the stop itself holds in memory and in the relay
                    self.warning = (f"emergency stop state not persisted ({exc}): a backend "
                                    f"restart would rely on the relay's latch alone")
                    log.error("%s", self.warning)
            self.writer(write)
        return self.state
