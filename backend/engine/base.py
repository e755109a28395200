"""The compute engine's common part: errors, health stats and a pool of worker processes.

A processor awaits ``engine.call(name, *args, timeout_s=...)``; the call runs in a worker
process, so the asyncio event loop keeps running. Every call has a deadline (the engine's
default when not given) that covers waiting for a free worker and the run itself. Failures
come back as exceptions of the call, never as a dead or hung caller:

- the function raised: ``EngineError`` with the remote traceback text; the worker stays;
- the worker died (os._exit, a segfault, Octave's ``exit``): ``EngineWorkerDied``; a new
  worker is started in the background;
- the deadline passed: ``EngineTimeout``; the worker (perhaps stuck in a loop) is killed and
  replaced. Cancelling the awaiting task does the same, since the worker's state is unknown.
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
import time
from abc import ABC, abstractmethod
from collections import deque
from typing import Any

from sslnet.rate import RateCounter

log = logging.getLogger("touchline.engine")


class EngineError(Exception):
    """A call failed. ``remote_traceback`` is the worker's traceback text (may be empty)."""

    def __init__(self, message: str, remote_traceback: str = "") -> None:
        super().__init__(message)
        self.remote_traceback = remote_traceback

    def __str__(self) -> str:
        base = super().__str__()
        return f"{base}\n{self.remote_traceback}" if self.remote_traceback else base


class EngineTimeout(EngineError, TimeoutError):
    """The call did not finish within its timeout; its worker was killed and replaced."""


class EngineWorkerDied(EngineError):
    """The worker process exited during the call; it is being replaced."""


class EngineClosed(EngineError):
    """The engine is not started or already closed."""


class RemoteError(Exception):
    """Raised by a worker's ``request`` when the remote function failed (worker is fine)."""

    def __init__(self, message: str, traceback_text: str) -> None:
        super().__init__(message)
        self.traceback_text = traceback_text


class WorkerDied(Exception):
    """Raised by a worker's ``request`` when its process is gone."""


class Worker(ABC):
    """One worker process. ``request`` is called by one caller at a time."""

    @abstractmethod
    async def start(self) -> None: ...

    @abstractmethod
    async def request(self, name: str, args: tuple[Any, ...], kwargs: dict[str, Any]) -> Any: ...

    @abstractmethod
    def kill(self) -> None:
        """Stop the process at once (SIGKILL); safe to call twice."""

    @abstractmethod
    async def wait_closed(self) -> None:
        """Wait until the process has exited and its pipes are closed."""

    async def close(self) -> None:
        """Ask the worker to stop; kill it if it does not exit promptly."""
        self.kill()
        await self.wait_closed()


class EngineStats:
    """Health numbers for the dashboard."""

    def __init__(self) -> None:
        self.rate = RateCounter(window_s=2.0)
        self.latency_ms: deque[float] = deque(maxlen=1024)
        self.calls = 0
        self.ok = 0
        self.errors = 0
        self.timeouts = 0
        self.crashes = 0
        self.restarts = 0
        self.start_failures = 0
        self.last_error = ""

    def summary(self) -> dict[str, float | int | str]:
        lat = sorted(self.latency_ms)
        mean = sum(lat) / len(lat) if lat else 0.0
        p99 = lat[min(len(lat) - 1, int(0.99 * len(lat)))] if lat else 0.0
        return {
            "calls_per_s": self.rate.rate_hz(),
            "latency_mean_ms": mean,
            "latency_p99_ms": p99,
            "calls": self.calls,
            "ok": self.ok,
            "errors": self.errors,
            "timeouts": self.timeouts,
            "crashes": self.crashes,
            "restarts": self.restarts,
            "start_failures": self.start_failures,
            "last_error": self.last_error,
        }


class PoolEngine(ABC):
    """A pool of ``workers`` processes serving ``call``s, one call per worker at a time.

    Use ``async with engine:`` or ``await engine.start()`` / ``await engine.close()``.
    """

    kind = "engine"

    def __init__(self, workers: int = 1, default_timeout_s: float = 1.0,
                 start_timeout_s: float = 30.0) -> None:
        if workers < 1:
            raise ValueError("workers must be >= 1")
        self.n_workers = workers
        self.default_timeout_s = default_timeout_s
        self.start_timeout_s = start_timeout_s
        self.stats = EngineStats()
        self._idle: asyncio.Queue[Worker] = asyncio.Queue()
        self._all: set[Worker] = set()
        self._dying: set[Worker] = set()  # killed, not yet reaped
        self._busy = 0
        self._bg: set[asyncio.Task[None]] = set()
        self._running = False

    @abstractmethod
    def _new_worker(self) -> Worker: ...

    async def __aenter__(self) -> PoolEngine:
        await self.start()
        return self

    async def __aexit__(self, *exc: object) -> None:
        await self.close()

    async def start(self) -> None:
        """Start every worker; raises EngineError if one cannot start."""
        if self._running:
            return
        self._running = True
        try:
            workers = await asyncio.gather(*(self._start_one() for _ in range(self.n_workers)))
        except BaseException:
            await self.close()
            raise
        for w in workers:
            self._idle.put_nowait(w)

    async def _start_one(self) -> Worker:
        w = self._new_worker()
        self._all.add(w)
        try:
            async with asyncio.timeout(self.start_timeout_s):
                await w.start()
        except BaseException as exc:
            self._all.discard(w)
            w.kill()
            with contextlib.suppress(Exception):
                await w.wait_closed()
            if isinstance(exc, TimeoutError):
                raise EngineError(f"{self.kind} worker did not start within "
                                  f"{self.start_timeout_s} s") from exc
            raise
        return w

    def _replace(self, dead: Worker) -> None:
        """Discard a worker (killing it) and start a new one in the background."""
        self._all.discard(dead)
        dead.kill()
        self._dying.add(dead)
        self._spawn_bg(self._reap(dead))
        if self._running:
            self.stats.restarts += 1
            self._spawn_bg(self._restart())

    def _spawn_bg(self, coro: Any) -> None:
        task: asyncio.Task[None] = asyncio.get_running_loop().create_task(coro)
        self._bg.add(task)
        task.add_done_callback(self._bg.discard)

    async def _reap(self, w: Worker) -> None:
        with contextlib.suppress(Exception):
            await w.wait_closed()
        self._dying.discard(w)

    async def _restart(self) -> None:
        delay = 0.2
        while self._running:
            try:
                w = await self._start_one()
            except asyncio.CancelledError:
                raise
            except Exception as exc:
                self.stats.start_failures += 1
                self.stats.last_error = f"worker start failed: {exc}"
                log.warning("%s worker start failed (%s); retrying in %.1f s", self.kind, exc,
                            delay)
                await asyncio.sleep(delay)
                delay = min(delay * 2, 5.0)
                continue
            if not self._running:
                await w.close()
                return
            self._idle.put_nowait(w)
            return

    async def call(self, name: str, *args: Any, timeout_s: float | None = None,
                   **kwargs: Any) -> Any:
        """Run function ``name`` on ``args`` in a worker and return its result.

        Raises EngineTimeout, EngineWorkerDied or EngineError (see the module docstring).
        """
        if not self._running:
            raise EngineClosed(f"{self.kind} engine is not running")
        timeout = self.default_timeout_s if timeout_s is None else timeout_s
        loop = asyncio.get_running_loop()
        deadline = loop.time() + timeout
        t0 = time.perf_counter()
        self.stats.calls += 1
        self.stats.rate.add()
        try:
            async with asyncio.timeout_at(deadline):
                worker = await self._idle.get()
        except TimeoutError:
            self.stats.timeouts += 1
            self.stats.last_error = f"{name}: no free worker within {timeout} s"
            raise EngineTimeout(self.stats.last_error) from None
        self._busy += 1
        healthy = False
        try:
            try:
                async with asyncio.timeout_at(deadline):
                    result = await worker.request(name, args, kwargs)
            except TimeoutError:
                self.stats.timeouts += 1
                self.stats.last_error = f"{name}: timed out after {timeout} s"
                raise EngineTimeout(self.stats.last_error
                                    + "; the worker was killed and is being replaced") from None
            except RemoteError as exc:
                healthy = True
                self.stats.errors += 1
                self.stats.last_error = f"{name}: {exc}"
                raise EngineError(f"{name} failed: {exc}", exc.traceback_text) from None
            except WorkerDied as exc:
                self.stats.crashes += 1
                self.stats.last_error = f"{name}: worker died: {exc}"
                raise EngineWorkerDied(f"{name}: the worker process died during the call "
                                       f"({exc}); it is being replaced") from None
            healthy = True
            self.stats.ok += 1
            return result
        finally:
            self._busy -= 1
            self.stats.latency_ms.append((time.perf_counter() - t0) * 1000.0)
            if healthy and self._running:
                self._idle.put_nowait(worker)
            elif healthy:
                await worker.close()
            else:
                self._replace(worker)

    def health(self) -> dict[str, float | int | str]:
        """Stats for the dashboard: rates, latency, failure counters, worker counts."""
        out = self.stats.summary()
        out["kind"] = self.kind
        out["workers"] = len(self._all)
        out["busy"] = self._busy
        out["idle"] = self._idle.qsize()
        return out

    async def close(self) -> None:
        """Stop every worker (in-flight calls fail with EngineWorkerDied) and background task."""
        self._running = False
        for task in list(self._bg):
            task.cancel()
        for task in list(self._bg):
            with contextlib.suppress(asyncio.CancelledError, Exception):
                await task
        workers = list(self._all) + list(self._dying)
        self._all.clear()
        self._dying.clear()
        while not self._idle.empty():
            self._idle.get_nowait()
        await asyncio.gather(*(w.close() for w in workers), return_exceptions=True)
