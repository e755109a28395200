"""Arming, the operator's decision, persisted like the emergency stop (``arming.json`` in the
state folder, written atomically): a backend the launcher's supervisor restarts after a crash
(``--restarted``) comes back armed or disarmed as the operator left it, so the robots of an
armed station are driven again as soon as the new backend has fresh vision; any other start
(a station started anew, a backend started by hand) starts disarmed and clears the file. The
emergency stop wins over both: a pressed stop disarms, and an armed file is not taken back
while the stop is pressed (docs/security.md)."""

from __future__ import annotations

import contextlib
import json
import logging
import time
from collections.abc import Callable
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

from .params.store import atomic_write_json, run_now

log = logging.getLogger("touchline.arming")


@dataclass(frozen=True)
class ArmingState:
    armed: bool = False
    since: float = 0.0  # Unix s of the last arm or disarm (0: never)
    by: str = ""  # who armed or disarmed it


class ArmingStore:
    """The arming state and its file; no file (or an unreadable one): disarmed."""

    def __init__(self, state_dir: Path | None, restarted: bool) -> None:
        self.file = None if state_dir is None else state_dir / "arming.json"
        self.state = ArmingState()
        self.warning = ""
        #: runs a file write (the station: its ordered writer thread); inline by default
        self.writer: Callable[[Callable[[], None]], None] = run_now
        #: taken back from the file after a crash (the supervisor's restart)
        self.restored = False
        if self.file is None:
            return
        if not restarted:
            # a start, not a restart: the last run's arming is not this run's
            with contextlib.suppress(FileNotFoundError):
                self.file.unlink()
            return
        if not self.file.exists():
            return
        try:
            data: Any = json.loads(self.file.read_text())
            armed = data["armed"]
            if not isinstance(armed, bool):
                raise TypeError(f"armed is {armed!r}, not true or false")
            self.state = ArmingState(armed, float(data.get("since", 0.0)),
                                     str(data.get("by", "")))
        except (ValueError, KeyError, TypeError, AttributeError, OSError) as exc:
            # unreadable: disarmed, the safe side (the operator arms again)
            self.warning = f"arming.json is not readable ({exc}): restarted disarmed"
            log.error("%s", self.warning)
            self.state = ArmingState()
            return
        self.restored = self.state.armed

    def set(self, armed: bool, by: str) -> ArmingState:
        """The state at once; its file written by ``writer`` (in order, off the caller's
        thread when the station gives one, as the e-stop's)."""
        self.state = state = ArmingState(armed, time.time(), by)
        file = self.file
        if file is None:
            return self.state

        def write() -> None:
            try:
                atomic_write_json(file, asdict(state))
                self.warning = ""
            except OSError as exc:
                if armed:  # the arming holds in memory; a restart comes up disarmed
                    self.warning = (f"arming not persisted ({exc}): a backend restart would "
                                    f"come up disarmed")
                else:  # an armed file must not outlive a disarm: no file is disarmed too
                    try:
                        file.unlink(missing_ok=True)
                        self.warning = ""
                    except OSError as exc2:
                        self.warning = (f"disarming not persisted ({exc}; {exc2}): a backend "
                                        f"restart could come up armed")
                if self.warning:
                    log.error("%s", self.warning)
        self.writer(write)
        return self.state
