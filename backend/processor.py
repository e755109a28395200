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
from collections.abc import Callable, Coroutine, Generator
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

from sslnet.rate import CountRate
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
    """Base class. Subclasses implement ``step`` (work that never waits: a plain call, which
    the runner makes in its pass without a coroutine) or ``tick`` (a coroutine, for work
    that awaits); ``setup``/``teardown`` are optional."""

    name = "processor"

    def __init__(self, trigger: Every | OnTopic | None) -> None:
        self.trigger = trigger
        self.stats = ProcessorStats()

    async def setup(self) -> None:
        return None

    def step(self) -> None:
        """One tick as a plain call (a processor whose work never waits implements this)."""
        raise NotImplementedError

    async def tick(self) -> None:
        """One tick; by default the plain ``step``."""
        self.step()

    async def wait_input(self) -> None:
        """For source processors (trigger None): wait until input is ready; not timed."""
        raise NotImplementedError

    def watch_input(self, ready: Callable[[], None]) -> bool:
        """For source processors: have ``ready`` called on the running loop whenever input
        waits (a descriptor the loop watches), instead of a task waiting in ``wait_input``;
        the runner then runs the tick and the pass inside that call. False (the default):
        not supported, the runner's task waits in ``wait_input``."""
        return False

    #: for a watched source whose ``hold_pass`` holds the pass: the longest the runner lets
    #: a pass wait, from the first of its ticks that held it (seconds; 0: never held)
    hold_max_s = 0.0

    def hold_pass(self) -> float | None:
        """For a watched source (``watch_input``), asked after each of its ticks: seconds the
        pass may wait for more of its input (the rest of a burst of camera frames), or None
        (the default): the pass now. The runner does not wait in it: it goes back to the
        loop and runs the pass at that time (never later than ``hold_max_s`` after the first
        held tick) or after this source's next tick that answers None, whichever comes
        first, once; then it calls ``held_pass_ran``. Meanwhile every other pass (a timer's
        tick, a deadline, a topic written from outside: a stop never waits for the hold)
        runs as ever but leaves what this source wrote to the held one."""
        return None

    def held_pass_ran(self) -> None:
        """The pass this source held (``hold_pass``) has run: what its ticks wrote was read."""
        return None

    async def teardown(self) -> None:
        return None

    def configure(self, params: StationParams) -> None:
        """Takes what this processor uses from a validated parameter set (the station calls it
        on every processor at start and on every change, between two ticks)."""
        return None

    #: for a topic-triggered processor with a max wait that has ``wake_in_s``: the runner
    #: asks it again at least this often while waiting (None: at its deadlines only)
    wake_check_s: float | None = None

    def wake_in_s(self) -> float | None:
        """For a topic-triggered processor with a max wait: seconds until it must run
        though no input arrives, if that is sooner than its max wait (a deadline of its own:
        the control's stop when every camera went silent); None: its max wait only."""
        return None

    def set_rate(self, hz: float) -> None:
        if not math.isfinite(hz) or hz <= 0:
            raise ValueError(f"{self.name}: rate must be a positive number, got {hz}")
        self.trigger = Every(hz)


def plain_step(proc: Processor) -> Callable[[], None] | None:
    """``proc.step`` when the processor implements its tick as ``step`` (and not ``tick``),
    else None."""
    cls = type(proc)
    if cls.step is Processor.step or cls.tick is not Processor.tick:
        return None
    return proc.step


class ProcessorStats:
    """Cheap to keep (a run is an integer added and a duration appended), computed when read:
    the rate from the count (``CountRate``), the mean and p99 from the last 512 durations."""

    def __init__(self) -> None:
        self.rate = CountRate(window_s=2.0)
        self.ticks_s: deque[float] = deque(maxlen=512)
        self.overruns = 0
        self.errors = 0
        self.last_error = ""

    def record(self, duration_s: float) -> None:
        self.rate.total += 1
        self.ticks_s.append(duration_s)

    @property
    def ticks_ms(self) -> list[float]:
        return [t * 1000.0 for t in self.ticks_s]

    def summary(self) -> dict[str, float]:
        ticks = sorted(self.ticks_s)
        mean = sum(ticks) / len(ticks) * 1000.0 if ticks else 0.0
        p99 = ticks[min(len(ticks) - 1, int(0.99 * len(ticks)))] * 1000.0 if ticks else 0.0
        return {"measured_hz": self.rate.rate_hz(), "tick_mean_ms": mean, "tick_p99_ms": p99}


class _Rest:
    """Awaits the rest of a coroutine that suspended on its first step (its first yield is
    handed on to the task, which resumes it as if it had been awaited from the start)."""

    __slots__ = ("coro", "first")

    def __init__(self, coro: Coroutine[Any, Any, None], first: Any) -> None:
        self.coro, self.first = coro, first

    def __await__(self) -> Generator[Any, Any, None]:
        coro, out = self.coro, self.first
        while True:
            try:
                got = yield out
            except BaseException as exc:  # cancelled (or thrown into): the coroutine's turn
                try:
                    out = coro.throw(exc)
                except StopIteration:
                    return
            else:
                try:
                    out = coro.send(got)
                except StopIteration:
                    return


class _Waiting:
    """A coroutine tick that waits: its coroutine, suspended on its first yield, and what
    it yielded; its processor and the time it began. ``Runner._finish`` finishes it in a
    task, made only when that task runs: a task cancelled before it ran (the runner
    stopped in between) left a coroutine never awaited, and the tick open until collected.
    """

    __slots__ = ("coro", "first", "proc", "t0")

    def __init__(self, proc: Processor, coro: Coroutine[Any, Any, None], first: Any,
                 t0: float) -> None:
        self.proc, self.coro, self.first, self.t0 = proc, coro, first, t0

    def close_if_cancelled(self, task: asyncio.Task[None]) -> None:
        """The done callback of the task that was to finish it: cancelled before it ran,
        the tick's coroutine is closed now (GeneratorExit where it waits). Once the task
        ran, the tick got the cancellation and is over: closing it again does nothing."""
        if task.cancelled():
            self.coro.close()


class _Link:
    """A topic-triggered processor in the pass: its topic, the newest sequence number it has
    seen, a run asked for by its max wait, the time of its last run."""

    __slots__ = ("due", "last_run", "proc", "seen", "step", "topic", "trigger")

    def __init__(self, proc: Processor, trigger: OnTopic) -> None:
        self.proc = proc
        self.trigger = trigger
        self.topic = trigger.topic
        self.seen = 0
        self.due = True  # once at the start, like after new records
        self.last_run = time.perf_counter()
        self.step = plain_step(proc)


class Runner:
    """Runs processors and stops them in reverse order.

    **One pass per input.** A source processor (socket, log player) or a fixed-rate one runs;
    when its tick is done, every processor triggered by a topic that got new records runs at
    once, in the order they were added (the pipeline's order), again and again until nothing
    new is left: one camera frame goes from the ZeroMQ socket through decoding, the world
    model, control and the command publisher in one synchronous pass. A source that signals
    its input through the loop (``Processor.watch_input``: the relay's ZeroMQ descriptor) is
    ticked and followed by its pass inside that callback, and a fixed-rate processor inside
    a timer's: no task, no future, no second turn of the event loop per frame. Processors
    implementing ``step`` are plain calls; a coroutine ``tick`` is stepped by hand and
    finishes there unless it really waits (then it, and the rest of its pass, go on in a
    task). A watched source may hold the pass after its tick (``Processor.hold_pass``: the
    relay ingest, for the rest of a burst of camera frames): the runner goes back to the loop
    with a timer and runs the pass at its time or once the source's input is whole, never
    blocking the thread; every other pass meanwhile (a timer's, a deadline's: a stop) runs
    at once and leaves the held input to the held pass. A topic written from outside a pass
    (an operator's command between two ticks) starts a pass of its own, once per burst.
    Topic-triggered processors with ``max_wait_s`` also run when nothing arrived for that
    long (a task per processor sleeps until that deadline).

    Stats are counters bumped in the pass (``ProcessorStats``); rates are computed when read.
    """

    def __init__(self) -> None:
        self.processors: list[Processor] = []
        self._tasks: list[asyncio.Task[None]] = []
        self._errlog = RateLimitedLog(log, interval_s=10.0)
        #: topic-triggered processors in pipeline order
        self._links: list[_Link] = []
        self._link_of: dict[int, _Link] = {}
        self._watched: set[int] = set()  # ids of the topics with a hook
        self._passing = False
        self._ticking = 0  # source and fixed-rate ticks under way (a pass follows each)
        self._pass_scheduled = False
        self._loop: asyncio.AbstractEventLoop | None = None
        #: the task going on with a pass whose tick waited, and the sources that became
        #: ready meanwhile (run when it is over)
        self._later: asyncio.Task[None] | None = None
        self._ready_after: list[Callable[[], None]] = []
        #: the next timer of each fixed-rate processor
        self._timers: dict[int, asyncio.Handle] = {}
        #: the clock (perf_counter) at the end of the last tick ``_run_now`` finished: the
        #: start of the pass that follows a source's tick
        self._t_end = 0.0
        #: a pass held by a watched source (``Processor.hold_pass``): the source, its timer,
        #: the timer's time and the time the pass is held until (it moves on with each held
        #: tick; the timer is set again when it fires before), the hold's last possible time
        #: (loop.time()); the links reading what the source wrote meanwhile (every other
        #: pass leaves them to the held one)
        self._held_by: Processor | None = None
        self._held_links: set[_Link] = set()
        self._hold_timer: asyncio.TimerHandle | None = None
        self._hold_at = self._hold_until = self._hold_end = 0.0
        #: topics a write to which ends a held pass at once (``end_hold_on``)
        self._ending: list[Topic[Any]] = []

    def add(self, proc: Processor) -> Processor:
        self.processors.append(proc)
        return proc

    async def start(self) -> None:
        self._loop = asyncio.get_running_loop()
        for proc in self.processors:
            await proc.setup()
            self._chain(proc)
            if proc.trigger is None and proc.watch_input(self._source_ready(proc)):
                continue  # ticked from the loop's callback: no task
            if isinstance(proc.trigger, Every):
                self._every(proc)  # a timer of the loop: no task
                continue
            self._tasks.append(asyncio.create_task(self._loop_of(proc), name=proc.name))
        self._request_pass()

    def _chain(self, proc: Processor) -> None:
        """A topic-triggered processor joins the pass (in the order added)."""
        if isinstance(proc.trigger, OnTopic):
            link = _Link(proc, proc.trigger)
            self._links.append(link)
            self._link_of[id(proc)] = link
            self._watch(proc.trigger.topic)

    async def stop(self) -> None:
        self._loop = None  # no pass is scheduled from here on
        if self._hold_timer is not None:
            self._hold_timer.cancel()
            self._hold_timer = None
        self._held_by = None
        self._held_links.clear()
        for topic in self._ending:
            topic.on_write = None
        self._ending.clear()
        for timer in self._timers.values():
            timer.cancel()
        self._timers.clear()
        tasks = list(reversed(self._tasks))
        for task in tasks:
            task.cancel()
        for task in tasks:
            with contextlib.suppress(asyncio.CancelledError):
                await task
        self._tasks.clear()
        for link in self._links:
            link.topic.on_write = None
        self._watched.clear()
        self._links.clear()
        self._link_of.clear()
        for proc in reversed(self.processors):
            try:
                await proc.teardown()
            except Exception:  # teardown must not prevent the others
                log.exception("teardown of %s failed", proc.name)

    def _watch(self, topic: Topic[Any]) -> None:
        if id(topic) not in self._watched:
            self._watched.add(id(topic))
            topic.on_write = self._written

    def _relink(self, link: _Link) -> None:
        """The processor's trigger changed (configure): its topic and max wait from now on."""
        trig = link.proc.trigger
        if not isinstance(trig, OnTopic):
            raise RuntimeError(f"{link.proc.name}: a topic-triggered processor stays so")
        if trig.topic is not link.topic:
            link.seen = 0
        link.trigger, link.topic = trig, trig.topic
        self._watch(trig.topic)

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
            self._pass_now()

    # ---- running a tick ----

    def _failed(self, proc: Processor, exc: Exception) -> None:
        proc.stats.errors += 1
        proc.stats.last_error = f"{type(exc).__name__}: {exc}"
        self._errlog.warning(proc.name, "processor %s tick failed: %s", proc.name,
                             proc.stats.last_error)
        log.debug("traceback", exc_info=True)

    def _run_now(self, proc: Processor, step: Callable[[], None] | None,
                 t0: float) -> _Waiting | None:
        """Runs one tick from ``t0`` (perf_counter) and records it. A coroutine tick that
        waits is not finished here: it is returned (the caller awaits ``_finish`` of it, or
        has a task do so)."""
        try:
            if step is not None:
                step()
            else:
                coro = proc.tick()
                try:
                    first = coro.send(None)
                except StopIteration:
                    pass
                else:
                    return _Waiting(proc, coro, first, t0)
        except Exception as exc:
            self._failed(proc, exc)
        self._t_end = t1 = time.perf_counter()
        proc.stats.record(t1 - t0)
        return None

    async def _finish(self, waiting: _Waiting) -> None:
        """The rest of a tick that waited, recorded like one that did not."""
        proc = waiting.proc
        try:
            await _Rest(waiting.coro, waiting.first)
        except asyncio.CancelledError:
            raise
        except Exception as exc:
            self._failed(proc, exc)
        proc.stats.record(time.perf_counter() - waiting.t0)

    async def _run_once(self, proc: Processor) -> float:
        """One timed tick of ``proc``, waiting for it if it waits."""
        t0 = time.perf_counter()
        waiting = self._run_now(proc, plain_step(proc), t0)
        if waiting is not None:
            await self._finish(waiting)
        return time.perf_counter() - t0

    # ---- the pass ----

    def _pass_now(self, t: float | None = None) -> None:
        """Runs every topic-triggered processor whose topic has new records (or whose max
        wait is up), in pipeline order, until none is left. One pass at a time: a pass asked
        for during another is the other's next round. A tick that really waits hands the
        rest of the pass to a task. ``t``: the clock (perf_counter) now, if just read.

        The clock is read once between two ticks: the end of one is the start of the next
        (what the runner does between them, a few tests, counts in the next one's time), and
        a plain step is run and recorded here (``_run_now``'s work, without its call and the
        stats' ``record``: four ticks a camera frame)."""
        if self._passing:
            return
        # a pass held by a source: this one (not the held one) leaves what the source wrote
        held = self._held_links if self._held_by is not None else None
        self._passing = True
        clock = time.perf_counter
        if t is None:
            t = clock()
        try:
            again = True
            while again:
                again = False
                for link in self._links:
                    if link.proc.trigger is not link.trigger:
                        self._relink(link)
                    seq = link.topic._seq
                    if (seq == link.seen and not link.due) or (held and link in held):
                        continue
                    link.seen = seq
                    link.due = False
                    link.last_run = t0 = t
                    again = True
                    step = link.step
                    if step is not None:
                        try:
                            step()
                        except Exception as exc:
                            self._failed(link.proc, exc)
                        t = clock()
                        stats = link.proc.stats
                        stats.rate.total += 1  # (ProcessorStats.record, inline)
                        stats.ticks_s.append(t - t0)
                        continue
                    rest = self._run_now(link.proc, None, t0)
                    if rest is not None:  # the rest of the pass after this tick
                        self._continue_later(rest)
                        return
                    t = clock()
        except BaseException:
            self._passing = False
            raise
        self._passing = False

    # ---- a pass held by a source ----

    def _hold(self, proc: Processor, wait_s: float) -> bool:
        """``proc``'s tick asked to hold the pass for ``wait_s``: True if it is held (a timer
        at its time, capped by ``hold_max_s`` from the hold's first tick), False if the pass
        is to run now (another source holds it, or the cap is reached)."""
        loop = self._loop
        assert loop is not None
        now = loop.time()
        if self._held_by is None:
            self._held_by, self._hold_end = proc, now + proc.hold_max_s
        elif self._held_by is not proc:
            return False
        until = min(now + wait_s, self._hold_end)
        if until <= now:
            return False
        # what the source wrote so far is the held pass's (a few links: only held ticks)
        self._held_links.update(link for link in self._links if link.topic._seq != link.seen)
        self._hold_until = until
        timer = self._hold_timer
        # one timer a hold: a later time waits for it to fire (``_held``), an earlier one
        # (the cap, a shorter wait) replaces it
        if timer is None or until < self._hold_at:
            if timer is not None:
                timer.cancel()
            self._hold_at = until
            self._hold_timer = loop.call_at(until, self._held)
        return True

    def end_hold_on(self, topic: Topic[Any]) -> None:
        """A write to ``topic`` (the emergency stop: control reads it in the pass, it does
        not trigger one) ends a held pass: it runs in the loop's next turn, so the stop
        is not held behind the rest of a burst. Without a hold nothing changes."""
        if topic.on_write is not None:
            raise RuntimeError(f"topic {topic.name!r} already has a writer hook")
        self._ending.append(topic)

        def written() -> None:
            if self._held_by is not None and self._loop is not None:
                self._loop.call_soon(self._end_hold)

        topic.on_write = written

    def _end_hold(self) -> None:
        if self._held_by is not None and self._loop is not None:
            self._release()
            self._pass_now()

    def _held(self) -> None:
        """The held pass's timer: the pass, unless its time moved on meanwhile."""
        self._hold_timer = None
        loop = self._loop
        if loop is None or self._held_by is None:
            return
        if self._hold_until > self._hold_at:
            self._hold_at = self._hold_until
            self._hold_timer = loop.call_at(self._hold_until, self._held)
            return
        self._release()
        self._pass_now()

    def _release(self) -> None:
        """The held pass is to run now: no timer, nothing held, and its source told."""
        src, self._held_by = self._held_by, None
        self._held_links.clear()
        if self._hold_timer is not None:
            self._hold_timer.cancel()
            self._hold_timer = None
        if src is not None:
            src.held_pass_ran()

    def _continue_later(self, rest: _Waiting) -> None:
        """A tick of the pass waits: the pass (still ``_passing``) goes on in a task."""
        async def go_on() -> None:
            try:
                await self._finish(rest)
            finally:
                self._passing = False
            if self._loop is not None:
                self._pass_now()
            if not self._passing:
                ready, self._ready_after = self._ready_after, []
                for fn in ready:
                    fn()

        self._later = self._spawn(self._loop or asyncio.get_running_loop(), go_on(),
                                  waiting=rest)

    def _spawn(self, loop: asyncio.AbstractEventLoop, coro: Coroutine[Any, Any, None],
               name: str | None = None, waiting: _Waiting | None = None) -> asyncio.Task[None]:
        """A task of the runner's (cancelled at stop, forgotten when done). ``waiting``: the
        tick it finishes, closed if the task is cancelled before it ran."""
        task = loop.create_task(coro, name=name)
        self._tasks.append(task)
        task.add_done_callback(self._forget_task)
        if waiting is not None:
            task.add_done_callback(waiting.close_if_cancelled)
        return task

    def _forget_task(self, task: asyncio.Task[None]) -> None:
        with contextlib.suppress(ValueError):
            self._tasks.remove(task)

    async def _pass(self) -> None:
        """The pass, for a caller on a coroutine: returns when the pass (and a rest of it
        in a task, if one of its ticks waited) is over."""
        self._pass_now()
        while self._passing and self._later is not None:  # a tick of it waits in a task
            await asyncio.wait([self._later])

    # ---- sources and fixed-rate processors ----

    def _source_ready(self, proc: Processor) -> Callable[[], None]:
        """The callback a watched source calls when input waits: its tick, then the pass,
        in this call."""
        step = plain_step(proc)
        clock = time.perf_counter
        # only a source that may hold its pass is asked
        hold = proc.hold_pass if type(proc).hold_pass is not Processor.hold_pass else None

        def ready() -> None:
            if self._loop is None:  # stopped
                return
            if self._passing:  # the pass waits in a task: take the input after it
                if ready not in self._ready_after:
                    self._ready_after.append(ready)
                return
            self._ticking += 1
            try:
                rest = self._run_now(proc, step, clock())
            finally:
                self._ticking -= 1
            if rest is not None:  # a source tick that waits: finished in a task
                self._continue_later(rest)
                return
            if hold is not None:
                try:
                    wait_s = hold()
                except Exception as exc:  # counted like its tick's: the pass now
                    self._failed(proc, exc)
                    wait_s = None
                if wait_s is not None and self._hold(proc, wait_s):
                    return  # back to the loop: the pass at the hold's time or sooner
            if self._held_by is not None:  # the held pass, now (or another source's)
                self._release()
            self._pass_now(self._t_end)

        return ready

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
        await self._deadlines(proc)

    def _every(self, proc: Processor) -> None:
        """A fixed-rate processor on a timer of the loop (``call_at``): its tick and the pass
        in the timer's callback. A tick that waits (the strategy's, for its worker thread)
        finishes in a task, then the pass, then the next timer."""
        loop = self._loop
        assert loop is not None
        clock = time.perf_counter
        next_t = loop.time()

        def schedule(period: float) -> None:
            nonlocal next_t
            if self._loop is None:
                return
            next_t += period
            now = loop.time()
            if next_t < now - period:  # fell far behind: don't burst to catch up
                next_t = now
            self._timers[id(proc)] = loop.call_at(next_t, fire)

        def ticked(dt: float, period: float) -> None:
            if dt > period:
                proc.stats.overruns += 1
            self._pass_now()
            schedule(period)

        def fire() -> None:
            if self._loop is None:
                return
            if self._passing:  # a pass waits in a task: this tick after it
                self._ready_after.append(fire)
                return
            trig = proc.trigger
            if not isinstance(trig, Every):  # configured into another trigger: not supported
                raise RuntimeError(f"{proc.name}: a fixed-rate processor stays fixed-rate")
            period = 1.0 / trig.hz
            t0 = clock()
            self._ticking += 1
            try:
                rest = self._run_now(proc, plain_step(proc), t0)
            finally:
                if rest is None:
                    self._ticking -= 1
            if rest is None:
                ticked(clock() - t0, period)
                return

            async def finish(rest: _Waiting) -> None:
                try:
                    await self._finish(rest)
                finally:
                    self._ticking -= 1
                if self._loop is not None:
                    ticked(clock() - t0, period)

            self._spawn(loop, finish(rest), proc.name, waiting=rest)

        self._timers[id(proc)] = loop.call_soon(fire)

    async def _deadlines(self, proc: Processor) -> None:
        """A topic-triggered processor with ``max_wait_s``: runs it when it has not run for
        that long (its input went quiet), or sooner when it says so (``wake_in_s``: asked
        again at every wake-up, and at least every ``wake_check_s``). Without a max wait
        there is nothing to do here."""
        link = self._link_of[id(proc)]
        check = proc.wake_check_s
        while True:
            trig = proc.trigger
            if not isinstance(trig, OnTopic):
                raise RuntimeError(f"{proc.name}: a topic-triggered processor stays so")
            if trig.max_wait_s is None:
                await asyncio.Event().wait()  # forever (cancelled at stop)
                return
            due = link.last_run + trig.max_wait_s
            now = time.perf_counter()
            soon = proc.wake_in_s()
            # (a deadline passed is served by any run since: run and still due, its tick
            # failed, and it waits for its max wait, no spinning on it)
            if soon is not None and now + soon > link.last_run:
                due = min(due, now + soon)
            if now < due:
                await asyncio.sleep(due - now if check is None else min(due - now, check))
                continue
            link.due = True
            if self._passing:  # the pass under way runs it in its next round
                link.last_run = now
                # (its own deadline stays due until then: not asked again at once)
                await asyncio.sleep(trig.max_wait_s if check is None
                                    else min(trig.max_wait_s, check))
                continue
            self._pass_now()
