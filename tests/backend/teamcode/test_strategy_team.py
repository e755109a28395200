"""The strategy with the team's plays: robots grouped by the play they run, built-in plays
for their own robots only, team plays' targets and velocities as entries, failed or missing
plays' robots stopped with the reason, operator targets first."""

from __future__ import annotations

import asyncio
import math
import os
from pathlib import Path

import pytest

from backend import topics
from backend.control.goto import Target
from backend.messages import OperatorTarget

from .helpers import Rig, until, write

LINE = ("from touchline import Target, Velocity\n"
        "def play(game):\n"
        "    out = {}\n"
        "    for k, rid in enumerate(game.mine):\n"
        "        out[rid] = Target(-2000.0, 1000.0 * k, 0.5, role='liner')\n"
        "    return out\n")


async def test_plays_per_robot_and_the_sources(tmp_path: Path) -> None:
    write(tmp_path, "liner.py", LINE)
    write(tmp_path, "spin_robot.py", "from touchline import Velocity\n"
                                     "def play(game):\n"
                                     "    return {r: Velocity(0.0, 0.0, 1.0, role='spinner')\n"
                                     "            for r in game.mine}\n")
    rig = Rig(tmp_path, "liner", robot_plays={"2": "formation", "3": "spin_robot"})
    try:
        await rig.running("liner.py")
        await rig.running("spin_robot.py")
        await rig.tick()
        t = rig.targets()
        assert rig.strategy.robot_plays == {1: "liner", 2: "formation", 3: "spin_robot"}
        assert t[1].source == "team" and t[1].role == "liner"
        # our frame is the field frame here (our goal at -x)
        assert (t[1].target.x, t[1].target.y, t[1].target.orientation) == (-2000.0, 0.0, 0.5)
        assert t[2].source == "strategy" and t[2].role == "formation"
        assert t[3].source == "team" and t[3].velocity is not None
        assert t[3].velocity.angular_radps == 1.0 and t[3].role == "spinner"
        assert rig.registry.runs["liner.py"].robots == (1,)
        assert rig.registry.runs["spin_robot.py"].robots == (3,)
        # an operator's target comes first: the play no longer has the robot
        rig.bus.of(topics.OPERATOR_TARGETS).write(
            OperatorTarget("blue", 1, Target(500.0, 500.0, None)))
        await rig.tick()
        t = rig.targets()
        assert t[1].source == "operator" and 1 not in rig.strategy.robot_plays
    finally:
        await rig.close()


async def test_a_play_s_robots_are_its_own(tmp_path: Path) -> None:
    """A team play ordering a robot it does not drive is malformed (kind output)."""
    write(tmp_path, "greedy.py", "from touchline import Target\n"
                                 "def play(game):\n"
                                 "    return {r.id: Target(0.0, 0.0) for r in game.ours}\n")
    rig = Rig(tmp_path, "formation", robot_plays={"3": "greedy"})
    try:
        await rig.running("greedy.py")
        await rig.tick()
        run = rig.registry.runs["greedy.py"]
        assert run.state == "error" and run.error is not None and run.error.kind == "output"
        assert "robot 1 is not one this play drives (it drives 3)" in run.error.message
        t = rig.targets()
        assert t[3].stop and t[1].source == "strategy" and not t[1].stop
        assert rig.strategy.stopped == [(3, "greedy", run.error.one_line())]
    finally:
        await rig.close()


async def test_a_missing_play_and_a_left_out_robot(tmp_path: Path) -> None:
    write(tmp_path, "one.py", "from touchline import Target\n"
                              "def play(game):\n"
                              "    return {min(game.mine): Target(0.0, -1500.0)}\n")
    rig = Rig(tmp_path, "one", robot_plays={"3": "vanished"})
    try:
        await rig.running("one.py")
        await rig.tick()
        t = rig.targets()
        assert not t[1].stop and t[1].source == "team"
        assert t[2].stop  # left out by the play: held, not an error
        assert t[3].stop
        assert [s[:2] for s in rig.strategy.stopped] == [(3, "vanished")]
        assert "missing" in rig.strategy.stopped[0][2]
    finally:
        await rig.close()


async def test_an_error_names_file_and_line_and_a_fix_resumes(tmp_path: Path) -> None:
    write(tmp_path, "flaky.py", "from touchline import Target\n"
                                "def play(game):\n"
                                "    return {r: Target(0.0, 1 / 0) for r in game.mine}\n")
    rig = Rig(tmp_path, "flaky")
    try:
        await rig.running("flaky.py")
        await rig.tick()
        assert {s[0] for s in rig.strategy.stopped} == {1, 2, 3}
        assert all("exception at flaky.py:3: ZeroDivisionError" in s[2]
                   for s in rig.strategy.stopped)
        write(tmp_path, "flaky.py", "from touchline import Target\n"
                                    "def play(game):\n"
                                    "    return {r: Target(-500.0, 0.0) for r in game.mine}\n")
        rig.registry.rescan()  # the watcher's part
        for _ in range(2000):
            await rig.tick()
            if not rig.strategy.stopped:
                break
        t = rig.targets()
        assert all(not e.stop and math.isclose(e.target.x, -500.0) for e in t.values())
        assert rig.registry.runs["flaky.py"].errors == 1
    finally:
        await rig.close()


async def test_a_play_reads_the_processors_topics(tmp_path: Path) -> None:
    write(tmp_path, "follows.py", "from touchline import Target\n"
                                  "def play(game):\n"
                                  "    v = game.topics.get('possession', {}).get('ours', -1.0)\n"
                                  "    return {r: Target(1000.0 * v, 0.0) for r in game.mine}\n")
    rig = Rig(tmp_path, "follows")
    rig.strategy.team_topics = lambda: {"possession": {"ours": 0.75}}
    try:
        await rig.running("follows.py")
        await rig.tick()
        assert math.isclose(rig.targets()[1].target.x, 750.0)
    finally:
        await rig.close()


async def test_a_play_no_robot_runs_gives_its_worker_back(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    from backend.teamcode import plays as plays_mod

    write(tmp_path, "liner.py", LINE)
    rig = Rig(tmp_path, "liner")
    try:
        await rig.running("liner.py")
        runner = rig.plays.runners["liner.py"]
        pid = runner.pid  # type: ignore[attr-defined]
        assert pid > 0 and rig.registry.runs["liner.py"].robots == (1, 2, 3)
        rig.configure(play="formation")  # the built-in play for the whole team
        await rig.tick()
        assert rig.registry.runs["liner.py"].robots == ()
        assert "liner.py" in rig.plays.runners  # kept a while: a switch back is instant
        monkeypatch.setattr(plays_mod, "IDLE_CLOSE_S", 0.0)
        await rig.tick()
        assert "liner.py" not in rig.plays.runners
        await until(lambda: runner.closed and not rig.plays._closing)  # its close done
        with pytest.raises(ProcessLookupError):
            os.kill(pid, 0)
    finally:
        await rig.close()



WARM = ("import os, time\n"
        "from touchline import Target\n"
        "GATE = {gate!r}\n"
        "deadline = time.monotonic() + 20.0\n"
        "while not os.path.exists(GATE) and time.monotonic() < deadline:\n"
        "    time.sleep(0.001)  # a slow import (a model, a big table), until the test opens\n"
        "CALLS = [0]\n"
        "def play(game):\n"
        "    CALLS[0] += 1\n"
        "    if CALLS[0] <= {slow}:  # warm-up: the first call builds what later ones use\n"
        "        t = time.thread_time()\n"
        "        while time.thread_time() - t < 0.03:\n"
        "            pass\n"
        "    return {{r: Target(-1000.0, 600.0 * k - 600.0, 0.0, role='v{v}')\n"
        "            for k, r in enumerate(sorted(game.mine))}}\n")


async def test_a_reload_and_its_warm_up_are_not_billed_as_over_budget(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """After a save the new version imports (slowly here: until a gate opens) and its first
    call warms up (30 ms of CPU against a 10 ms budget); neither is an overrun: the ticks
    during the import are not sent to a worker that cannot answer (the play's robots are
    held meanwhile, 'reloading'), and the first call after a load is not held to the budget.
    The next calls are."""
    from backend.teamcode import plays as plays_mod

    # only the CPU-time budget is judged here: the ticks wait long for the answers (a
    # loaded machine stretches wall time)
    monkeypatch.setattr(plays_mod, "IPC_GRACE_S", 2.0)
    gate = tmp_path / "gate"
    gate.touch()
    write(tmp_path, "warm.py", WARM.format(gate=str(gate), slow=1, v=1))
    rig = Rig(tmp_path, "warm", team_budget_ms=10.0)
    try:
        run = rig.registry.runs["warm.py"]

        async def ticks_until(cond: object, what: str) -> None:
            for _ in range(2000):
                await rig.tick()
                if cond():  # type: ignore[operator]
                    return
                await asyncio.sleep(0.005)
            raise AssertionError(f"never: {what} ({run})")

        def runs(v: int) -> bool:  # every robot driven by version v
            t = rig.targets()
            return len(t) == 3 and all(not e.stop and e.role == f"v{v}" for e in t.values())
        await ticks_until(lambda: runs(1), "loaded and running")
        assert (run.overruns, run.errors, run.state) == (0, 0, "running")

        gate.unlink()
        write(tmp_path, "warm.py", WARM.format(gate=str(gate), slow=1, v=2))
        rig.registry.rescan()  # the watcher's part
        runner = rig.plays.runners["warm.py"]
        await until(lambda: runner.reloading, what="the new version's import under way")
        for _ in range(3):  # ticks while it imports: nobody to answer them
            await rig.tick()
        assert run.overruns == 0
        assert {rid for rid, _play, _why in rig.strategy.stopped} == {1, 2, 3}
        assert all("reloading" in why for _rid, _play, why in rig.strategy.stopped)
        gate.touch()
        # the new version's first call (its warm-up), then the next ones within budget
        await ticks_until(lambda: runs(2) and run.ticks >= 8, "the new version")
        assert (run.overruns, run.errors, run.state, run.reloads) == (0, 0, "running", 2)

        # only the first call is excused: a second one over the budget is counted
        write(tmp_path, "warm.py", WARM.format(gate=str(gate), slow=2, v=3))
        rig.registry.rescan()
        await ticks_until(lambda: run.overruns == 1, "the second call over the budget")
        await ticks_until(lambda: runs(3), "the version after it")
        assert run.state == "running" and run.overruns == 1
    finally:
        await rig.close()
