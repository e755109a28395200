"""NumpyEngine: results, timeouts, exceptions, crashes, the event loop stays free."""

from __future__ import annotations

import asyncio
import time
from collections.abc import AsyncIterator

import numpy as np
import pytest

from backend import geometry
from backend.engine import (
    EngineClosed,
    EngineError,
    EngineTimeout,
    EngineWorkerDied,
    NumpyEngine,
)

FUNCS = "tests.backend.engine.engine_funcs"


@pytest.fixture
async def engine() -> AsyncIterator[NumpyEngine]:
    eng = NumpyEngine({"geometry": "backend.geometry", "t": FUNCS}, workers=1,
                      default_timeout_s=5.0)
    await eng.start()
    try:
        yield eng
    finally:
        await eng.close()


async def test_geometry_call_matches_local(engine: NumpyEngine) -> None:
    rng = np.random.default_rng(1)
    a, b = rng.normal(size=(22, 2)) * 1000, rng.normal(size=(22, 2)) * 1000
    remote = await engine.call("geometry.distance", a, b, timeout_s=1.0)
    assert np.array_equal(remote, geometry.distance(a, b))
    hit = await engine.call("geometry.segment_hits_circles", a, b, a[:3] + 5, 100.0)
    assert isinstance(hit, geometry.SegmentHit)
    assert await engine.call("t.scale", np.arange(3.0), k=3.0) == pytest.approx([0, 3, 6])


async def test_unknown_and_private_names(engine: NumpyEngine) -> None:
    with pytest.raises(EngineError, match="no module registered"):
        await engine.call("nope.distance", 1)
    with pytest.raises(EngineError, match="not public"):
        await engine.call("t._private")
    with pytest.raises(EngineError, match="has no function"):
        await engine.call("geometry.nope")


async def test_exception_becomes_error_with_remote_traceback(engine: NumpyEngine) -> None:
    with pytest.raises(EngineError) as info:
        await engine.call("t.fail", "bad input")
    assert not isinstance(info.value, EngineTimeout | EngineWorkerDied)
    assert "ValueError: bad input" in str(info.value)
    assert "engine_funcs.py" in info.value.remote_traceback
    assert "raise ValueError" in info.value.remote_traceback
    # the same worker keeps serving
    before = await engine.call("t.pid")
    assert await engine.call("t.add", 1, 2) == 3
    assert await engine.call("t.pid") == before
    h = engine.health()
    assert h["errors"] == 1 and h["restarts"] == 0


async def test_unpicklable_result_is_an_error_not_a_hang(engine: NumpyEngine) -> None:
    with pytest.raises(EngineError, match="not picklable"):
        await engine.call("t.unpicklable", timeout_s=2.0)
    assert await engine.call("t.add", 2, 2) == 4


async def test_prints_do_not_corrupt_the_protocol(engine: NumpyEngine) -> None:
    assert await engine.call("t.chatty") == 42
    assert await engine.call("t.add", 1, 1) == 2


async def test_timeout_kills_and_replaces_the_worker(engine: NumpyEngine) -> None:
    old = await engine.call("t.pid")
    t0 = time.monotonic()
    with pytest.raises(EngineTimeout) as info:
        await engine.call("t.forever", timeout_s=0.2)
    elapsed = time.monotonic() - t0
    assert 0.19 <= elapsed < 0.2 + 0.3
    assert isinstance(info.value, TimeoutError)
    # the next call waits for the replacement worker (a fresh process) and works
    assert await engine.call("t.add", 1, 2, timeout_s=10.0) == 3
    assert await engine.call("t.pid") != old
    h = engine.health()
    assert h["timeouts"] == 1 and h["restarts"] == 1 and h["workers"] == 1


async def test_a_cancelled_waiter_does_not_stop_the_next_one_from_waiting() -> None:
    """The reaper of a killed worker cancelled while it waits (the engine closing), then the
    engine's own close waits for the same worker: that wait completes."""
    import sys

    from backend.engine._process import ProcessWorker, worker_env

    class Sleeper(ProcessWorker):
        async def start(self) -> None:
            await self._spawn(sys.executable, "-c", "import time; time.sleep(60)",
                              env=worker_env())

        async def request(self, name: str, args: tuple[object, ...],
                          kwargs: dict[str, object]) -> object:
            raise NotImplementedError

    w = Sleeper()
    await w.start()
    w.kill()
    reaper = asyncio.create_task(w.wait_closed())
    await asyncio.sleep(0)  # the reaper is now waiting inside wait_closed
    reaper.cancel()
    with pytest.raises(asyncio.CancelledError):
        await reaper
    await w.wait_closed()  # raised CancelledError before (the shared stdin waiter)
    assert w.proc is not None and w.proc.returncode is not None


async def test_worker_crash_is_an_error_and_the_worker_is_replaced(engine: NumpyEngine) -> None:
    old = await engine.call("t.pid")
    t0 = time.monotonic()
    with pytest.raises(EngineWorkerDied, match="exit status 7"):
        await engine.call("t.crash", timeout_s=5.0)
    assert time.monotonic() - t0 < 1.0  # reported at once, not at the timeout
    assert await engine.call("t.add", 2, 3, timeout_s=10.0) == 5
    assert await engine.call("t.pid") != old
    h = engine.health()
    assert h["crashes"] == 1 and h["restarts"] == 1


async def test_event_loop_keeps_ticking_during_a_call(engine: NumpyEngine) -> None:
    ticks: list[float] = []
    stop = asyncio.Event()

    async def ticker() -> None:
        while not stop.is_set():
            ticks.append(time.monotonic())
            await asyncio.sleep(0.01)

    task = asyncio.create_task(ticker())
    t0 = time.monotonic()
    assert await engine.call("t.sleep_s", 0.2, timeout_s=2.0) == 0.2
    t1 = time.monotonic()
    stop.set()
    await task
    during = [t for t in ticks if t0 <= t <= t1]
    assert t1 - t0 >= 0.2
    # a 10 ms ticker runs ~20 times in 200 ms; a blocked loop would run it at most once
    assert len(during) >= 10
    assert max(np.diff(during)) < 0.1


async def test_two_workers_run_calls_in_parallel() -> None:
    async with NumpyEngine({"t": FUNCS}, workers=2) as eng:
        t0 = time.monotonic()
        res = await asyncio.gather(*(eng.call("t.sleep_s", 0.3, timeout_s=2.0)
                                     for _ in range(2)))
        assert res == [0.3, 0.3]
        assert time.monotonic() - t0 < 0.55  # serially it would take 0.6 s
        pids = await asyncio.gather(eng.call("t.sleep_s", 0.05), eng.call("t.pid"))
        assert pids[0] == 0.05


async def _busy(engine: NumpyEngine, timeout_s: float = 5.0) -> None:
    """Returns once a call holds a worker (bounded)."""
    deadline = time.monotonic() + timeout_s
    while engine.health()["busy"] < 1:
        assert time.monotonic() < deadline, "no call took a worker"
        await asyncio.sleep(0.001)


async def test_waiting_for_a_busy_worker_counts_towards_the_timeout(engine: NumpyEngine) -> None:
    slow = asyncio.create_task(engine.call("t.sleep_s", 0.5, timeout_s=2.0))
    await _busy(engine)  # it has taken the only worker
    with pytest.raises(EngineTimeout, match="no free worker"):
        await engine.call("t.add", 1, 1, timeout_s=0.1)
    assert await slow == 0.5


async def test_cancelled_caller_leaves_a_working_engine(engine: NumpyEngine) -> None:
    task = asyncio.create_task(engine.call("t.forever", timeout_s=30.0))
    await _busy(engine)  # cancelled while its worker runs it
    task.cancel()
    with pytest.raises(asyncio.CancelledError):
        await task
    assert await engine.call("t.add", 1, 1, timeout_s=10.0) == 2


async def test_health_dict(engine: NumpyEngine) -> None:
    for _ in range(20):
        await engine.call("t.add", 1, 1)
    h = engine.health()
    assert h["calls"] == 20 and h["ok"] == 20
    assert h["calls_per_s"] > 0 and 0 < float(h["latency_mean_ms"]) <= float(h["latency_p99_ms"])
    assert h["kind"] == "numpy" and h["idle"] == 1 and h["busy"] == 0


async def test_closed_engine_refuses_calls() -> None:
    eng = NumpyEngine({"t": FUNCS})
    with pytest.raises(EngineClosed):
        await eng.call("t.add", 1, 2)
    await eng.start()
    await eng.close()
    with pytest.raises(EngineClosed):
        await eng.call("t.add", 1, 2)
