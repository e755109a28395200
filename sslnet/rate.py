"""Counters with a per-second rate, used by every process for its health numbers."""

from __future__ import annotations

import time
from collections import deque


class RateCounter:
    """Counts events; ``rate_hz`` is the number of events in the last ``window_s`` / window."""

    def __init__(self, window_s: float = 1.0) -> None:
        self.window_s = window_s
        self.total = 0
        self.last_time: float | None = None
        self._times: deque[float] = deque()

    def add(self, now: float | None = None) -> None:
        t = time.monotonic() if now is None else now
        self.total += 1
        self.last_time = t
        times = self._times
        times.append(t)
        # trimmed in bulk once the oldest is a window older than the window (at most two
        # windows of times are kept): an event is counted hundreds of times a second per
        # stream, and ``rate_hz`` trims exactly when read
        if times[0] < t - 2.0 * self.window_s:
            self._trim(t)

    def add_many(self, n: int, now: float) -> None:
        """``n`` events at ``now`` (a reader's batch of datagrams counted once per wake-up:
        one clock read and one call, not one per datagram); the same as ``add(now)`` n times."""
        if n <= 0:
            return
        self.total += n
        self.last_time = now
        times = self._times
        if n == 1:  # the common batch (no list to extend from)
            times.append(now)
        else:
            times.extend([now] * n)
        if times[0] < now - 2.0 * self.window_s:
            self._trim(now)

    def _trim(self, now: float) -> None:
        cutoff = now - self.window_s
        times = self._times
        while times and times[0] < cutoff:
            times.popleft()

    def rate_hz(self, now: float | None = None) -> float:
        t = time.monotonic() if now is None else now
        self._trim(t)
        return len(self._times) / self.window_s

    def age_s(self, now: float | None = None) -> float:
        """Seconds since the last event, -1 if none yet."""
        if self.last_time is None:
            return -1.0
        t = time.monotonic() if now is None else now
        return t - self.last_time


class CountRate:
    """A count whose rate is computed when read: counting is ``total += 1`` (no clock read
    per event, for counts bumped hundreds of times a second in a hot path); ``rate_hz``
    compares the count with the counts seen at earlier reads, the newest one at least
    ``window_s`` old (or the start). Read at least once a window, it is the rate over the
    last window or a little more; read more rarely, the mean since the last read."""

    def __init__(self, window_s: float = 1.0, now: float | None = None) -> None:
        self.window_s = window_s
        self.total = 0
        t = time.monotonic() if now is None else now
        self._marks: deque[tuple[float, int]] = deque([(t, 0)])

    def add(self, n: int = 1) -> None:
        self.total += n

    def rate_hz(self, now: float | None = None) -> float:
        t = time.monotonic() if now is None else now
        marks = self._marks
        cutoff = t - self.window_s
        while len(marks) > 1 and marks[1][0] <= cutoff:  # the newest mark a window old
            marks.popleft()
        t0, n0 = marks[0]
        if t - marks[-1][0] >= self.window_s / 8:  # a few marks a window, however often read
            marks.append((t, self.total))
        return (self.total - n0) / (t - t0) if t > t0 else 0.0
