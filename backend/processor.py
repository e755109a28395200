"""Processors: units of work run in a loop, either at a fixed rate or on new data in a topic.

The runner measures what the UI shows: configured and actual rate, tick time (mean, p99),
overruns (a fixed-rate tick longer than its period), errors. An exception in one tick is
counted and logged (rate-limited); the processor keeps running.
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
import math
import time
from collections import deque
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

from sslnet.rate import RateCounter
from sslnet.ratelog import RateLimitedLog

from .bus import Topic

if TYPE_CHECKING:
    from .params.model import StationParams

log = logging.getLogger("touchline.processor")


@dataclass(frozen=True)
class Every:
    """Run at a fixed rate."""

    hz: float


@dataclass(frozen=True)
class OnTopic:
    """Run when the topic has new records (coalesced: one run for any number of new records).

    ``max_wait_s`` makes the processor also run when nothing arrived for that long, so a
    controller can command a stop when its input goes quiet.
    """

    topic: Topic[Any]
    max_wait_s: float | None = None


class Processor:
    """Base class. Subclasses implement ``tick``; ``setup``/``teardown`` are optional."""

    name = "processor"

    def __init__(self, trigger: Every | OnTopic | None) -> None:
        self.trigger = trigger
        self.stats = ProcessorStats()

    async def setup(self) -> None:
        return None

    async def tick(self) -> None:
        raise NotImplementedError

    async def wait_input(self) -> None:
        """For source processors (trigger None): wait until input is ready; not timed."""
        raise NotImplementedError

    async def teardown(self) -> None:
        return None

    def configure(self, params: StationParams) -> None:
        """Takes what this processor uses from a validated parameter set (the station calls it
        on every processor at start and on every change, between two ticks)."""
        return None

    def set_rate(self, hz: float) -> None:
        if not math.isfinite(hz) or hz <= 0:
            raise ValueError(f"{self.name}: rate must be a positive number, got {hz}")
        self.trigger = Every(hz)


class ProcessorStats:
    def __init__(self) -> None:
        self.rate = RateCounter(window_s=2.0)
        self.ticks_ms: deque[float] = deque(maxlen=512)
        self.overruns = 0
        self.errors = 0
        self.last_error = ""

    def record(self, duration_s: float) -> None:
        self.rate.add()
        self.ticks_ms.append(duration_s * 1000.0)

    def summary(self) -> dict[str, float]:
        ticks = sorted(self.ticks_ms)
        mean = sum(ticks) / len(ticks) if ticks else 0.0
        p99 = ticks[min(len(ticks) - 1, int(0.99 * len(ticks)))] if ticks else 0.0
        return {"measured_hz": self.rate.rate_hz(), "tick_mean_ms": mean, "tick_p99_ms": p99}


class Runner:
    """Runs processors as asyncio tasks and stops them in reverse order."""

    def __init__(self) -> None:
        self.processors: list[Processor] = []
        self._tasks: list[asyncio.Task[None]] = []
        self._errlog = RateLimitedLog(log, interval_s=10.0)

    def add(self, proc: Processor) -> Processor:
        self.processors.append(proc)
        return proc

    async def start(self) -> None:
        for proc in self.processors:
            await proc.setup()
            self._tasks.append(asyncio.create_task(self._loop(proc), name=proc.name))

    async def stop(self) -> None:
        for task in reversed(self._tasks):
            task.cancel()
        for task in reversed(self._tasks):
            with contextlib.suppress(asyncio.CancelledError):
                await task
        self._tasks.clear()
        for proc in reversed(self.processors):
            try:
                await proc.teardown()
            except Exception:  # teardown must not prevent the others
                log.exception("teardown of %s failed", proc.name)

    async def _run_once(self, proc: Processor) -> float:
        t0 = time.perf_counter()
        try:
            await proc.tick()
        except asyncio.CancelledError:
            raise
        except Exception as exc:
            proc.stats.errors += 1
            proc.stats.last_error = f"{type(exc).__name__}: {exc}"
            self._errlog.warning(proc.name, "processor %s tick failed: %s", proc.name,
                                 proc.stats.last_error)
            log.debug("traceback", exc_info=True)
        dt = time.perf_counter() - t0
        proc.stats.record(dt)
        return dt

    async def _loop(self, proc: Processor) -> None:
        if proc.trigger is None:  # a source processor: wait for input, then a timed tick
            while True:
                await proc.wait_input()
                await self._run_once(proc)
        next_t = time.monotonic()
        event: asyncio.Event | None = None
        event_topic: Topic[Any] | None = None
        try:
            while True:
                trig = proc.trigger
                if isinstance(trig, Every):
                    period = 1.0 / trig.hz
                    dt = await self._run_once(proc)
                    if dt > period:
                        proc.stats.overruns += 1
                    next_t += period
                    now = time.monotonic()
                    if next_t < now - period:  # fell far behind: don't burst to catch up
                        next_t = now
                    await asyncio.sleep(max(0.0, next_t - now))
                elif isinstance(trig, OnTopic):
                    if event_topic is not trig.topic:
                        if event is not None and event_topic is not None:
                            event_topic.unsubscribe_event(event)
                        event = trig.topic.subscribe_event()
                        event_topic = trig.topic
                        event.set()  # run once at once: records written before we subscribed
                    assert event is not None
                    if trig.max_wait_s is None:
                        await event.wait()
                    else:
                        with contextlib.suppress(TimeoutError):
                            await asyncio.wait_for(event.wait(), trig.max_wait_s)
                    event.clear()
                    await self._run_once(proc)
                    next_t = time.monotonic()
        finally:
            if event is not None and event_topic is not None:
                event_topic.unsubscribe_event(event)
