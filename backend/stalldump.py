"""A stall hunt (bench/tracker_gaps.py): with ``TOUCHLINE_STALL_DUMP=FILE`` every thread's
stack is written to FILE when no tracked frame has gone out for ``TOUCHLINE_STALL_DUMP_MS``
(default 50), by faulthandler's own watchdog thread, which needs no GIL: the thread that holds
the GIL then is the one faulthandler calls "Current thread". The end of each stall, and every
garbage collection over 5 ms, is a line with its wall-clock time."""

from __future__ import annotations

import faulthandler
import gc
import os
import time
from typing import IO, Any

ENV = "TOUCHLINE_STALL_DUMP"
GC_REPORT_S = 0.005


class StallDump:
    def __init__(self, path: str, after_s: float) -> None:
        # appended (one file descriptor, shared with faulthandler's writes; flushed per line)
        self.file: IO[str] = open(path, "a")  # noqa: SIM115 - open for the process's life
        self.after_s = after_s
        self._last: float | None = None
        self._gc_t0 = 0.0
        gc.callbacks.append(self._gc)

    def _line(self, text: str) -> None:
        self.file.write(f"--- {text} at unix {time.time():.3f}\n")
        self.file.flush()

    def _gc(self, phase: str, info: dict[str, Any]) -> None:
        if phase == "start":
            self._gc_t0 = time.perf_counter()
            return
        took = time.perf_counter() - self._gc_t0
        if took > GC_REPORT_S:
            self._line(f"gc generation {info['generation']} took {took * 1000:.1f} ms, "
                       f"{info['collected']} collected")

    def beat(self) -> None:
        """A tracked frame went out: the watchdog starts again."""
        now = time.monotonic()
        if self._last is not None and now - self._last > self.after_s:
            self._line(f"stall of {(now - self._last) * 1000:.0f} ms ended")
        self._last = now
        faulthandler.dump_traceback_later(self.after_s, file=self.file)


def from_env() -> StallDump | None:
    path = os.environ.get(ENV)
    if not path:
        return None
    return StallDump(path, float(os.environ.get(ENV + "_MS", "50")) / 1000.0)

