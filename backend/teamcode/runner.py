"""One team file running: start its worker, load it, send it a tick, account for the answer
(its CPU time against the budget), reload it on a save, fail it and say why.

A failed file (import error, exception, malformed output, over budget 3 ticks in a row,
spinning, stuck, crashed) stays failed until it (or a library) is saved again; then it is
loaded again and resumes. Its robots are stopped meanwhile by whoever asked (the strategy).

Budget: the worker's CPU time for a call (``time.thread_time``), so a busy machine does not
make a play late; over budget, that tick's output is discarded. A reload is not billed: no
call is sent while the worker imports (it would wait behind the import), and the first call
after a load (its warm-up) is not held to the budget.

Limits, on CPU time too: a call that uses its CPU limit (``cpu_limit_s``: at least 0.25 s,
ten budgets) is spinning: the worker's ``SIGPROF`` raises in it (the error names the line)
and the station ends that worker; should the raise not come (a long C call, the limit
switched off), the station ends it ``KILL_GRACE_S`` of CPU time later, from the CPU time
/proc shows. A worker the machine does not schedule uses no CPU time and is not stopped: its
robots are held ("late") until it answers. Behind that, a wall-clock backstop
(``wall_limit_s``: ten CPU limits) for a call that waits on something (a sleep, a lock, a
socket) or a worker never scheduled: its stack is asked for, then it is ended. Loads alike
(``LOAD_LIMIT_S`` of CPU time, ``LOAD_WALL_LIMIT_S`` of wall time).
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
import time
from collections.abc import Awaitable, Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, cast

from sslnet.ratelog import RateLimitedLog

from .discovery import Found
from .pyworker import PyWorker, WorkerGone
from .state import ErrorInfo, ErrorKind, FileRun

log = logging.getLogger("touchline.team")
_ratelog = RateLimitedLog(log, interval_s=10.0)

#: the CPU time a file's import may use (numpy, scipy, a library of the team's...)
LOAD_LIMIT_S = 10.0
#: the wall time a load may take before it is stuck (a busy machine, a slow disk, a wait)
LOAD_WALL_LIMIT_S = 60.0
#: the station ends a worker whose call went this much CPU time past its limit: the
#: worker's own SIGPROF did not stop it (a long call into C, or the team's code turned it off)
KILL_GRACE_S = 0.5
#: a call with no answer after this many CPU limits of wall time is stuck (the backstop)
WALL_FACTOR = 10.0
#: a worker's stack (SIGUSR1: where it spins or waits) is waited for this long before it is
#: ended
STACK_WAIT_S = 0.1
#: this many ticks in a row over budget: failed until the next save
OVER_BUDGET_IN_A_ROW = 3


def cpu_limit_s(budget_s: float) -> float:
    """A call that uses this much CPU time is spinning."""
    return max(0.25, 10.0 * budget_s)


def wall_limit_s(budget_s: float) -> float:
    """A call not answered after this long (wall clock) is stuck, whatever its CPU time."""
    return WALL_FACTOR * cpu_limit_s(budget_s)


@dataclass
class Pending:
    """One tick's request: ``fut`` gets the reply; ``output`` is set when it was usable."""

    fut: asyncio.Future[Any]
    sent_mono: float
    budget_s: float
    output: Any = None
    version: str = ""
    reason: str = "no answer yet"  # why there is no output
    done: bool = False
    cpu_ms: float | None = None
    extra: dict[str, Any] = field(default_factory=dict)
    #: the first call after a load: its warm-up (lazy imports, caches) is not held to the
    #: budget
    warmup: bool = False
    #: the worker's CPU time when the call was sent (None: unknown)
    cpu0: float | None = None


@dataclass
class Watch:
    """One call the station watches (a tick or a load) against its CPU and wall limits."""

    done: Callable[[], bool]
    started: float  # monotonic
    cpu0: float | None
    cpu_limit_s: float
    wall_limit_s: float
    loading: bool = False
    #: (wall s, CPU s) since the start at the latest look that let it go on
    seen: tuple[float, float | None] = (0.0, None)
    looks: int = 0


class Runner:
    """What every kind of runner shares: the file, its ``FileRun``, failing and accounting.
    Subclasses: ``PythonRunner`` (a worker process), ``teamcode.octave.OctaveRunner``."""

    language = "python"
    #: the (re)start under way (``_start_soon``), the starts asked for and the ones begun
    #: (set by each subclass)
    _task: asyncio.Task[None] | None
    _want: int
    _done: int

    def __init__(self, found: Found, run: FileRun) -> None:
        self.found = found
        self.run = run
        self.over_in_a_row = 0
        self.inflight: Pending | None = None
        self.closed = False
        #: the next call is the first since a load (its warm-up is not billed)
        self.fresh = False

    @property
    def name(self) -> str:
        return self.found.name

    @property
    def failed(self) -> bool:
        return self.run.state == "error"

    @property
    def reloading(self) -> bool:
        """A new version is being loaded where the calls run: no call can be answered."""
        return False

    def _warmup(self, p: Pending) -> Pending:
        p.warmup, self.fresh = self.fresh, False
        return p

    def fail(self, err: ErrorInfo) -> None:
        if self.run.fail(err):
            _ratelog.warning(f"team-{self.name}", "team code %s failed: %s", self.name,
                             err.one_line())

    def accept(self, p: Pending, reply: Any) -> None:
        """Accounts for one tick's reply (called when it arrives, late or not)."""
        p.done = True
        if self.inflight is p:
            self.inflight = None
        if self.closed:
            p.reason = "closed"
            return
        kind = reply[0] if isinstance(reply, tuple) and reply else None
        if kind == "out" and len(reply) == 5:
            _, _, payload, cpu, version = reply
            cpu_s = float(cpu) if isinstance(cpu, int | float) else 0.0
            p.cpu_ms = cpu_s * 1000.0
            p.version = str(version)
            self.run.ticks += 1
            self.run.tick_ms.append(p.cpu_ms)
            if cpu_s > p.budget_s and not p.warmup:
                self.run.overruns += 1
                self.over_in_a_row += 1
                p.reason = f"over its budget ({p.cpu_ms:.1f} ms of {p.budget_s * 1000:.0f} ms)"
                if self.over_in_a_row >= OVER_BUDGET_IN_A_ROW:
                    self.fail(ErrorInfo(
                        "budget", f"over its time budget {self.over_in_a_row} ticks in a row "
                        f"(the last: {p.cpu_ms:.1f} ms of CPU time; strategy.team_budget_ms "
                        f"= {p.budget_s * 1000:.0f})", self.name))
                return
            self.over_in_a_row = 0
            if self.failed:  # a reply from before the failure (a reload was under way)
                p.reason = self._why_failed()
                return
            p.output = payload
            p.reason = ""
            return
        if kind == "error" and len(reply) == 4 and isinstance(reply[2], dict):
            _, _, err, cpu = reply
            if isinstance(cpu, int | float):
                p.cpu_ms = float(cpu) * 1000.0
            self.fail(error_from(err, self.name))
            p.reason = self._why_failed()
            return
        self.fail(ErrorInfo("crash", f"the worker answered {str(reply)[:120]}", self.name))
        p.reason = self._why_failed()

    def _why_failed(self) -> str:
        """The reason a failed call's robots stand still: the file's error with its line (as
        on every later tick), not a bare "failed" the page would show for this one tick."""
        err = self.run.error
        return err.one_line() if err is not None else "failed"

    # ---- (re)starting: a save during a start is one more start, not one each ----

    def _start_soon(self, start: Callable[[], Awaitable[None]]) -> None:
        self._want += 1
        if self._task is None:
            self._task = asyncio.get_running_loop().create_task(self._starts(start))

    async def _starts(self, start: Callable[[], Awaitable[None]]) -> None:
        try:
            while self._done < self._want and not self.closed:
                self._done = self._want
                await start()
        finally:
            self._task = None

    async def _close_start(self) -> None:
        """Closed: the start under way is cancelled (and awaited)."""
        self.closed = True
        if self._task is not None:
            self._task.cancel()
            with contextlib.suppress(asyncio.CancelledError, Exception):
                await self._task

    # ---- what each kind of runner does its own way ----

    def ensure(self) -> None:
        """Starts and loads the file unless it runs, is starting, or failed."""
        raise NotImplementedError

    def update(self, found: Found) -> None:
        """The file (or a library) changed: load it again."""
        raise NotImplementedError

    def send(self, game: Any, inputs: Any, budget_s: float,
             now: float | None = None) -> Pending | None:
        """Sends one tick's request (None: nothing asked)."""
        raise NotImplementedError

    async def close(self) -> None:
        raise NotImplementedError

    def call_cpu_s(self, p: Pending) -> float | None:
        """The CPU time call ``p`` has used so far (None: unknown)."""
        return None

    def late(self, p: Pending) -> None:
        """The tick stopped waiting for ``p``: its output, whenever it comes, is discarded."""
        if not p.done and p.warmup:
            p.reason = "warming up (the first call after a load)"
        elif not p.done:
            # not judged over its budget here (CPU time, when the answer comes): late (wall
            # time: the machine is busy, or the worker was not scheduled)
            p.reason = f"late: no answer within the budget + grace{self._so_far(p)}"
            self.run.late += 1

    def waiting(self) -> str:
        """Why no call was sent this tick: the previous one has not answered (the machine
        is busy, or the play computes: its CPU time says which)."""
        p = self.inflight
        used = self.call_cpu_s(p) if p is not None else None
        if p is None or used is None:
            return "busy: its previous tick has not answered"
        if p.warmup:
            return f"warming up (the first call after a load; {used * 1000:.0f} ms of CPU time)"
        if used >= p.budget_s:
            return f"busy: its previous tick is still computing{self._so_far(p, used)}"
        return f"late: its previous tick has not answered yet{self._so_far(p, used)}"

    def _so_far(self, p: Pending, used: float | None = None) -> str:
        used = self.call_cpu_s(p) if used is None else used
        if used is None:
            return ""
        if used < p.budget_s:
            return f" (the machine is busy: {used * 1000:.0f} ms of CPU time so far)"
        return (f" ({used * 1000:.0f} ms of CPU time so far, over its "
                f"{p.budget_s * 1000:.0f} ms budget)")


def error_from(err: dict[str, Any], name: str) -> ErrorInfo:
    """An error dict from a worker (plain data, checked) as ErrorInfo."""
    kind = err.get("kind")
    if kind not in ("import", "exception", "output", "budget", "crash", "missing"):
        kind = "crash"
    line = err.get("line")
    return ErrorInfo(cast(ErrorKind, kind), str(err.get("message", ""))[:4000],
                     str(err.get("file") or name),
                     line if isinstance(line, int) and not isinstance(line, bool) else None,
                     str(err.get("traceback", ""))[:20000])


class PythonRunner(Runner):
    """A Python play or processor in a worker process of its own."""

    language = "python"

    def __init__(self, found: Found, run: FileRun, team_dir: Path, memory_mb: int,
                 kind: str = "play") -> None:
        super().__init__(found, run)
        self.team_dir = team_dir
        self.memory_mb = memory_mb
        self.kind = kind
        self.worker: PyWorker | None = None
        self._task: asyncio.Task[None] | None = None
        self._lock = asyncio.Lock()
        self._want = 0  # loads asked for (a save during a load loads again)
        self._done = 0
        self._loading = False  # a load request is with the worker
        #: workers ended after a spin (closing)
        self._retiring: set[asyncio.Task[None]] = set()
        #: the latest call watched against the limits (a tick or a load)
        self.watched: Watch | None = None
        #: what the loaded file says of itself (a processor: rate_hz, trigger, max_hz,
        #: reads), checked by ``info_check``
        self.info: dict[str, Any] = {}
        self.info_check: Callable[[dict[str, Any]], str | None] | None = None

    def check_info(self, info: Any) -> str | None:
        """What the loaded file says of itself (a processor's schedule): kept in ``info``
        when usable; else why not. ``info_check`` (set by the processors' host) judges."""
        if not isinstance(info, dict):
            return "the worker described the file wrongly"
        why = self.info_check(info) if self.info_check is not None else None
        if why is None:
            self.info = info
        return why

    @property
    def reloading(self) -> bool:
        return self._loading

    @property
    def pid(self) -> int:
        return self.worker.pid if self.worker is not None and self.worker.alive else 0

    # ---- start, load, reload ----

    def ensure(self) -> None:
        """Starts the worker and loads the file, unless it runs, is starting, or failed."""
        if self.closed or self.failed or self._task is not None:
            return
        if self.worker is not None and self.worker.alive and self.run.state == "running":
            return
        self._load_soon()

    def update(self, found: Found) -> None:
        """The file (or a library) changed: load it again, in the same worker if it lives
        (``keep``/``restore`` carry a class's state over); a file that cannot load fails at
        once (its old version stops too: never the last command repeated)."""
        self.found = found
        self.over_in_a_row = 0
        if found.error is not None:
            self.fail(ErrorInfo(found.error.kind, found.error.message, found.name,
                                found.error.line, at_unix=time.time()))
            return
        if self.run.state == "error":
            self.run.state = "starting"
            self.run.error = None
        self._load_soon()

    def _load_soon(self) -> None:
        if self._task is None and self.run.state != "running":
            self.run.state = "starting"
        self._start_soon(self._load)

    async def _load(self) -> None:
        found = self.found
        if self.worker is None or not self.worker.alive:
            self.run.state = "starting"
            w = PyWorker(self.team_dir, self.memory_mb)
            try:
                await w.start()
            except WorkerGone as exc:
                await w.close()
                self.fail(ErrorInfo("crash", str(exc), found.name,
                                    traceback=exc.dump[-4000:]))
                return
            if self.closed:
                await w.close()
                return
            w.on_gone = self._gone
            self.worker = w
        w = self.worker
        cpu0 = w.cpu_s()
        fut = w.request("load", found.name, self.kind, found.entry, LOAD_LIMIT_S)
        # set until the answer is accounted (``_loaded``) or the worker is gone (``_gone``
        # says it was loading): never before, or a load the station ended reads as a tick's
        # failure
        self._loading = True
        # The answer is accounted in the future's callback, as the ticks' answers are: in the
        # order the worker gave them. (Awaited here, it was accounted a few loop steps later,
        # after the answer of a tick sent during the reload: that tick's failure was cleared
        # by "loaded" and counted again on the next tick.)
        fut.add_done_callback(lambda f: self._loaded(found, w, f))
        self._watch(w, Watch(fut.done, time.monotonic(), cpu0, LOAD_LIMIT_S,
                             LOAD_WALL_LIMIT_S, loading=True))
        await asyncio.wait([fut])  # bounded: the watch ends a worker past its limits

    def _loaded(self, found: Found, w: PyWorker, fut: asyncio.Future[Any]) -> None:
        """The worker's answer to a load (not called if it ended first: _gone says it)."""
        if fut.cancelled() or fut.exception() is not None:
            return
        self._loading = False
        reply = fut.result()
        self._spun(w, reply)
        if self.closed or self._done < self._want:
            return  # saved again meanwhile: the next load counts
        if isinstance(reply, tuple) and reply[:1] == ("loaded",) and len(reply) == 4:
            problem = self.check_info(reply[3])
            if problem is not None:
                self.fail(ErrorInfo("import", problem, found.name))
                return
            self.run.loaded_version = str(reply[2])
            self.run.reloaded_at_unix = time.time()
            self.run.reloads += 1
            self.run.error = None
            self.run.state = "running"
            self.fresh = True
            log.info("team code %s loaded (version %s)", found.name, reply[2])
        elif isinstance(reply, tuple) and reply[:1] == ("error",) and len(reply) == 4 \
                and isinstance(reply[2], dict):
            self.fail(error_from(reply[2], found.name))
        else:
            self.fail(ErrorInfo("crash", f"the worker answered {str(reply)[:120]}",
                                found.name))

    def _spun(self, w: PyWorker, reply: Any) -> None:
        """A call stopped at its CPU limit (the worker's SIGPROF raised in it): that worker
        is ended (what the interrupted code left behind, a thread it started, goes with it);
        the next save starts a new one."""
        if not (isinstance(reply, tuple) and reply[:1] == ("error",) and len(reply) == 4
                and isinstance(reply[2], dict) and reply[2].get("spinning") is True):
            return
        if self.worker is w:
            self.worker = None
        w.on_gone = None
        task = asyncio.get_running_loop().create_task(w.close())
        self._retiring.add(task)
        task.add_done_callback(self._retiring.discard)

    def _gone(self, gone: WorkerGone) -> None:
        """The worker ended without being asked: spinning or stuck (the station ended it),
        or crashed. Failed until the next save, which starts a new one."""
        self.worker = None
        self.inflight = None
        if self.closed:
            return
        file, line, stack = gone.where(_team_namer(self.team_dir))
        at = f" at {file}:{line}" if file is not None else ""
        loading, self._loading = self._loading, False
        if gone.reason.startswith(("spinning", "stuck")):
            self.fail(ErrorInfo("import" if loading else "budget",
                                f"{gone.reason}{at} (its worker was stopped)",
                                file or self.name, line, stack))
        elif gone.reason:
            self.fail(ErrorInfo("crash", f"{gone.reason}{at}", file or self.name, line, stack))
        else:
            self.fail(ErrorInfo("crash", f"{gone.describe()}{at}", file or self.name, line,
                                stack or gone.dump[-4000:]))

    # ---- the limits: the worker's CPU time, and a wall-clock backstop ----

    def _watch(self, w: PyWorker, c: Watch) -> None:
        """Looks at call ``c`` when it could be past its CPU limit at the earliest (one
        thread uses at most a second of CPU time a second), again as long as it has not
        answered, and ends its worker once past a limit."""
        self.watched = c
        asyncio.get_running_loop().call_later(c.cpu_limit_s + KILL_GRACE_S, self._look, w, c)

    def _look(self, w: PyWorker, c: Watch, verdict: str = "") -> None:
        if c.done() or not w.alive:
            return
        if verdict:
            w.kill(verdict)  # _gone says it
            return
        cpu = w.cpu_s()
        elapsed = time.monotonic() - c.started
        used = cpu - c.cpu0 if cpu is not None and c.cpu0 is not None else None
        c.looks += 1
        if used is not None and used > c.cpu_limit_s + KILL_GRACE_S:
            what = "while loading" if c.loading else "in one call"
            verdict = (f"spinning: over its CPU limit {what} ({used:.2f} s of CPU time, the "
                       f"limit {c.cpu_limit_s:g} s) and not stopped by it (a long call into "
                       "C, or the limit turned off)")
        elif elapsed >= c.wall_limit_s:
            spent = f"{used:.2f} s" if used is not None else "unknown"
            verdict = (f"stuck: {'not loaded' if c.loading else 'no answer'} within "
                       f"{c.wall_limit_s:g} s of wall time, with {spent} of CPU time (waiting "
                       "on something, or its worker not scheduled)")
        else:
            c.seen = (elapsed, used)
            left = c.cpu_limit_s + KILL_GRACE_S - (used or 0.0)
            asyncio.get_running_loop().call_later(
                max(0.02, min(left, c.wall_limit_s - elapsed)), self._look, w, c)
            return
        # where it is (its stack, for the error's line), then ended a moment later: also a
        # reply that came while the station's loop was busy is read first, not killed
        w.ask_stack()
        asyncio.get_running_loop().call_later(STACK_WAIT_S, self._look, w, c, verdict)

    def call_cpu_s(self, p: Pending) -> float | None:
        w = self.worker
        cpu = w.cpu_s() if w is not None else None
        return cpu - p.cpu0 if cpu is not None and p.cpu0 is not None else None

    # ---- ticks ----

    def send(self, game: Any, inputs: Any, budget_s: float,
             now: float | None = None) -> Pending | None:
        """Sends this tick's request; None when there is nothing to ask (not running, or the
        previous call still runs: then it is stopped once past its limits)."""
        now = time.monotonic() if now is None else now
        w = self.worker
        if self.closed or self.run.state != "running" or w is None or not w.alive:
            return None
        if self.inflight is not None:
            return None  # still running (stopped past its limits: see _look)
        if self._loading:
            # the worker imports the new version: a call would wait behind the import and be
            # billed for it (late); its robots are held until the new version answers
            return None
        cpu0 = w.cpu_s()
        limit = cpu_limit_s(budget_s)
        fut = w.request("tick", game, inputs, limit)
        p = self._warmup(Pending(fut, now, budget_s, cpu0=cpu0))
        self.inflight = p
        fut.add_done_callback(lambda f: self._replied(w, p, f))
        self._watch(w, Watch(lambda: p.done, time.monotonic(), cpu0, limit,
                             wall_limit_s(budget_s)))
        return p

    def _replied(self, w: PyWorker, p: Pending, f: asyncio.Future[Any]) -> None:
        if f.cancelled():
            return
        exc = f.exception()
        if exc is not None:
            p.done = True
            p.reason = "its worker ended"
            if self.inflight is p:
                self.inflight = None
            return
        reply = f.result()
        self.accept(p, reply)
        self._spun(w, reply)

    async def close(self) -> None:
        await self._close_start()
        w, self.worker = self.worker, None
        if w is not None:
            w.on_gone = None
            await w.close()
        if self._retiring:
            await asyncio.gather(*self._retiring, return_exceptions=True)
        if self.run.state in ("running", "starting"):
            self.run.state = "idle"


def _team_namer(team_dir: Path) -> Any:
    root = team_dir.resolve()

    def name(filename: str) -> str | None:
        try:
            return Path(filename).resolve().relative_to(root).as_posix()
        except (ValueError, OSError):
            return None
    return name
