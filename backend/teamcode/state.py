"""How each team file runs: its state, its error, its counters (shown in the page's Code tab,
GET /api/team and health)."""

from __future__ import annotations

import time
from collections import deque
from dataclasses import dataclass, field
from typing import Literal

from .. import contract

ErrorKind = Literal["import", "exception", "output", "budget", "crash", "missing"]
RunState = Literal["idle", "starting", "running", "error"]


@dataclass(frozen=True, slots=True)
class ErrorInfo:
    """Why a file does not run: kind, message, where (team file, line) and the traceback."""

    kind: ErrorKind
    message: str
    file: str
    line: int | None = None
    traceback: str = ""
    at_unix: float = field(default_factory=time.time)

    def one_line(self) -> str:
        where = f"{self.file}:{self.line}" if self.line is not None else self.file
        first = self.message.strip().splitlines()[0] if self.message.strip() else self.kind
        return f"{self.kind} at {where}: {first}"[:300]

    def view(self) -> contract.TeamError:
        return {"kind": self.kind, "message": self.message, "file": self.file,
                "line": self.line, "traceback": self.traceback, "at_unix": self.at_unix}


def _percentile(sorted_values: list[float], q: float) -> float:
    return sorted_values[min(len(sorted_values) - 1, int(q * len(sorted_values)))]


@dataclass
class FileRun:
    """The running side of one file (plays and processors; libraries stay idle)."""

    state: RunState = "idle"
    error: ErrorInfo | None = None
    loaded_version: str | None = None
    reloaded_at_unix: float | None = None
    reloads: int = 0
    ticks: int = 0
    errors: int = 0
    overruns: int = 0
    #: answers that came after the tick stopped waiting (a busy machine), discarded
    late: int = 0
    moved_out: int = 0
    #: the CPU time of the latest calls, ms
    tick_ms: deque[float] = field(default_factory=lambda: deque(maxlen=512))
    robots: tuple[int, ...] = ()
    outputs: dict[str, float] = field(default_factory=dict)

    def fail(self, err: ErrorInfo) -> bool:
        """Marks the file failed with ``err``; True when this is a new error (not the same
        one again): logged once, counted once."""
        new = self.error is None or self.state != "error" or (
            self.error.kind, self.error.message, self.error.line) != (
            err.kind, err.message, err.line)
        self.state = "error"
        self.error = err
        if new:
            self.errors += 1
        return new

    def tick_percentiles(self) -> tuple[float | None, float | None]:
        if not self.tick_ms:
            return None, None
        s = sorted(self.tick_ms)
        return _percentile(s, 0.5), _percentile(s, 0.99)
