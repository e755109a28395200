import asyncio
import gc
import inspect
import itertools
import time
import types
import warnings

import pytest

from backend import processor
from backend.bus import Reader, Topic
from backend.processor import Every, OnTopic, Processor, Runner
from tests.waiting import until


class Counter(Processor):
    name = "counter"

    def __init__(self, hz: float) -> None:
        super().__init__(Every(hz))
        self.ticks = 0

    async def tick(self) -> None:
        self.ticks += 1


async def test_fixed_rate_processor_runs_at_its_rate_without_a_default_pause() -> None:
    p = Counter(200.0)
    r = Runner()
    r.add(p)
    await r.start()
    t0 = time.monotonic()
    await until(lambda: p.ticks >= 100)
    elapsed = time.monotonic() - t0
    await r.stop()
    # 100 ticks at 200 Hz take ~0.5 s; the seed's 1 s default pause would take 100 s
    assert elapsed < 2.0
    assert p.stats.rate.total >= 100
    assert p.stats.summary()["tick_mean_ms"] >= 0.0


class Echo(Processor):
    name = "echo"

    def __init__(self, src: Topic[int], dst: Topic[list[int]]) -> None:
        super().__init__(OnTopic(src))
        self.reader = Reader(src)
        self.dst = dst

    async def tick(self) -> None:
        vals = self.reader.read_new()
        if vals:
            self.dst.write(vals)


async def test_topic_triggered_processor_coalesces_and_loses_nothing() -> None:
    src: Topic[int] = Topic("src", 100)
    dst: Topic[list[int]] = Topic("dst", 100)
    r = Runner()
    r.add(Echo(src, dst))
    await r.start()
    for i in range(50):
        src.write(i)  # written without yielding: one run sees them all
    await until(lambda: dst.seq >= 1)
    src.write(50)
    await until(lambda: sum(len(v.value) for v in dst.records_after(0)) == 51)
    await r.stop()
    got = [x for rec in dst.records_after(0) for x in rec.value]
    assert got == list(range(51))
    assert dst.seq <= 3  # coalesced: not one run per record


class Boom(Processor):
    name = "boom"

    def __init__(self) -> None:
        super().__init__(Every(500.0))
        self.calls = 0

    async def tick(self) -> None:
        self.calls += 1
        if self.calls % 2:
            raise ValueError("bad tick")


async def test_exception_in_tick_is_counted_and_the_processor_keeps_running() -> None:
    p = Boom()
    r = Runner()
    r.add(p)
    await r.start()
    await until(lambda: p.calls >= 10)
    await r.stop()
    assert p.stats.errors >= 5
    assert "ValueError: bad tick" in p.stats.last_error


class Slow(Processor):
    name = "slow"

    def __init__(self) -> None:
        super().__init__(Every(100.0))

    async def tick(self) -> None:
        t = time.perf_counter()
        while time.perf_counter() - t < 0.015:  # 15 ms of work in a 10 ms period
            pass


async def test_overruns_are_counted() -> None:
    p = Slow()
    r = Runner()
    r.add(p)
    await r.start()
    await until(lambda: p.stats.rate.total >= 5)
    await r.stop()
    assert p.stats.overruns >= 5


class Watchdog(Processor):
    name = "watchdog"

    def __init__(self, src: Topic[int]) -> None:
        super().__init__(OnTopic(src, max_wait_s=0.02))
        self.runs = 0

    async def tick(self) -> None:
        self.runs += 1


async def test_max_wait_runs_a_quiet_processor() -> None:
    src: Topic[int] = Topic("src", 4)
    p = Watchdog(src)
    r = Runner()
    r.add(p)
    await r.start()
    await until(lambda: p.runs >= 5)  # nothing is ever written: only the max wait runs it
    await r.stop()


def test_set_rate_rejects_nonsense() -> None:
    p = Counter(10.0)
    with pytest.raises(ValueError):
        p.set_rate(float("nan"))
    with pytest.raises(ValueError):
        p.set_rate(0.0)
    p.set_rate(50.0)
    assert isinstance(p.trigger, Every) and p.trigger.hz == 50.0


class Stepper(Processor):
    """A fixed-rate processor whose tick is a plain ``step``."""

    name = "stepper"

    def __init__(self, hz: float, dst: Topic[int]) -> None:
        super().__init__(Every(hz))
        self.dst = dst
        self.tasks: set[object] = set()

    def step(self) -> None:
        self.tasks.add(asyncio.current_task())
        self.dst.write(self.dst.seq + 1)


class SlowWait(Processor):
    """A fixed-rate tick that really waits (like the strategy's, for its worker thread)."""

    name = "slow-wait"

    def __init__(self, dst: Topic[int]) -> None:
        super().__init__(Every(100.0))
        self.dst = dst

    async def tick(self) -> None:
        await asyncio.sleep(0.015)  # longer than its 10 ms period
        self.dst.write(self.dst.seq + 1)


async def test_fixed_rate_ticks_run_on_loop_timers_and_their_pass_follows() -> None:
    """A plain ``step`` at a fixed rate runs in a timer's callback (no task); a tick that
    waits finishes in a task, overruns counted; each one's readers run in its pass."""
    a: Topic[int] = Topic("a", 100)
    b: Topic[int] = Topic("b", 100)
    a_out: Topic[list[int]] = Topic("a-out", 100)
    b_out: Topic[list[int]] = Topic("b-out", 100)
    stepper, slow = Stepper(200.0, a), SlowWait(b)
    r = Runner()
    for p in (stepper, slow, Echo(a, a_out), Echo(b, b_out)):
        r.add(p)
    await r.start()
    assert not any(t.get_name() == "stepper" for t in asyncio.all_tasks())
    await until(lambda: stepper.stats.rate.total >= 40 and slow.stats.rate.total >= 5)
    await r.stop()
    assert stepper.tasks == {None}
    assert slow.stats.overruns >= 4
    assert slow.stats.summary()["tick_mean_ms"] >= 15.0
    echoed_a = [x for rec in a_out.records_after(0) for x in rec.value]
    echoed_b = [x for rec in b_out.records_after(0) for x in rec.value]
    assert echoed_a == list(range(1, len(echoed_a) + 1)) and len(echoed_a) >= 39
    assert echoed_b == list(range(1, len(echoed_b) + 1)) and len(echoed_b) >= 4


class Abandoned(Processor):
    """A tick that waits for ever (stopped with the runner); it says when it began and
    whether its coroutine was closed."""

    def __init__(self, trigger: Every | OnTopic) -> None:
        super().__init__(trigger)
        self.name = f"abandoned-{type(trigger).__name__}"
        self.began = 0
        self.resumed = False
        self.closed = False

    async def tick(self) -> None:
        self.began += 1
        try:
            await asyncio.get_running_loop().create_future()  # never done
            self.resumed = True
        finally:
            self.closed = True


@pytest.mark.parametrize("kind", ["pass", "fixed-rate"])
async def test_a_tick_left_waiting_by_a_stop_before_its_task_ran_is_closed(kind: str) -> None:
    """The runner's stop cancels the task that was to go on with a tick that waits (the
    rest of a pass, or of a fixed-rate tick) before the task ever ran: the tick's coroutine
    is closed at the stop and no coroutine of the runner's is left never started (one
    warned "coroutine 'Runner._rest' was never awaited" whenever it was collected: the
    cancelled task's traceback kept it until the loop's end)."""
    src: Topic[int] = Topic("src", 8)
    proc = Abandoned(OnTopic(src) if kind == "pass" else Every(100.0))
    r = Runner()
    r.add(proc)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        await r.start()  # the first pass (or the first tick) is scheduled: call_soon
        # one turn of the loop: the tick begins, waits, and hands its rest to a new task,
        # whose first step comes in the loop's next turn; this task goes on before it
        await asyncio.sleep(0)
        assert proc.began == 1 and not proc.closed
        await r.stop()  # cancels the task before it ran
        assert proc.closed and not proc.resumed
        del r
        gc.collect()
        never_started = [
            c for c in gc.get_objects()
            if isinstance(c, types.CoroutineType) and c.cr_code.co_filename == processor.__file__
            and inspect.getcoroutinestate(c) == inspect.CORO_CREATED
        ]
        assert never_started == []
    assert [w for w in caught if "never awaited" in str(w.message)] == []


class OwnDeadline(Processor):
    """Topic-triggered with a long max wait and a deadline of its own (the control's stop
    when every camera fell silent): ``wake_in_s`` says how long until it."""

    name = "own-deadline"
    wake_check_s = 0.05

    def __init__(self, src: Topic[int], max_wait_s: float) -> None:
        super().__init__(OnTopic(src, max_wait_s=max_wait_s))
        self.runs: list[float] = []
        self.deadline: float | None = None  # perf_counter
        self.fail = False
        self.asked = 0

    def step(self) -> None:
        self.runs.append(time.perf_counter())
        if self.fail:  # before it forgets its deadline: it stays due
            raise RuntimeError("broken tick")
        if self.deadline is not None and time.perf_counter() >= self.deadline:
            self.deadline = None  # done: the processor asks nothing more

    def wake_in_s(self) -> float | None:
        self.asked += 1
        if self.deadline is None or self.asked >= 2000:  # (never forever, should it spin)
            return None
        return self.deadline - time.perf_counter()


async def test_a_processor_runs_at_its_own_deadline_before_its_max_wait() -> None:
    """Max wait 10 s, its own deadline 30 ms away (set after its last run, as a frame's
    arrival sets the control's): it runs then, not 10 s later; a deadline set while the
    runner naps is seen at the next check (``wake_check_s``)."""
    src: Topic[int] = Topic("src", 8)
    p = OwnDeadline(src, max_wait_s=10.0)
    r = Runner()
    r.add(p)
    await r.start()
    try:
        await until(lambda: len(p.runs) >= 1)  # the first pass
        for _ in range(3):
            n = len(p.runs)
            p.deadline = deadline = time.perf_counter() + 0.03
            # (bounded well inside the max wait: without the deadline it runs in 10 s)
            await until(lambda n=n: len(p.runs) > n, timeout_s=5.0)  # type: ignore[misc]
            assert p.runs[n] >= deadline and p.deadline is None  # at, not before, it
    finally:
        await r.stop()


async def test_a_deadline_that_stays_due_does_not_spin_the_loop() -> None:
    """A processor whose deadline passed and whose tick fails (so it stays due): run once
    for it, then at its max wait, not over and over (the loop stays free)."""
    src: Topic[int] = Topic("src", 8)
    p = OwnDeadline(src, max_wait_s=0.05)
    r = Runner()
    r.add(p)
    await r.start()
    try:
        await until(lambda: len(p.runs) >= 1)
        p.fail = True
        p.deadline = time.perf_counter() + 0.01
        n = len(p.runs)
        await until(lambda: len(p.runs) >= n + 6)
        assert p.asked < 2000  # asked at each wake-up, not in a loop
        # after the first run for it, one run a max wait (a slow machine only widens the
        # gaps; spinning makes them microseconds)
        runs = p.runs[n + 1:]
        gaps = [b - a for a, b in itertools.pairwise(runs)]
        assert min(gaps) >= 0.04, gaps
    finally:
        await r.stop()
