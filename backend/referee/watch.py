"""Whether the referee the station obeys still speaks.

When the game controller goes quiet (its process died, the network dropped it) the station
keeps obeying its last command, as the rules expect of a team while the game controller
hiccups: robots are not stopped for it. But the operator must see it: once a referee source
was heard and nothing arrived for more than ``REFEREE_SILENT_S``, /api/health reports it, the
transition is logged (rate-limited), and the page shows "referee silent N s" until it speaks
again."""

from __future__ import annotations

import logging
import time
from collections.abc import Callable
from typing import Any

from sslnet.ratelog import RateLimitedLog

from ..world.referee import RefereeState

log = logging.getLogger("touchline.referee")

#: A referee heard before and quiet for longer than this is silent. The official game
#: controller publishes on every engine tick (every 25 ms) and on every change, the internal
#: referee at 20 Hz: 3 s are over 60 missed messages, no network hiccup.
REFEREE_SILENT_S = 3.0

#: At most one log line per transition kind in this interval (a flapping source).
SILENCE_LOG_INTERVAL_S = 30.0


class RefereeWatch:
    """The newest valid referee message's time and source; silence as of ``clock()``."""

    def __init__(self, silent_after_s: float = REFEREE_SILENT_S,
                 clock: Callable[[], float] = time.monotonic) -> None:
        self.silent_after_s = silent_after_s
        self.clock = clock
        #: False while the station ignores the last referee heard (the internal referee,
        #: switched off by the operator): its silence is then expected, not reported
        self.obeyed: Callable[[], bool] = lambda: True
        self.last_heard: float | None = None
        self.source_identifier = ""
        self.command = ""
        self.silent = False  # as of the last check()
        self._log = RateLimitedLog(log, interval_s=SILENCE_LOG_INTERVAL_S)
        self._silent_source = ""  # the source that fell silent last

    def heard(self, ref: RefereeState) -> None:
        self.last_heard = self.clock()
        self.source_identifier = ref.source_identifier
        self.command = ref.command

    def status(self) -> dict[str, Any] | None:
        """The health section: None before any referee message was heard."""
        if self.last_heard is None:
            return None
        age = self.clock() - self.last_heard
        obeyed = self.obeyed()
        return {
            "last_heard_s": age,
            "source_identifier": self.source_identifier,
            "command": self.command,
            "obeyed": obeyed,
            "silent": obeyed and age > self.silent_after_s,
            "silent_after_s": self.silent_after_s,
        }

    @staticmethod
    def warning(status: dict[str, Any] | None) -> str | None:
        """The health warning line for a silent referee, None otherwise."""
        if status is None or not status["silent"]:
            return None
        source = status["source_identifier"] or "(no source identifier)"
        return (f"referee silent {int(status['last_heard_s'])} s: still obeying "
                f"{status['command']} from {source}")

    def check(self) -> dict[str, Any] | None:
        """``status()``, logging a change of silence (rate-limited)."""
        st = self.status()
        silent = bool(st and st["silent"])
        if st is not None and silent != self.silent:
            if silent:
                self._silent_source = st["source_identifier"]
                self._log.log(logging.WARNING, "silent",
                              "referee %s silent for %.1f s: still obeying its last command %s",
                              st["source_identifier"] or "(no source identifier)",
                              st["last_heard_s"], st["command"])
            elif st["obeyed"] and st["source_identifier"] != self._silent_source:
                # a game controller started anew (a new id), not the silent one back
                self._log.log(logging.INFO, "back", "referee %s heard (%s fell silent before)",
                              st["source_identifier"] or "(no source identifier)",
                              self._silent_source or "(no source identifier)")
            elif st["obeyed"]:
                self._log.log(logging.INFO, "back", "referee %s heard again",
                              st["source_identifier"] or "(no source identifier)")
        self.silent = silent
        return st
