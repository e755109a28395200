"""Wall-clock times as people read them, one way everywhere.

What an operator reads (a log line, a refusal, a health warning, a file name) is in the
station machine's local time, the time on the operators' watches at the field; data written
for other programs (``python -m ssllog info``, exports) is ISO 8601 in UTC, marked as such.
"""

from __future__ import annotations

import time
from datetime import UTC, datetime


def clock(unix_s: float) -> str:
    """"14:03:07": the local time of day (a message about something minutes ago)."""
    return time.strftime("%H:%M:%S", time.localtime(unix_s))


def date_clock(unix_s: float) -> str:
    """"2026-11-29 14:03:07": local date and time (a state that may be days old)."""
    return time.strftime("%Y-%m-%d %H:%M:%S", time.localtime(unix_s))


def file_stamp(unix_s: float | None = None) -> str:
    """"20261129-140307": local date and time for a file name (sorts by time); now by default."""
    return time.strftime("%Y%m%d-%H%M%S", time.localtime(unix_s))


def iso_utc(unix_s: float) -> str:
    """"2026-11-29T13:03:07.250+00:00": UTC with milliseconds, for data."""
    return datetime.fromtimestamp(unix_s, UTC).isoformat(timespec="milliseconds")
