"""The adaptive filter's step is written once for both dimensions (``_Step``, branches under
``if two:``) and each filter runs it compiled for its own (``_compiled``): the compiled step
must do exactly what the written one does, to the bit, on data that takes every branch
(outliers, kicks, a placed ball, second cameras)."""

from __future__ import annotations

import math
import random
from typing import Any

import pytest

from backend.filters.adaptive import AdaptiveIMM, AdaptiveIMM1D
from backend.filters.adaptive.step import _compiled, _Step


class _Written2(AdaptiveIMM):
    """The 2-D filter running the step as written (``two`` read at run time)."""

    __slots__ = ()
    update = _Step.update
    revise = _Step.revise


class _Written1(AdaptiveIMM1D):
    __slots__ = ()
    update = _Step.update
    revise = _Step.revise


def _measurements(seed: int) -> list[tuple[float, float, float, float | None]]:
    """(t, x, y, a second camera's x or None): a ball at rest, kicked, bounced off a wall,
    slowing down, then placed elsewhere; 3 mm noise, false detections at p = 0.1, missed
    frames."""
    rng = random.Random(seed)
    out: list[tuple[float, float, float, float | None]] = []
    x, y, vx, vy = 0.0, 0.0, 0.0, 0.0
    for k in range(3000):
        t = k / 75.0
        if k == 300:
            vx, vy = 4000.0, 1500.0  # a kick
        if k > 300 and x > 4000.0:
            vx = -abs(vx)  # a wall
        if k == 1500:
            x, y, vx, vy = -2500.0, 1000.0, 0.0, 0.0  # placed elsewhere
        if k == 2000:
            vx, vy = 0.0, -3000.0
        vx *= 0.995
        vy *= 0.995
        x += vx / 75.0
        y += vy / 75.0
        if rng.random() < 0.05:
            continue
        zx, zy = x + rng.gauss(0, 3), y + rng.gauss(0, 3)
        if rng.random() < 0.1:
            zx += rng.uniform(-1500, 1500)
            zy += rng.uniform(-1500, 1500)
        second = zx + rng.gauss(0, 3) if rng.random() < 0.5 else None
        out.append((t, zx, zy, second))
    return out


def _run(f: Any, data: list[tuple[float, float, float, float | None]],
         one_d: bool) -> list[Any]:
    trace: list[Any] = []
    for t, zx, zy, second in data:
        if one_d:  # an angle: the x measurement scaled to radians, wrapped (y: ignored)
            zx = math.remainder(zx / 1000.0, math.tau)
            second = None if second is None else math.remainder(second / 1000.0, math.tau)
        trace.append(f.update(t, zx, zy))
        if second is not None:
            trace.append(f.revise(second, zy))
        trace.append((f.velocity(), f.predict(t + 0.01), tuple(f.S), f.rejected))
    return trace


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_the_2d_step_compiled_does_what_it_says(seed: int) -> None:
    data = _measurements(seed)
    compiled, written = _run(AdaptiveIMM(), data, False), _run(_Written2(), data, False)
    assert compiled == written
    assert any(r[3] for r in compiled if isinstance(r, tuple) and len(r) == 4)  # rejections ran


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_the_1d_step_compiled_does_what_it_says(seed: int) -> None:
    data = _measurements(seed)
    compiled, written = _run(AdaptiveIMM1D(), data, True), _run(_Written1(), data, True)
    assert compiled == written


def test_each_filter_runs_a_step_without_the_other_dimension() -> None:
    for cls in (AdaptiveIMM, AdaptiveIMM1D):
        for name in ("update", "revise"):
            code = getattr(cls, name).__code__
            assert "two" not in code.co_varnames and "two" not in code.co_names
            # tracebacks and coverage point at the step as written
            assert code.co_filename == getattr(_Step, name).__code__.co_filename
            assert code.co_firstlineno == getattr(_Step, name).__code__.co_firstlineno
    assert AdaptiveIMM.update.__code__ is not AdaptiveIMM1D.update.__code__
    assert AdaptiveIMM1D.update.__qualname__ == "AdaptiveIMM1D.update"


class _ReadsTwo:
    def step(self) -> bool:  # (a method: _compiled takes the step's methods, indented)
        two = self._two  # type: ignore[attr-defined]
        return bool(two)


def test_a_read_of_two_outside_its_branches_is_refused() -> None:
    with pytest.raises(ValueError, match="`two` read outside"):
        _compiled(_ReadsTwo.step, True, "x")
