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
    """Runs processors and stops them in reverse order.

    **One pass per input.** A source processor (socket, log player) or a fixed-rate one runs
    in its own task; when its tick is done, every processor triggered by a topic that got new
    records runs at once, in the order they were added (the pipeline's order), again and again
    until nothing new is left: one camera frame goes from the ZeroMQ socket through decoding,
    the world model, control and the command publisher in one synchronous pass, without a
    wake-up of the event loop between two stages. A topic written from outside a pass (an
    operator's command between two ticks) starts a pass of its own, once per burst.
    Topic-triggered processors with ``max_wait_s`` also run when nothing arrived for that
    long (a task per processor sleeps until that deadline)."""

    def __init__(self) -> None:
        self.processors: list[Processor] = []
        self._tasks: list[asyncio.Task[None]] = []
        self._errlog = RateLimitedLog(log, interval_s=10.0)
        #: topic-triggered processors in pipeline order, with the sequence number of their
        #: topic they have seen and the monotonic time of their last run
        self._chained: list[Processor] = []
        self._seen: dict[int, int] = {}
        self._last_run: dict[int, float] = {}
        self._due: set[int] = set()  # deadline runs asked for while a pass was going on
        self._watched: set[int] = set()  # ids of the topics with a hook
        self._passing = False
        self._ticking = 0  # source and fixed-rate ticks under way (a pass follows each)
        self._pass_scheduled = False
        self._loop: asyncio.AbstractEventLoop | None = None

    def add(self, proc: Processor) -> Processor:
        self.processors.append(proc)
        return proc

    async def start(self) -> None:
        self._loop = asyncio.get_running_loop()
        for proc in self.processors:
            await proc.setup()
            self._chain(proc)
            self._tasks.append(asyncio.create_task(self._loop_of(proc), name=proc.name))
        self._request_pass()

    def _chain(self, proc: Processor) -> None:
        """A topic-triggered processor joins the pass (in the order added)."""
        if isinstance(proc.trigger, OnTopic):
            self._chained.append(proc)
            self._seen[id(proc)] = 0
            self._due.add(id(proc))  # once at the start, like after new records
            self._last_run[id(proc)] = time.monotonic()
            self._watch(proc.trigger.topic)

    async def stop(self) -> None:
        self._loop = None  # no pass is scheduled from here on
        tasks = list(reversed(self._tasks))
        for task in tasks:
            task.cancel()
        for task in tasks:
            with contextlib.suppress(asyncio.CancelledError):
                await task
        self._tasks.clear()
        for proc in self._chained:
            if isinstance(proc.trigger, OnTopic):
                proc.trigger.topic.on_write = None
        self._watched.clear()
        self._chained.clear()
        for proc in reversed(self.processors):
            try:
                await proc.teardown()
            except Exception:  # teardown must not prevent the others
                log.exception("teardown of %s failed", proc.name)

    def _watch(self, topic: Topic[Any]) -> None:
        if id(topic) not in self._watched:
            self._watched.add(id(topic))
            topic.on_write = self._written

    def _written(self) -> None:
        """A watched topic got a record: a pass follows the tick under way, if there is one;
        else (written between two ticks) one is scheduled."""
        if not self._passing and not self._ticking:
            self._request_pass()

    def _request_pass(self) -> None:
        loop = self._loop
        if self._pass_scheduled or loop is None:
            return
        self._pass_scheduled = True
        loop.call_soon(self._scheduled_pass)

    def _scheduled_pass(self) -> None:
        self._pass_scheduled = False
        if self._loop is not None:
            task = self._loop.create_task(self._pass())
            self._tasks.append(task)
            task.add_done_callback(self._forget_task)

    def _forget_task(self, task: asyncio.Task[None]) -> None:
        with contextlib.suppress(ValueError):
            self._tasks.remove(task)

    async def _pass(self) -> None:
        """Runs every topic-triggered processor whose topic has new records (or whose max
        wait is up), in pipeline order, until none is left. One pass at a time: a pass asked
        for during another is the other's next round."""
        if self._passing:
            return
        self._passing = True
        try:
            again = True
            while again:
                again = False
                for proc in self._chained:
                    trig = proc.trigger
                    if not isinstance(trig, OnTopic):
                        continue
                    if trig.topic.on_write is None:  # the trigger changed topic (configure)
                        self._watch(trig.topic)
                    key = id(proc)
                    seq = trig.topic.seq
                    if seq == self._seen[key] and key not in self._due:
                        continue
                    self._seen[key] = seq
                    self._due.discard(key)
                    self._last_run[key] = time.monotonic()
                    await self._run_once(proc)
                    again = True
        finally:
            self._passing = False

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

    async def _tick_then_pass(self, proc: Processor) -> float:
        self._ticking += 1
        try:
            dt = await self._run_once(proc)
        finally:
            self._ticking -= 1
        await self._pass()
        return dt

    async def _loop_of(self, proc: Processor) -> None:
        if proc.trigger is None:  # a source processor: wait for input, then a timed tick
            while True:
                await proc.wait_input()
                await self._tick_then_pass(proc)
        if isinstance(proc.trigger, OnTopic):
            await self._deadlines(proc)
            return
        next_t = time.monotonic()
        while True:
            trig = proc.trigger
            if not isinstance(trig, Every):  # configured into another trigger: not supported
                raise RuntimeError(f"{proc.name}: a fixed-rate processor stays fixed-rate")
            period = 1.0 / trig.hz
            dt = await self._tick_then_pass(proc)
            if dt > period:
                proc.stats.overruns += 1
            next_t += period
            now = time.monotonic()
            if next_t < now - period:  # fell far behind: don't burst to catch up
                next_t = now
            await asyncio.sleep(max(0.0, next_t - now))

    async def _deadlines(self, proc: Processor) -> None:
        """A topic-triggered processor with ``max_wait_s``: runs it when it has not run for
        that long (its input went quiet). Without a max wait there is nothing to do here."""
        key = id(proc)
        while True:
            trig = proc.trigger
            if not isinstance(trig, OnTopic):
                raise RuntimeError(f"{proc.name}: a topic-triggered processor stays so")
            if trig.max_wait_s is None:
                await asyncio.Event().wait()  # forever (cancelled at stop)
                return
            due = self._last_run[key] + trig.max_wait_s
            now = time.monotonic()
            if now < due:
                await asyncio.sleep(due - now)
                continue
            self._due.add(key)
            if self._passing:  # the pass under way runs it in its next round
                self._last_run[key] = now
                continue
            await self._pass()
