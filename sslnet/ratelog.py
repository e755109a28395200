"""Rate-limited logging: bad input is logged once, then summarised, never flooding the log."""

from __future__ import annotations

import logging
import time


class RateLimitedLog:
    """Logs the first occurrence of each key at once, then at most one summary per interval."""

    def __init__(self, logger: logging.Logger, interval_s: float = 5.0) -> None:
        self._logger = logger
        self._interval_s = interval_s
        self._last: dict[str, float] = {}
        self._suppressed: dict[str, int] = {}

    def warning(self, key: str, message: str, *args: object) -> None:
        self.log(logging.WARNING, key, message, *args)

    def log(self, level: int, key: str, message: str, *args: object) -> None:
        now = time.monotonic()
        last = self._last.get(key)
        if last is not None and now - last < self._interval_s:
            self._suppressed[key] = self._suppressed.get(key, 0) + 1
            return
        suppressed = self._suppressed.pop(key, 0)
        self._last[key] = now
        if suppressed:
            message = f"{message} ({suppressed} more since last report)"
        self._logger.log(level, message, *args)
