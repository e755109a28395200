"""The compute engine inside the strategy: the keeper computed by the shipped .m example in
GNU Octave, by the numpy engine, and by the built-in code, behaves alike; an engine that
fails, hangs or dies costs one fallback per tick, never the strategy."""

from __future__ import annotations

import math
import random
from pathlib import Path

import numpy as np
import pytest

from backend import topics
from backend.bus import DataBus
from backend.engine import NumpyEngine, OctaveEngine, PoolEngine, find_octave
from backend.messages import TargetEntry
from backend.params.model import StrategyParams
from backend.processors import StrategyProcessor
from backend.world.state import BallState, RobotState, WorldState

ROOT = Path(__file__).resolve().parents[3]
needs_octave = pytest.mark.skipif(find_octave() is None,
                                  reason="GNU Octave not installed (make test installs it)")


def world(ball: tuple[float, float, float, float]) -> WorldState:
    rnd = random.Random(3)
    robots = [RobotState("blue", i, rnd.uniform(-4000, 0), rnd.uniform(-2500, 2500), 0.0)
              for i in range(6)]
    robots += [RobotState("yellow", i, rnd.uniform(0, 4000), rnd.uniform(-2500, 2500), math.pi)
               for i in range(6)]
    b = BallState(ball[0], ball[1], ball[2], ball[3], t_seen=0.0)
    return WorldState(0.0, 0, b, tuple(robots))


def make_processor(engine: PoolEngine | None, fn: str = "goalkeeper",
                   timeout_s: float = 1.0) -> tuple[StrategyProcessor, DataBus]:
    bus = DataBus({})
    p = StrategyProcessor(bus, "blue", StrategyParams(play="match", goalkeeper_function=fn,
                                                      engine_timeout_s=timeout_s,
                                                      engine="numpy" if engine else "off"))
    p.engine = engine
    return p, bus


BALLS = [(-2000.0, 800.0, -2500.0, -1000.0), (-2000.0, -900.0, 0.0, 0.0),
         (-2000.0, 200.0, 0.0, 0.0), (-1500.0, -300.0, -2000.0, 50.0),
         (-3000.0, 1000.0, -400.0, -900.0)]


async def keeper_targets(engine: PoolEngine | None) -> list[tuple[float, float]]:
    out = []
    for ball in BALLS:
        p, bus = make_processor(engine)
        bus.of(topics.WORLD).write(world(ball))
        await p.tick()  # asks the engine (never waits for it)
        await p.engine_settled()
        await p.tick()  # uses its answer
        targets: dict[tuple[str, int], TargetEntry] = bus.of(topics.TARGETS).latest_value()
        keepers = [e for e in targets.values() if e.role == "goalkeeper"]
        assert len(keepers) == 1
        out.append((keepers[0].target.x, keepers[0].target.y))
        assert p.engine_fallbacks == 0, p.engine_last_error
    return out


@needs_octave
async def test_octave_numpy_and_builtin_keepers_agree() -> None:
    builtin = await keeper_targets(None)
    async with NumpyEngine(functions={"goalkeeper": "backend.geometry.fit:goalkeeper_target"},
                           default_timeout_s=5.0) as npe:
        by_numpy = await keeper_targets(npe)
        assert npe.stats.ok >= len(BALLS)
    async with OctaveEngine(ROOT / "engine_scripts", default_timeout_s=10.0) as oct_engine:
        by_octave = await keeper_targets(oct_engine)
        assert oct_engine.stats.ok >= len(BALLS)
    np.testing.assert_allclose(by_numpy, builtin, atol=1e-6)
    np.testing.assert_allclose(by_octave, builtin, atol=1e-6)
    # and the cases differ from each other, so agreement means something
    assert len({round(y) for _, y in builtin}) >= 4


@pytest.mark.parametrize("fn,expect", [
    ("engine.keeper_fail", "boom"),  # raises
    ("engine.keeper_hang", "timed out"),  # hangs past the timeout
    ("engine.keeper_crash", "died"),  # the worker process exits
    ("engine.keeper_scalar", "expected [x y]"),  # returns a scalar, not [x y]
])
async def test_a_failing_engine_falls_back_to_the_builtin_keeper(fn: str, expect: str) -> None:
    builtin = await keeper_targets(None)
    async with NumpyEngine({"engine": "tests.backend.engine.engine_funcs"},
                           default_timeout_s=0.3) as eng:
        p, bus = make_processor(eng, fn, timeout_s=0.3)
        bus.of(topics.WORLD).write(world(BALLS[0]))
        await p.tick()
        await p.engine_settled()
        await p.tick()  # the failure arrives: must not raise
        targets = bus.of(topics.TARGETS).latest_value()
        keeper = next(e for e in targets.values() if e.role == "goalkeeper")
        assert (keeper.target.x, keeper.target.y) == pytest.approx(builtin[0])
        assert p.engine_fallbacks == 1
        assert expect in p.engine_last_error
