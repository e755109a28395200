"""The station thread: the bus and every processor run on their own event loop, so web traffic
(JSON encoding, websocket sends) never delays control. The web side changes station state only
through the command queue (``call``) and reads what the station publishes."""

from __future__ import annotations

import asyncio
import concurrent.futures
import cProfile
import ctypes
import gc
import logging
import os
import sys
import threading
import time
from collections.abc import Awaitable, Callable
from typing import Any, TypeVar

log = logging.getLogger("touchline.station")
T = TypeVar("T")

PROFILE_ENV = "TOUCHLINE_PROFILE"


def _name_native_thread(name: str) -> None:
    """Names the calling thread for the OS too (Linux: /proc/PID/task/TID/comm), so per-thread
    CPU figures (bench/loop_bench.py, top -H) tell the station thread from the others.
    Best effort: elsewhere nothing happens."""
    if not sys.platform.startswith("linux"):
        return
    try:
        libc = ctypes.CDLL(None, use_errno=True)
        libc.prctl(15, name.encode()[:15], 0, 0, 0)  # PR_SET_NAME
    except (OSError, AttributeError):
        pass


SWITCH_INTERVAL_ENV = "TOUCHLINE_SWITCH_INTERVAL_S"
DEFAULT_SWITCH_INTERVAL_S = 0.0005


def switch_interval_s() -> float:
    """The GIL switch interval the station runs with: how long another thread may hold the GIL
    while the station thread waits for it (the default 5 ms of Python would be the station's
    worst wait). ``TOUCHLINE_SWITCH_INTERVAL_S`` overrides it (benches); a value that is not a
    positive number is ignored with a warning."""
    raw = os.environ.get(SWITCH_INTERVAL_ENV, "")
    if not raw:
        return DEFAULT_SWITCH_INTERVAL_S
    try:
        value = float(raw)
    except ValueError:
        value = -1.0
    if not (0.0 < value <= 1.0):
        log.warning("%s=%r is not a number of seconds in (0, 1]: %g s used",
                    SWITCH_INTERVAL_ENV, raw, DEFAULT_SWITCH_INTERVAL_S)
        return DEFAULT_SWITCH_INTERVAL_S
    return value


class StationLoop:
    """Runs ``start()`` on a new event loop in its own thread, keeps the loop running until
    ``stop_thread``, then runs ``stop()``. ``after_command`` runs on the loop after every
    command (the station publishes fresh views, so the next read sees the change)."""

    def __init__(self, start: Callable[[], Awaitable[None]], stop: Callable[[], Awaitable[None]],
                 after_command: Callable[[], None] = lambda: None) -> None:
        self._start, self._stop, self._after_command = start, stop, after_command
        self.loop: asyncio.AbstractEventLoop | None = None
        self.thread: threading.Thread | None = None
        self._stop_event: asyncio.Event | None = None

    @property
    def running(self) -> bool:
        """The station thread runs (started, not stopped)."""
        return self.thread is not None and self.thread.is_alive()

    def start_thread(self) -> None:
        """Starts the station loop in its own thread and returns once it runs."""
        ready = threading.Event()
        errors: list[BaseException] = []

        def main() -> None:
            _name_native_thread("station")
            loop = asyncio.new_event_loop()
            # the strategy's worker (asyncio.to_thread) named too
            loop.set_default_executor(concurrent.futures.ThreadPoolExecutor(
                thread_name_prefix="station-worker", initializer=_name_native_thread,
                initargs=("station-worker",)))
            asyncio.set_event_loop(loop)
            stop_event = asyncio.Event()
            self._stop_event = stop_event

            async def run() -> None:
                try:
                    await self._start()
                except BaseException as exc:
                    errors.append(exc)
                    ready.set()
                    raise
                self.loop = loop
                _schedule_profile(loop)
                _schedule_memory_diff(loop)
                ready.set()
                await stop_event.wait()
                await self._stop()

            try:
                loop.run_until_complete(run())
            except BaseException:
                log.exception("station loop ended with an error")
            finally:
                self.loop = None
                loop.close()

        # control latency: let the station thread take the GIL back quickly from web work and
        # the strategy's worker (TOUCHLINE_SWITCH_INTERVAL_S: another value, for benches)
        sys.setswitchinterval(switch_interval_s())
        self.thread = threading.Thread(target=main, name="station", daemon=True)
        self.thread.start()
        if not ready.wait(30):
            raise RuntimeError("station did not start within 30 s")
        if errors:
            raise RuntimeError(f"station failed to start: {errors[0]}") from errors[0]

    def stop_thread(self) -> None:
        loop, ev = self.loop, self._stop_event
        if loop is not None and ev is not None:
            loop.call_soon_threadsafe(ev.set)
        if self.thread is not None:
            self.thread.join(timeout=10)
            self.thread = None

    def schedule(self, fn: Callable[..., T], *args: Any) -> concurrent.futures.Future[T]:
        """Runs ``fn(*args)`` on the station loop (at once when called on it, or before the
        loop runs); its result or exception in the future."""
        fut: concurrent.futures.Future[T] = concurrent.futures.Future()

        def run() -> None:
            try:
                fut.set_result(fn(*args))
            except BaseException as exc:  # handed to the caller
                fut.set_exception(exc)

        loop = self.loop
        if loop is None or threading.current_thread() is self.thread:
            run()
        else:
            loop.call_soon_threadsafe(run)
        return fut

    def command(self, fn: Callable[..., T], *args: Any) -> concurrent.futures.Future[T]:
        """Queues ``fn(*args)`` for the station loop (between two ticks), then
        ``after_command``."""
        def command() -> T:
            try:
                return fn(*args)
            finally:
                if self.loop is not None:
                    self._after_command()
        return self.schedule(command)

    async def call(self, fn: Callable[..., T], *args: Any) -> T:
        """The one way the web side changes station state (the command queue): runs
        ``fn(*args)`` on the station loop and returns its result."""
        return await asyncio.wrap_future(self.command(fn, *args))

    async def read(self, fn: Callable[..., T], *args: Any) -> T:
        """Runs ``fn(*args)`` on the station loop for an answer that must be current (not the
        published views): the station thread reads its own state."""
        return await asyncio.wrap_future(self.schedule(fn, *args))

    def call_sync(self, fn: Callable[..., T], *args: Any, timeout_s: float = 5.0) -> T:
        """``call`` for a thread without an event loop (tests, scripts)."""
        return self.command(fn, *args).result(timeout=timeout_s)


def _schedule_profile(loop: asyncio.AbstractEventLoop) -> None:
    """With ``TOUCHLINE_PROFILE=FILE`` (bench/profile_station.py) the station thread runs
    under cProfile from ``TOUCHLINE_PROFILE_AFTER`` s after the start (default 5) for
    ``TOUCHLINE_PROFILE_FOR`` s (default 15), then writes the statistics to FILE. With
    ``TOUCHLINE_PROFILE_CLOCK=cpu`` it counts the thread's CPU time instead of the wall clock
    (a send that wakes another thread, or a wait in epoll, then costs only what it burns)."""
    out = os.environ.get(PROFILE_ENV)
    if not out:
        return
    after = float(os.environ.get(PROFILE_ENV + "_AFTER", "5"))
    span = float(os.environ.get(PROFILE_ENV + "_FOR", "15"))
    cpu = os.environ.get(PROFILE_ENV + "_CLOCK", "wall") == "cpu"
    prof = cProfile.Profile(time.thread_time) if cpu else cProfile.Profile()

    def stop() -> None:
        prof.disable()
        prof.dump_stats(out)
        log.info("station profile of %.0f s written to %s", span, out)

    def start() -> None:
        prof.enable()
        loop.call_later(span, stop)

    loop.call_later(after, start)


#: start-up objects are frozen once the station runs, and once more this much later (what
#: the first ticks, requests and the compute engine imported or built on first use)
FREEZE_AGAIN_S = 15.0


def freeze_start_up(loop: asyncio.AbstractEventLoop) -> None:
    """``gc.freeze()`` now and again after ``FREEZE_AGAIN_S``: the objects alive then (modules,
    classes, the FastAPI app, processors, parameter models: ~105 000 at full scale) move to
    the collector's permanent generation, so a full collection looks only at what came
    later. Each full collection went over all of them, holding the GIL (whichever thread
    triggers it, the station thread waits): 65 ms of CPU at full scale, 444 ms seen on a
    busy machine while a log was indexed; 0.5 ms frozen (bench/tracker_gaps.py with
    TOUCHLINE_STALL_DUMP). What is frozen is freed by its reference count as before; only a
    reference cycle among frozen objects would stay (start-up objects live as long as the
    process anyway)."""
    gc.freeze()
    loop.call_later(FREEZE_AGAIN_S, gc.freeze)


MEMORY_ENV = "TOUCHLINE_MEMORY_DIFF"


def _schedule_memory_diff(loop: asyncio.AbstractEventLoop) -> None:
    """With ``TOUCHLINE_MEMORY_DIFF=FILE`` (a memory-growth hunt, bench/soak.py) tracemalloc
    runs from the start; a snapshot at ``..._AFTER`` s (default 30) and one ``..._FOR`` s later
    (default 120) are compared and the 25 biggest growths written to FILE."""
    out = os.environ.get(MEMORY_ENV)
    if not out:
        return
    import tracemalloc

    after = float(os.environ.get(MEMORY_ENV + "_AFTER", "30"))
    span = float(os.environ.get(MEMORY_ENV + "_FOR", "120"))
    tracemalloc.start(12)
    first: list[tracemalloc.Snapshot] = []

    def second() -> None:
        snap = tracemalloc.take_snapshot()
        stats = snap.compare_to(first[0], "traceback")
        with open(out, "w") as f:
            for st in stats[:25]:
                f.write(f"{st.size_diff / 1024:.1f} KiB in {st.count_diff} blocks\n")
                f.write("\n".join(st.traceback.format()[-12:]) + "\n\n")
        log.info("memory growth over %.0f s written to %s", span, out)

    def first_snapshot() -> None:
        first.append(tracemalloc.take_snapshot())
        loop.call_later(span, second)

    loop.call_later(after, first_snapshot)
