"""Octave plays (the paper's way): matrices in (touchline.octave's columns), a matrix out,
several functions in one file, lib/ on the path, a save restarting the worker (persistent
state starts afresh), errors with file and line, the engine's timeout as the budget."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from backend.engine import find_octave
from backend.teamcode.octave import OctaveOutputError, OctaveRunner, plain_matrix_orders
from backend.teamcode.orders import TargetOrder, VelocityOrder, validate_orders
from backend.teamcode.state import FileRun

from .helpers import Rig, answer, found, game, until, write

pytestmark = pytest.mark.skipif(
    find_octave() is None,
    reason="GNU Octave (octave-cli) is not installed: "
           "apt-get install --no-install-recommends octave")

ROOT = Path(__file__).resolve().parents[3]

ECHO = """function orders = echo(ours, theirs, ball, game)
  % Echo: tells what it got, as orders
  mine = ours(ours(:, 9) == 1, :);
  orders = zeros(0, 9);
  for k = 1:rows(mine)
    orders(end + 1, :) = [mine(k, 1) 0 game.field.length size(theirs, 1) NaN NaN 0 0 0];
  end
  orders(end + 1, :) = [7 1 ball(1, 1) twice(game.t) strcmp(game.our_team, 'blue') 0 0 0 1];
end

function y = twice(x)
  y = 2 * x;
end
"""


async def started(folder: Path, name: str, timeout_s: float = 5.0) -> OctaveRunner:
    r = OctaveRunner(found(folder, name), FileRun(), folder, timeout_s)
    r.ensure()
    await until(lambda: r.run.state not in ("starting", "idle"), 60.0, f"{name} started")
    return r


async def test_matrices_in_and_out(tmp_path: Path) -> None:
    write(tmp_path, "echo.m", ECHO)
    f = found(tmp_path, "echo.m")
    assert (f.kind, f.play, f.title) == ("play", "echo", "Echo: tells what it got, as orders")
    r = await started(tmp_path, "echo.m")
    try:
        assert r.run.state == "running" and r.run.reloads == 1
        p = await answer(r.send(game((1, 2, 7), t=1.5), None, 0.01))
        assert p.reason == "", p.reason
        orders = validate_orders(p.output, (1, 2, 7))
        assert orders[1] == TargetOrder(1, 9000.0, 2.0)  # field length, two of theirs
        assert orders[2] == TargetOrder(2, 9000.0, 2.0)
        assert orders[7] == VelocityOrder(7, 0.0, 3.0, 1.0, dribble=True)  # ball x, 2t, blue
        assert r.run.ticks == 1 and r.run.tick_ms
    finally:
        await r.close()


async def test_lib_on_the_path_and_a_save_restarts_with_a_clean_workspace(
        tmp_path: Path) -> None:
    write(tmp_path, "lib/step_size.m", "function s = step_size()\n  s = 10;\nend\n")
    write(tmp_path, "counter.m", "function orders = counter(ours, theirs, ball, game)\n"
                                 "  persistent n\n  if isempty(n)\n    n = 0;\n  end\n"
                                 "  n = n + step_size();\n"
                                 "  orders = [1 0 n 0 NaN NaN 0 0 0];\nend\n")
    r = await started(tmp_path, "counter.m")
    try:
        xs = [(await answer(r.send(game((1,)), None, 0.01))).output[0][2] for _ in range(3)]
        assert xs == [10.0, 20.0, 30.0]
        write(tmp_path, "lib/step_size.m", "function s = step_size()\n  s = 1;\nend\n")
        r.update(found(tmp_path, "counter.m"))  # what the host does on an .m library's save
        await until(lambda: r.run.state == "running" and r.run.reloads == 2, 60.0)
        xs = [(await answer(r.send(game((1,)), None, 0.01))).output[0][2] for _ in range(2)]
        assert xs == [1.0, 2.0]  # persistent n started afresh, the new library in use
    finally:
        await r.close()


async def test_errors_say_where(tmp_path: Path) -> None:
    write(tmp_path, "oops.m", "function orders = oops(ours, theirs, ball, game)\n"
                              "  orders = helper(ours);\nend\n"
                              "function y = helper(x)\n  y = [1 2] * [3 4];\nend\n")
    write(tmp_path, "typo.m", "function orders = typo(ours, theirs, ball, game)\n"
                              "  x = (1;\n  orders = [];\nend\n")
    r = await started(tmp_path, "oops.m")
    r2 = await started(tmp_path, "typo.m")
    try:
        await answer(r.send(game(), None, 0.01))
        e = r.run.error
        assert e is not None and (e.kind, e.file, e.line) == ("exception", "oops.m", 5)
        assert "nonconformant" in e.message and "oops.m, line 2" in e.traceback
        e = r2.run.error  # read when its worker started: nothing to ask
        assert r2.run.state == "error" and r2.send(game(), None, 0.01) is None
        assert e is not None and (e.kind, e.file, e.line) == ("import", "typo.m", 2)
        # fixed: resumes
        write(tmp_path, "typo.m", "function orders = typo(ours, theirs, ball, game)\n"
                                  "  orders = [];\nend\n")
        r2.update(found(tmp_path, "typo.m"))
        await until(lambda: r2.run.state == "running", 60.0)
        assert (await answer(r2.send(game(), None, 0.01))).output == []
    finally:
        await r.close()
        await r2.close()


async def test_a_stuck_play_is_stopped_by_the_engine_timeout(tmp_path: Path) -> None:
    """Each call past the engine's timeout is discarded (the worker restarted, nothing is
    asked meanwhile); the third in a row fails the play until its next save."""
    write(tmp_path, "forever.m", "function orders = forever(ours, theirs, ball, game)\n"
                                 "  while true\n  end\nend\n")
    r = await started(tmp_path, "forever.m", timeout_s=0.3)
    try:
        timed_out = 0
        while r.run.state == "running":
            # (after a timeout nothing is asked until the engine's new worker is up)
            await until(lambda: r.engine is not None and r.engine.health()["idle"] == 1,
                        60.0, "a worker to call")
            p = r.send(game(), None, 0.01)
            await answer(p)
            assert p.output is None and p.reason.startswith("over its budget")
            timed_out += 1
        assert timed_out == 3 and r.run.overruns == 3
        e = r.run.error
        assert e is not None and e.kind == "budget" and "engine_timeout_s = 0.3 s" in e.message
        assert "3 ticks in a row" in e.message
    finally:
        await r.close()


def test_malformed_matrices() -> None:
    assert plain_matrix_orders([]) == [] and plain_matrix_orders(np.zeros((0, 9))) == []
    with pytest.raises(OctaveOutputError, match="9 columns"):
        plain_matrix_orders(np.zeros((2, 4)))
    with pytest.raises(OctaveOutputError, match="mode"):
        plain_matrix_orders(np.array([[1, 2, 0, 0, 0, 0, 0, 0, 0]]))
    with pytest.raises(OctaveOutputError, match="robot id"):
        plain_matrix_orders(np.array([[math.nan, 0, 0, 0, 0, 0, 0, 0, 0]]))
    with pytest.raises(OctaveOutputError):
        plain_matrix_orders("text")
    # NaN where a number is needed passes through to the station's check
    plain = plain_matrix_orders(np.array([[1, 0, math.nan, 0, 0, 0, 0, 0, 0]]))
    with pytest.raises(ValueError, match="x is nan"):
        validate_orders(plain, (1,))


async def test_the_shipped_octave_play_drives_through_the_strategy() -> None:
    rig = Rig(ROOT / "team", "keeper_wall")
    rig.robots[0] = (-2000.0, 0.0, 0.0)
    try:
        await rig.running("keeper_wall.m")
        await rig.tick()
        run = rig.registry.runs["keeper_wall.m"]
        assert run.state == "running" and run.error is None, run.error
        t = rig.targets()
        assert set(t) == {0, 1, 2, 3} and all(e.source == "team" and not e.stop
                                              for e in t.values())
        assert run.moved_out == 0
        keeper = t[0].target  # robot 0 keeps goal (no referee names another)
        assert keeper.x < -4000.0 and abs(keeper.y) < 500.0
        for rid in (1, 2, 3):  # the wall, outside our defence area
            assert t[rid].target.x > -4500.0 + 1000.0
    finally:
        await rig.close()
