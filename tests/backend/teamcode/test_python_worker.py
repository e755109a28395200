"""A Python play or processor in its worker process: loading, reloading (state kept when the
play says how), errors with file and line, budgets (CPU time), a spin stopped with its line,
the memory limit, a crash, and the interface (plain data both ways)."""

from __future__ import annotations

import math
import pickle
from pathlib import Path

import pytest

from backend.teamcode.orders import OrderError, TargetOrder, VelocityOrder, validate_orders
from backend.teamcode.pyworker import plain_loads
from backend.teamcode.runner import OVER_BUDGET_IN_A_ROW, PythonRunner
from backend.teamcode.worker import OutputError, plain_orders, plain_outputs
from touchline import STOP, Target, Velocity

from .helpers import answer, found, game, started, until, write

BUDGET = 0.010


async def test_a_play_loads_and_answers(tmp_path: Path) -> None:
    write(tmp_path, "ring.py", "from touchline import Target, STOP\n"
                               "def play(game):\n"
                               "    r = game.robot(game.mine[0])\n"
                               "    return {game.mine[0]: Target(r.x + 100.0, game.t, None,\n"
                               "                                 role='ring'),\n"
                               "            game.mine[1]: STOP}\n")
    r = await started(tmp_path, "ring.py")
    try:
        assert r.run.state == "running" and r.run.error is None
        assert r.run.loaded_version == found(tmp_path, "ring.py").version
        assert r.pid > 0
        p = await answer(r.send(game((1, 2), t=7.0), None, BUDGET))
        assert p.reason == "" and p.version == r.run.loaded_version
        assert p.output == [("T", 1, -600.0, 7.0, None, None, 0.0, False, False, True, "ring"),
                            ("V", 2, 0.0, 0.0, 0.0, 0.0, False, False, "")]
        assert r.run.ticks == 1 and len(r.run.tick_ms) == 1
        orders = validate_orders(p.output, {1, 2})
        assert orders[1] == TargetOrder(1, -600.0, 7.0, role="ring")
        assert orders[2] == VelocityOrder(2, 0.0, 0.0, 0.0)
    finally:
        await r.close()
    assert r.run.state == "idle"


async def test_a_reload_keeps_state_when_the_play_says_how(tmp_path: Path) -> None:
    src = ("from touchline import Target\nSTEP = {step}\nclass Play:\n"
           "    def __init__(self):\n        self.n = 0\n"
           "    def tick(self, game):\n        self.n += STEP\n"
           "        return {{1: Target(self.n, 0.0)}}\n"
           "    def keep(self):\n        return self.n\n"
           "    def restore(self, kept):\n        self.n = kept\n")
    write(tmp_path, "count.py", src.format(step=1))
    write(tmp_path, "plain.py", "from touchline import Target\nN = [0]\n"
                                "def play(game):\n    N[0] += 1\n"
                                "    return {1: Target(N[0], 0.0)}\n")
    counter = await started(tmp_path, "count.py")
    plain = await started(tmp_path, "plain.py")
    try:
        pid = counter.pid
        for want in (1, 2, 3):
            p = await answer(counter.send(game((1,)), None, 1.0))
            assert p.output[0][2] == want
            q = await answer(plain.send(game((1,)), None, 1.0))
            assert q.output[0][2] == want
        write(tmp_path, "count.py", src.format(step=100))
        write(tmp_path, "plain.py", "from touchline import Target\nN = [0]\n"
                                    "def play(game):\n    N[0] += 10\n"
                                    "    return {1: Target(N[0], 0.0)}\n")
        counter.update(found(tmp_path, "count.py"))
        plain.update(found(tmp_path, "plain.py"))
        await until(lambda: counter.run.reloads == 2 and plain.run.reloads == 2)
        assert counter.pid == pid  # reloaded in place, not a new process
        p = await answer(counter.send(game((1,)), None, 1.0))
        assert p.output[0][2] == 103  # 3 kept, then the new step
        assert p.version == found(tmp_path, "count.py").version
        q = await answer(plain.send(game((1,)), None, 1.0))
        assert q.output[0][2] == 10  # module state starts afresh
    finally:
        await counter.close()
        await plain.close()


async def test_a_library_is_imported_again_on_reload(tmp_path: Path) -> None:
    write(tmp_path, "lib/speeds.py", "FAST = 1.0\n")
    write(tmp_path, "uses_lib.py", "from touchline import Target\nimport speeds\n"
                                   "def play(game):\n"
                                   "    return {1: Target(0.0, 0.0, max_speed_mps=speeds.FAST)}\n")
    r = await started(tmp_path, "uses_lib.py")
    try:
        p = await answer(r.send(game((1,)), None, 1.0))
        assert p.output[0][5] == 1.0
        write(tmp_path, "lib/speeds.py", "FAST = 2.5\n")
        r.update(found(tmp_path, "uses_lib.py"))  # what the host does on a library's save
        await until(lambda: r.run.reloads == 2)
        p = await answer(r.send(game((1,)), None, 1.0))
        assert p.output[0][5] == 2.5
    finally:
        await r.close()


async def test_an_import_error_says_where(tmp_path: Path) -> None:
    write(tmp_path, "bad_import.py", "from touchline import Target\n\n"
                                     "import no_such_module_here\n"
                                     "def play(game):\n    return {}\n")
    write(tmp_path, "lib/broken_lib.py", "X = 1\nY = 1 / 0\n")
    write(tmp_path, "bad_lib.py", "import broken_lib\ndef play(game):\n    return {}\n")
    r = await started(tmp_path, "bad_import.py")
    r2 = await started(tmp_path, "bad_lib.py")
    try:
        e = r.run.error
        assert r.run.state == "error" and e is not None
        assert (e.kind, e.file, e.line) == ("import", "bad_import.py", 3)
        assert "no_such_module_here" in e.message and "ModuleNotFoundError" in e.message
        assert "worker.py" not in e.traceback and 'File "bad_import.py", line 3' in e.traceback
        assert r.send(game(), None, BUDGET) is None  # a failed file is not asked
        e2 = r2.run.error
        assert e2 is not None and (e2.kind, e2.file, e2.line) == ("import", "lib/broken_lib.py",
                                                                   2)
        assert "ZeroDivisionError" in e2.message
        # the next save that fixes it resumes
        write(tmp_path, "bad_import.py", "def play(game):\n    return {}\n")
        r.update(found(tmp_path, "bad_import.py"))
        await until(lambda: r.run.state == "running")
        assert (await answer(r.send(game(), None, 1.0))).output == []
        assert r.run.errors == 1 and r.run.error is None
    finally:
        await r.close()
        await r2.close()


async def test_a_syntax_error_fails_at_once_and_the_old_version_stops(tmp_path: Path) -> None:
    write(tmp_path, "edit.py", "from touchline import Target\n"
                               "def play(game):\n    return {1: Target(0.0, 0.0)}\n")
    r = await started(tmp_path, "edit.py")
    try:
        assert r.run.state == "running"
        write(tmp_path, "edit.py", "from touchline import Target\n"
                                   "def play(game):\n    return {1: Target(0.0, 0.0}\n")
        f = found(tmp_path, "edit.py")
        assert f.error is not None  # discovery saw it (no worker involved)
        r.update(f)
        assert r.run.state == "error" and r.run.error is not None
        assert (r.run.error.kind, r.run.error.line) == ("import", 3)
        assert r.send(game(), None, BUDGET) is None  # never the last version's answer
    finally:
        await r.close()


async def test_an_exception_has_its_traceback(tmp_path: Path) -> None:
    write(tmp_path, "lib/helpers.py", "def divide(a, b):\n    return a / b\n")
    write(tmp_path, "raises.py", "from helpers import divide\n"
                                 "def play(game):\n"
                                 "    return {1: divide(1, 0)}\n")
    r = await started(tmp_path, "raises.py")
    try:
        p = await answer(r.send(game(), None, 1.0))
        e = r.run.error
        assert e is not None and (e.kind, e.file, e.line) == ("exception", "lib/helpers.py", 2)
        # the failing tick's robots say why, as every later tick's do (not a bare "failed")
        assert p.output is None and p.reason == e.one_line()
        assert p.reason.startswith("exception at lib/helpers.py:2: ZeroDivisionError"), p.reason
        assert e.message == "ZeroDivisionError: division by zero"
        assert 'File "raises.py", line 3, in play' in e.traceback
        assert 'File "lib/helpers.py", line 2, in divide' in e.traceback
        assert "backend" not in e.traceback
        assert r.run.errors == 1
        assert r.send(game(), None, 1.0) is None
    finally:
        await r.close()


async def test_a_failure_right_after_a_reload_is_counted_once(tmp_path: Path) -> None:
    """A save with a typo that only a call finds (game.mien): the reload imports fine, the
    first call fails. The failure must stand: counted once, not cleared by the load's answer
    and counted again on the next tick (errors: 2 for one typo before, when a tick sent
    during the reload was answered in the same read as the load). No call goes to a worker
    that is importing (it could not answer: the call would be billed for the import); the
    first one after the load is the one that fails."""
    good = ("import os, time\nfrom touchline import Target\n"
            "GATE = {gate!r}\n"
            "deadline = time.monotonic() + 20.0\n"
            "while not os.path.exists(GATE) and time.monotonic() < deadline:\n"
            "    time.sleep(0.001)  # a slow import (numpy, a model...), until the test opens\n"
            "def play(game):\n    return {{r: Target(0.0, 0.0) for r in game.mine}}\n")
    gate = tmp_path / "gate"
    gate.touch()
    write(tmp_path, "typo.py", good.format(gate=str(gate)))
    r = await started(tmp_path, "typo.py")
    try:
        assert (await answer(r.send(game(), None, 1.0))).output is not None
        gate.unlink()
        write(tmp_path, "typo.py", good.format(gate=str(gate)).replace("game.mine", "game.mien"))
        r.update(found(tmp_path, "typo.py"))
        await until(lambda: r._loading, what="the load request with the worker")
        assert r.run.state == "running" and r.reloading
        assert r.send(game(), None, 1.0) is None  # not asked while it imports
        gate.touch()  # the import ends; the worker answers the load
        await until(lambda: r._task is None and not r.reloading, what="the load accounted")
        p = await answer(r.send(game(), None, 1.0))
        assert r.run.state == "error" and r.run.error is not None
        assert p.reason == r.run.error.one_line()
        assert "mien" in r.run.error.message
        assert r.run.errors == 1
        assert r.send(game(), None, 1.0) is None  # failed: not asked again until a save
        assert r.run.errors == 1
    finally:
        await r.close()


@pytest.mark.parametrize(("body", "message"), [
    ("return [1, 2]", "the play returned list"),
    ("return {1: 'fast'}", "robot 1's order is str"),
    ("return {'1': Target(0, 0)}", "a key of the play's dict is str"),
    ("return {1.5: Target(0, 0)}", "a key of the play's dict is float"),
    ("return {1: Target('a', 0)}", "robot 1's order x is str"),
    ("return None", "the play returned NoneType None (no return statement reached?)"),
    ("pass", "the play returned NoneType None (no return statement reached?)"),
    ("return Target(0, 0)", "(one order: say for which robot, {robot id: order})"),
])
async def test_malformed_output_is_an_output_error(tmp_path: Path, body: str,
                                                   message: str) -> None:
    write(tmp_path, "malformed.py", f"from touchline import Target\n"
                                    f"def play(game):\n    {body}\n")
    r = await started(tmp_path, "malformed.py")
    try:
        p = await answer(r.send(game(), None, 1.0))
        assert p.output is None
        e = r.run.error
        assert e is not None and e.kind == "output" and message in e.message, e
    finally:
        await r.close()


def test_the_station_checks_values_and_ids_itself() -> None:
    ok = ("T", 1, 0.0, 0.0, None, None, 0.0, False, False, True, "")
    assert validate_orders([ok], {1}) == {1: TargetOrder(1, 0.0, 0.0)}
    cases = [
        ([("T", 1, math.nan, 0.0, None, None, 0.0, False, False, True, "")], "x is nan"),
        ([("T", 1, 0.0, math.inf, None, None, 0.0, False, False, True, "")], "y is inf"),
        ([("V", 1, 0.0, math.nan, 0.0, 0.0, False, False, "")], "left_mps is nan"),
        ([("T", 7, 0.0, 0.0, None, None, 0.0, False, False, True, "")],
         "robot 7 is not one this play drives (it drives 1, 2)"),
        ([ok, ok], "robot 1 has two orders"),
        ([("T", 1, 0.0, 0.0, None, None, -1.0, False, False, True, "")], "kick_mps is -1.0"),
        ([("T", 1, 0.0, 0.0, None, -2.0, 0.0, False, False, True, "")], "max_speed_mps"),
        ([("T", 1, 0.0, 0.0, None, None, 0.0, 1, False, True, "")], "chip is int"),
        ([("T", True, 0.0)], "no robot id"),
        ([("X", 1)], "not a Target or a Velocity"),
        ({"1": 2}, "not a list"),
        ([[1]], "not an order"),
    ]
    for plain, message in cases:
        with pytest.raises(OrderError, match=None) as exc:
            validate_orders(plain, {1, 2})
        assert message in str(exc.value), (plain, exc.value)
    # a max speed of 0 is the controller's own (as NaN/0 in an Octave play)
    z = validate_orders([("T", 1, 0.0, 0.0, None, 0.0, 0.0, False, False, True, "")], {1})
    assert z[1].max_speed_mps is None  # type: ignore[union-attr]


def test_plain_data_both_ways() -> None:
    import numpy as np

    assert plain_orders({np.int64(3): Target(np.float64(1.0), 2, None)}) == [
        ("T", 3, 1.0, 2.0, None, None, 0.0, False, False, True, "")]
    assert plain_orders({2: Velocity(1, 0, 0.5, kick_mps=3)}) == [
        ("V", 2, 1.0, 0.0, 0.5, 3.0, False, False, "")]
    assert plain_orders({1: STOP}) == [("V", 1, 0.0, 0.0, 0.0, 0.0, False, False, "")]
    with pytest.raises(OutputError):
        plain_orders({True: STOP})
    assert plain_outputs({"ours": 0.7, "near": 3, "flag": True}) == {
        "ours": 0.7, "near": 3.0, "flag": 1.0}
    with pytest.raises(OutputError, match="output name"):
        plain_outputs({"has space": 1.0})
    with pytest.raises(OutputError, match="not a number"):
        plain_outputs({"x": "1.0"})
    with pytest.raises(OutputError, match=r"tick returned NoneType None \(no return statement"):
        plain_outputs(None)  # a tick that forgot its return
    # what the station reads from a worker is plain data only: a class is refused
    assert plain_loads(pickle.dumps(("out", 1, [("T", 1)], 0.0, "v"))) == \
        ("out", 1, [("T", 1)], 0.0, "v")
    with pytest.raises(pickle.UnpicklingError):
        plain_loads(pickle.dumps(Target(0, 0)))


BURN = ("import time\nfrom touchline import Target\nMS = {ms}\n"
        "def play(game):\n    t = time.thread_time()\n"
        "    while time.thread_time() - t < MS / 1000.0:\n        pass\n"
        "    return {{1: Target(0.0, 0.0)}}\n")


async def test_over_budget_three_ticks_in_a_row_fails(tmp_path: Path) -> None:
    write(tmp_path, "slow.py", BURN.format(ms=30))
    r = await started(tmp_path, "slow.py")
    try:
        # the first call after a load is its warm-up: not held to the budget
        p = await answer(r.send(game(), None, BUDGET))
        assert p.output is not None and p.cpu_ms is not None and p.cpu_ms >= 30.0
        assert r.run.overruns == 0
        for k in range(OVER_BUDGET_IN_A_ROW):
            assert r.run.state == "running"
            p = await answer(r.send(game(), None, BUDGET))
            assert p.output is None and p.reason.startswith("over its budget")
            assert p.cpu_ms is not None and p.cpu_ms >= 30.0
            assert r.run.overruns == k + 1
        e = r.run.error
        assert r.run.state == "error" and e is not None and e.kind == "budget"
        assert "3 ticks in a row" in e.message
        # within budget again after a save
        write(tmp_path, "slow.py", BURN.format(ms=1))
        r.update(found(tmp_path, "slow.py"))
        await until(lambda: r.run.state == "running")
        p = await answer(r.send(game(), None, 0.5))
        assert p.output is not None and r.run.overruns == 3
    finally:
        await r.close()


async def test_one_tick_over_budget_is_discarded_but_not_fatal(tmp_path: Path) -> None:
    write(tmp_path, "once.py", "import time\nfrom touchline import Target\nN = [0]\n"
                               "def play(game):\n    N[0] += 1\n    t = time.thread_time()\n"
                               "    while N[0] == 2 and time.thread_time() - t < 0.03:\n"
                               "        pass\n    return {1: Target(N[0], 0.0)}\n")
    r = await started(tmp_path, "once.py")
    try:
        got = [(await answer(r.send(game(), None, 0.015))).output for _ in range(4)]
        assert got[1] is None and [g[0][2] for g in (got[0], got[2], got[3])] == [1, 3, 4]
        assert r.run.state == "running" and r.run.overruns == 1
    finally:
        await r.close()


async def test_a_late_answer_is_counted_late_not_over_budget(tmp_path: Path) -> None:
    """An answer that comes after the tick stopped waiting, with little CPU time spent (the
    worker not scheduled on a busy machine; here: it waits on a gate, asleep): discarded for
    that tick and counted as late, not over the play's CPU budget."""
    gate = tmp_path / "gate"
    gate.touch()
    write(tmp_path, "sleepy.py", "import os, time\nfrom touchline import Target\n"
                                 f"GATE = {str(gate)!r}\n"
                                 "def play(game):\n"
                                 "    end = time.monotonic() + 20.0\n"
                                 "    while not os.path.exists(GATE) and time.monotonic() < end:\n"
                                 "        time.sleep(0.001)\n"
                                 "    return {1: Target(0.0, 0.0)}\n")
    r = await started(tmp_path, "sleepy.py")
    try:
        assert (await answer(r.send(game(), None, BUDGET))).output is not None  # warm-up
        gate.unlink()
        p = r.send(game(), None, BUDGET)
        assert p is not None
        r.late(p)  # the tick's deadline (TeamTick.wait): no answer yet
        assert p.reason.startswith("late") and (r.run.late, r.run.overruns) == (1, 0)
        gate.touch()
        await answer(p)
        assert p.cpu_ms is not None and p.cpu_ms < BUDGET * 1000.0
        assert (r.run.late, r.run.overruns, r.run.state) == (1, 0, "running")
    finally:
        await r.close()


async def test_the_reason_says_whether_the_machine_or_the_play_is_busy(tmp_path: Path) -> None:
    """While a call has not answered, the robots' reason tells a busy machine (the call has
    used less CPU time than its budget) from a play that computes (more): from the worker's
    CPU time."""
    gate = tmp_path / "gate"
    write(tmp_path, "churn.py", "import os\nfrom touchline import Target\n"
                                f"GATE = {str(gate)!r}\n"
                                "def play(game):\n"
                                "    while os.path.exists(GATE):\n"
                                "        pass\n"
                                "    return {1: Target(0.0, 0.0)}\n")
    r = await started(tmp_path, "churn.py")
    try:
        assert (await answer(r.send(game(), None, 0.05))).output is not None  # warm-up
        gate.touch()
        p = r.send(game(), None, 0.05)
        assert p is not None
        assert r.waiting().startswith("late: its previous tick has not answered yet (the "
                                      "machine is busy: "), r.waiting()
        # two budgets: /proc counts CPU time in 10 ms ticks, the worker's own count is exact
        await until(lambda: (r.call_cpu_s(p) or 0.0) >= 0.1, what="100 ms of CPU time used")
        assert r.waiting().startswith("busy: its previous tick is still computing ("), \
            r.waiting()
        assert "ms of CPU time so far, over its 50 ms budget)" in r.waiting()
        gate.unlink()
        await answer(p)
        assert p.output is None and p.reason.startswith("over its budget")
        assert r.run.state == "running"
    finally:
        gate.unlink(missing_ok=True)
        await r.close()


def alive(pid: int) -> bool:
    """Process ``pid`` exists and has not ended (a zombie has)."""
    try:
        with open(f"/proc/{pid}/stat") as f:
            return f.read().rsplit(")", 1)[1].split()[0] != "Z"
    except OSError:
        return False


#: the call's own CPU time (its thread's) when the 0.25 s limit stops it: the limit counts the
#: worker process's CPU time (ITIMER_PROF, every thread, sampled by the kernel's ticks), so on
#: a loaded machine the call's thread has 215-229 ms of it then (seen at load 3-7)
CPU_SEEN_MS = 200.0


async def test_a_spin_is_stopped_at_its_cpu_limit_with_its_line(tmp_path: Path) -> None:
    """A ``while True:`` is stopped once it used its CPU limit (10 budgets, at least 0.25 s
    of CPU time), by the worker itself: the error names the CPU limit and the line where it
    spun (its traceback, even through ``except Exception``); its worker is ended."""
    write(tmp_path, "spin.py", "from touchline import Target\n"
                               "def play(game):\n"
                               "    x = 0\n"
                               "    while True:\n"
                               "        try:\n"
                               "            x += 1\n"
                               "        except Exception:\n"
                               "            pass\n"
                               "    return {}\n")
    r = await started(tmp_path, "spin.py")
    try:
        pid = r.pid
        p = r.send(game(), None, BUDGET)
        assert p is not None
        # the tick gives up after its budget; later ticks find the call still running
        assert r.send(game(), None, BUDGET) is None
        await until(lambda: r.run.state == "error", what="the spin stopped")
        e = r.run.error
        assert e is not None and e.kind == "budget", e
        assert e.message.startswith("spinning: over its CPU limit in one call (0.25 s of CPU "
                                    "time"), e.message
        assert (e.file, e.line) in (("spin.py", 4), ("spin.py", 5), ("spin.py", 6)), e
        assert 'File "spin.py", line' in e.traceback and "CpuLimitExceeded" in e.traceback
        assert "worker.py" not in e.traceback  # how it was stopped is not the team's code
        assert p.done and p.output is None and p.cpu_ms is not None and p.cpu_ms >= CPU_SEEN_MS
        await until(lambda: not alive(pid), what="its worker ended")
        assert r.pid == 0
        # a fixed save starts a new worker
        write(tmp_path, "spin.py", "def play(game):\n    return {}\n")
        r.update(found(tmp_path, "spin.py"))
        await until(lambda: r.run.state == "running")
        assert r.pid not in (0, pid)
        assert (await answer(r.send(game(), None, 1.0))).output == []
    finally:
        await r.close()


async def test_a_play_that_catches_its_cpu_limit_goes_on_and_a_later_crash_says_its_line(
        tmp_path: Path) -> None:
    """A play that catches CpuLimitExceeded (``except BaseException``) and answers: over its
    budget, not failed, same worker. The stacks written at the limit are forgotten: a crash
    later names its own line, not the old spin's."""
    write(tmp_path, "catches.py", "import os, signal\n"
                                  "N = [0]\n"
                                  "def play(game):\n"
                                  "    N[0] += 1\n"
                                  "    if N[0] == 2:\n"
                                  "        try:\n"
                                  "            while True:\n"
                                  "                pass\n"
                                  "        except BaseException:\n"
                                  "            return {}\n"
                                  "    if N[0] == 3:\n"
                                  "        os.kill(os.getpid(), signal.SIGSEGV)\n"
                                  "    return {}\n")
    r = await started(tmp_path, "catches.py")
    try:
        pid = r.pid
        assert (await answer(r.send(game(), None, BUDGET))).output == []  # warm-up
        p = await answer(r.send(game(), None, BUDGET))
        assert p.reason.startswith("over its budget") and p.cpu_ms is not None and \
            p.cpu_ms >= CPU_SEEN_MS
        assert (r.run.state, r.run.overruns, r.pid) == ("running", 1, pid)
        r.send(game(), None, BUDGET)
        await until(lambda: r.run.state == "error", what="the crash")
        e = r.run.error
        assert e is not None and e.kind == "crash" and (e.file, e.line) == ("catches.py", 12), e
    finally:
        await r.close()


async def test_a_spin_in_one_long_c_call_is_stopped_by_the_station(tmp_path: Path) -> None:
    """A call into C that never looks at signals (here ``sum`` over a huge range) cannot be
    interrupted by the worker's SIGPROF: the station sees the worker's CPU time (/proc) go
    past the limit and ends it; the stack written at the limit gives the line."""
    write(tmp_path, "csum.py", "def play(game):\n"
                               "    n = 0\n"
                               "    n += sum(range(10 ** 15))\n"
                               "    return {}\n")
    r = await started(tmp_path, "csum.py")
    try:
        pid = r.pid
        assert r.send(game(), None, BUDGET) is not None
        await until(lambda: r.run.state == "error", what="the worker stopped")
        e = r.run.error
        assert e is not None and e.kind == "budget", e
        assert e.message.startswith("spinning: over its CPU limit in one call (") and \
            "the limit 0.25 s) and not stopped by it" in e.message, e.message
        assert (e.file, e.line) == ("csum.py", 3) and "its worker was stopped" in e.message
        assert r.pid == 0
        await until(lambda: not alive(pid), what="its worker ended")
    finally:
        await r.close()


async def test_a_spin_that_turns_its_cpu_limit_off_is_stopped_by_the_station(
        tmp_path: Path) -> None:
    write(tmp_path, "sly.py", "import faulthandler, signal\n"
                              "def play(game):\n"
                              "    faulthandler.cancel_dump_traceback_later()\n"
                              "    signal.setitimer(signal.ITIMER_PROF, 0.0)\n"
                              "    while True:\n"
                              "        pass\n")
    r = await started(tmp_path, "sly.py")
    try:
        assert r.send(game(), None, BUDGET) is not None
        await until(lambda: r.run.state == "error", what="the worker stopped")
        e = r.run.error
        assert e is not None and e.kind == "budget", e
        assert e.message.startswith("spinning: over its CPU limit in one call"), e.message
        # where: the stack the station asked for (SIGUSR1) before it ended the worker
        assert e.file == "sly.py" and e.line in (5, 6), e
        assert r.pid == 0
    finally:
        await r.close()


async def test_a_call_that_waits_is_stopped_at_the_wall_clock_backstop(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """A call that waits (a sleep, a lock) uses no CPU time: it is stopped by the wall-clock
    backstop (here 2 CPU limits, 0.5 s, instead of 10), with the line where it waited."""
    from backend.teamcode import runner as runner_mod

    monkeypatch.setattr(runner_mod, "WALL_FACTOR", 2.0, raising=False)
    write(tmp_path, "nap.py", "import time\n"
                              "def play(game):\n"
                              "    time.sleep(600)\n"
                              "    return {}\n")
    r = await started(tmp_path, "nap.py")
    try:
        p = r.send(game(), None, BUDGET)
        assert p is not None
        await until(lambda: r.run.state == "error", what="the worker stopped")
        e = r.run.error
        assert e is not None and e.kind == "budget", e
        assert e.message.startswith("stuck: no answer within 0.5 s of wall time, with 0."), \
            e.message
        assert "waiting on something, or its worker not scheduled" in e.message
        assert (e.file, e.line) == ("nap.py", 3), e
    finally:
        await r.close()


async def test_a_stopped_worker_is_not_killed_while_the_machine_does_not_run_it(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """A healthy play whose worker the machine does not run (SIGSTOP, a real process signal,
    for longer than the old wall-clock limit of 0.75 s; a loaded laptop does the same in
    smaller doses) is not ended: it used no CPU time. Its tick is late meanwhile (the
    reason says the machine is busy), and after SIGCONT it answers and goes on in the same
    worker. (The wall-clock backstop is put far off, so that a loaded test machine cannot
    reach it before the test sends SIGCONT: the backstop is tested on its own.)"""
    import os
    import signal

    from backend.teamcode import runner as runner_mod

    monkeypatch.setattr(runner_mod, "WALL_FACTOR", 100.0, raising=False)
    write(tmp_path, "calm.py", "from touchline import Target\n"
                               "def play(game):\n"
                               "    return {1: Target(1.0, 2.0)}\n")
    r = await started(tmp_path, "calm.py")
    try:
        await answer(r.send(game(), None, BUDGET))  # its warm-up
        pid = r.pid
        os.kill(pid, signal.SIGSTOP)
        try:
            p = r.send(game(), None, BUDGET)
            assert p is not None
            r.late(p)  # the tick's deadline (TeamTick.wait): no answer
            # the station's watch looked at it past the old wall-clock limit (0.75 s) and
            # let it live (it ends a call at its CPU limit, or at the wall-clock backstop)
            await until(lambda: r.run.state == "error" or (
                getattr(r, "watched", None) is not None and r.watched.seen[0] > 1.0),
                what="a look past 1 s")
            assert r.run.state == "running" and r.pid == pid and not p.done, r.run.error
            assert r.watched is not None and r.watched.seen[1] is not None and \
                r.watched.seen[1] < BUDGET
            # its robots are held meanwhile, and the reasons say why: the machine
            assert p.output is None and p.reason.startswith(
                "late: no answer within the budget + grace (the machine is busy: 0 ms of CPU "
                "time so far)"), p.reason
            assert r.send(game(), None, BUDGET) is None  # nothing asked: still waiting
            assert r.waiting().startswith("late: its previous tick has not answered yet (the "
                                          "machine is busy"), r.waiting()
        finally:
            os.kill(pid, signal.SIGCONT)
        await answer(p)
        assert p.output is not None and p.cpu_ms is not None and p.cpu_ms < 250.0
        assert (r.run.state, r.run.late, r.pid) == ("running", 1, pid)
        q = await answer(r.send(game(), None, BUDGET))
        assert q.output == [("T", 1, 1.0, 2.0, None, None, 0.0, False, False, True, "")]
    finally:
        await r.close()


async def test_a_spin_at_import_is_stopped_too(tmp_path: Path, monkeypatch: pytest.MonkeyPatch
                                               ) -> None:
    from backend.teamcode import runner as runner_mod

    monkeypatch.setattr(runner_mod, "LOAD_LIMIT_S", 0.5)
    write(tmp_path, "spin_import.py", "while True:\n    pass\n")
    r = await started(tmp_path, "spin_import.py")
    try:
        await until(lambda: r.run.state == "error")
        e = r.run.error
        assert e is not None and (e.kind, e.file) == ("import", "spin_import.py")
        assert e.line in (1, 2) and e.message.startswith(
            "spinning: over its CPU limit while loading (0.5 s"), e.message
        await until(lambda: r.pid == 0, what="its worker ended")
    finally:
        await r.close()


async def test_a_spin_at_import_the_station_stops_says_import(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """The station ends a load that spins past its CPU limit with the limit turned off:
    an import error (the runner still knows it was loading when the worker is gone; it
    forgot it before and said "budget" when the station ended the load)."""
    from backend.teamcode import runner as runner_mod

    monkeypatch.setattr(runner_mod, "LOAD_LIMIT_S", 0.5)
    write(tmp_path, "sly_import.py", "import faulthandler, signal\n"
                                     "faulthandler.cancel_dump_traceback_later()\n"
                                     "signal.setitimer(signal.ITIMER_PROF, 0.0)\n"
                                     "while True:\n    pass\n")
    r = await started(tmp_path, "sly_import.py")
    try:
        await until(lambda: r.run.state == "error")
        e = r.run.error
        assert e is not None and (e.kind, e.file) == ("import", "sly_import.py"), e
        assert e.message.startswith("spinning: over its CPU limit while loading"), e.message
        assert e.line in (4, 5) and r.pid == 0
    finally:
        await r.close()


async def test_the_memory_limit(tmp_path: Path) -> None:
    write(tmp_path, "hog.py", "def play(game):\n"
                              "    block = bytearray(2 << 30)\n"
                              "    return {}\n")
    r = await started(tmp_path, "hog.py", memory_mb=256)
    try:
        await answer(r.send(game(), None, 1.0))
        e = r.run.error
        assert e is not None and (e.kind, e.line) == ("exception", 2)
        assert "MemoryError" in e.message
        # it says what the limit is and where it is set (a bare MemoryError did not)
        assert "memory limit of 256 MB" in e.message and "--team-memory-mb" in e.message
    finally:
        await r.close()


async def test_a_crash_says_so_and_a_save_respawns(tmp_path: Path) -> None:
    write(tmp_path, "crash.py", "import os, signal\n"
                                "def play(game):\n"
                                "    os.kill(os.getpid(), signal.SIGSEGV)\n")
    r = await started(tmp_path, "crash.py")
    try:
        r.send(game(), None, 1.0)
        await until(lambda: r.run.state == "error")
        e = r.run.error
        assert e is not None and e.kind == "crash", e
        assert (e.file, e.line) == ("crash.py", 3)  # faulthandler wrote the stack
        write(tmp_path, "crash.py", "def play(game):\n    return {}\n")
        r.update(found(tmp_path, "crash.py"))
        await until(lambda: r.run.state == "running")
    finally:
        await r.close()


async def test_prints_and_system_exit_do_not_break_the_protocol(tmp_path: Path) -> None:
    write(tmp_path, "chatty.py", "import sys\nfrom touchline import Target\n"
                                 "def play(game):\n"
                                 "    print('hello from the play' * 1000)\n"
                                 "    sys.stdout.write('\\x00\\x00\\x00\\x05junk')\n"
                                 "    return {1: Target(1.0, 2.0)}\n")
    write(tmp_path, "exits.py", "import sys\ndef play(game):\n    sys.exit(3)\n")
    r = await started(tmp_path, "chatty.py")
    r2 = await started(tmp_path, "exits.py")
    try:
        for _ in range(3):
            p = await answer(r.send(game(), None, 1.0))
            assert p.output is not None and p.output[0][2:4] == (1.0, 2.0)
        await answer(r2.send(game(), None, 1.0))
        e = r2.run.error
        assert e is not None and (e.kind, e.line) == ("exception", 3) and "SystemExit" in \
            e.message
    finally:
        await r.close()
        await r2.close()


async def test_a_processor_and_its_state(tmp_path: Path) -> None:
    write(tmp_path, "count_proc.py",
          "from touchline import Processor\n"
          "class Count(Processor):\n    rate_hz = 5.0\n"
          "    def __init__(self):\n        self.n = 0\n"
          "    def tick(self, game, inputs):\n        self.n += 1\n"
          "        return {'n': self.n, 'robots': len(game.ours), 'seen': 'x' in inputs,\n"
          "                'flag': self.n > 1}\n"
          "    def keep(self):\n        return self.n\n"
          "    def restore(self, kept):\n        self.n = kept\n")
    f = found(tmp_path, "count_proc.py")
    assert (f.kind, f.entry) == ("processor", "Count")
    r = await started(tmp_path, "count_proc.py", kind="processor")
    assert isinstance(r, PythonRunner)
    try:
        p = await answer(r.send(game(), {"x": [1, 2]}, 1.0))
        assert p.output == {"n": 1.0, "robots": 4.0, "seen": 1.0, "flag": 0.0}
        write(tmp_path, "count_proc.py", (tmp_path / "count_proc.py").read_text()
              .replace("self.n += 1", "self.n += 10"))
        r.update(found(tmp_path, "count_proc.py"))
        await until(lambda: r.run.reloads == 2)
        p = await answer(r.send(game(), {}, 1.0))
        assert p.output is not None and p.output["n"] == 11.0
    finally:
        await r.close()
