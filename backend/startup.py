"""The backend's start, step by step: when each step was done, in seconds from the process's
own start (the kernel's record of it, so the interpreter and the imports count too), or for a
warm spare from the word to start (its imports were done before). Health
shows it (``startup``) and the log says it once the start is over: after a crash the
station's first command must leave quickly, and this tells where a slow start goes
(bench/restart_bench.py prints it for every restart)."""

from __future__ import annotations

import logging
import os
import threading
import time

log = logging.getLogger("touchline.startup")

#: the steps the first command waits for, in the order they happen
FIRST_COMMAND_STEPS = ("imports", "station built", "station running", "first frame",
                       "first targets", "first command")
#: what starts once the first command is out (or the wait for it is over)
LATE_STEPS = ("recorder open", "engine started", "web imports", "web serving")


def process_start_mono() -> float | None:
    """The monotonic time this process started (Linux: ``/proc/self/stat``, in clock ticks
    since boot, 10 ms), or None where that is not known."""
    try:
        with open("/proc/self/stat") as f:
            stat = f.read()
        # the fields after the command name (which may hold spaces and parentheses)
        fields = stat[stat.rindex(")") + 2:].split()
        started_s = int(fields[19]) / os.sysconf("SC_CLK_TCK")  # field 22: starttime
        age = time.clock_gettime(time.CLOCK_BOOTTIME) - started_s
    except (OSError, ValueError, IndexError, AttributeError):
        return None
    return time.monotonic() - age if age >= 0 else None


class StartupTimeline:
    """Each step's time from the process start, kept once (the first time it is marked)."""

    def __init__(self, t0_mono: float | None = None) -> None:
        self.t0_mono = t0_mono if t0_mono is not None else time.monotonic()
        self.steps: dict[str, float] = {}
        #: started by the launcher's supervisor after a crash (``--restarted``)
        self.restarted = False
        #: a warm spare (``--standby``) told to start: imported before, the steps count from
        #: the word to start instead of the process start
        self.standby = False
        self._lock = threading.Lock()
        self._said = False

    def mark(self, step: str) -> None:
        with self._lock:
            if step not in self.steps:
                self.steps[step] = time.monotonic() - self.t0_mono

    def done(self, step: str) -> bool:
        return step in self.steps

    def log_once(self) -> None:
        """Says the timeline in the log once (when the start is over)."""
        with self._lock:
            if self._said:
                return
            self._said = True
            steps = ", ".join(f"{k} {v:.2f}" for k, v in self.steps.items())
        log.info("%s in s from %s: %s",
                 "restart (after a crash)" if self.restarted else "start",
                 "the word to start (a warm spare)" if self.standby else "the process start",
                 steps)

    def view(self) -> dict[str, object]:
        with self._lock:
            return {"restarted": self.restarted, "standby": self.standby,
                    "steps_s": dict(self.steps)}


#: this process's timeline (one backend per process; tests that build several stations share
#: it, which only matters to what its first steps say)
TIMELINE = StartupTimeline(process_start_mono())
