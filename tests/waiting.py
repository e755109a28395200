"""Waiting for a condition in a test, bounded: never a sleep standing in for it. ``cond`` is
polled until it returns something truthy, which is returned; AssertionError (with what was
awaited and the last value) after ``timeout_s``."""

from __future__ import annotations

import asyncio
import time
from collections.abc import Callable
from typing import Any


def wait_until(cond: Callable[[], Any], timeout_s: float, interval_s: float = 0.1,
               what: str = "") -> Any:
    """Polls ``cond`` every ``interval_s`` (this thread sleeps between)."""
    deadline = time.monotonic() + timeout_s
    last = None
    while time.monotonic() < deadline:
        last = cond()
        if last:
            return last
        time.sleep(interval_s)
    raise AssertionError(f"timed out after {timeout_s} s waiting for {what or cond}: {last!r}")


async def until(cond: Callable[[], Any], timeout_s: float = 5.0, what: str = "",
                interval_s: float = 0.005) -> Any:
    """Polls ``cond`` every ``interval_s``, letting the event loop run between."""
    deadline = time.monotonic() + timeout_s
    while True:
        last = cond()
        if last:
            return last
        if time.monotonic() > deadline:
            raise AssertionError(f"timed out after {timeout_s} s waiting for {what or cond}: "
                                 f"{last!r}")
        await asyncio.sleep(interval_s)
