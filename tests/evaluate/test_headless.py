"""The headless run: the station's pipeline on fieldsim on a virtual clock, recorded as an SSL
log; deterministic for a seed."""

from __future__ import annotations

import dataclasses
import json
import os
import subprocess
import sys
from pathlib import Path
from typing import Any

import pytest

from evaluate.runner import (
    Entrant,
    MatchTask,
    ScenarioTask,
    run_match_task,
    run_scenario_task,
)
from evaluate.scenario import load_scenario
from ssllog.format import TYPE_REFEREE_2013, TYPE_TL_COMMANDS, TYPE_VISION_2014
from ssllog.reader import LogReader

DATA = Path(__file__).parent / "quick"


def _run(name: str, log: Path | None, **changes: Any) -> dict[str, Any]:
    sc = load_scenario(DATA / f"{name}.toml")
    if changes:
        sc = dataclasses.replace(sc, **changes)
    res = run_scenario_task(ScenarioTask(sc, 0, Entrant(), str(log) if log else None))
    assert res["error"] is None, res["error"]
    return {k: v for k, v in res.items() if k not in ("wall_s", "log")}


def test_same_seed_same_run_and_log(tmp_path: Path) -> None:
    a = _run("quick_keeper", tmp_path / "a.log")
    b = _run("quick_keeper", tmp_path / "b.log")
    assert a == b
    assert (tmp_path / "a.log").read_bytes() == (tmp_path / "b.log").read_bytes()
    c = _run("quick_keeper", tmp_path / "c.log", seed=6)
    assert (tmp_path / "c.log").read_bytes() != (tmp_path / "a.log").read_bytes()
    assert c["seed"] == 6


def test_the_log_is_what_the_station_records(tmp_path: Path) -> None:
    _run("quick_keeper", tmp_path / "k.log")
    types: dict[int, int] = {}
    times = []
    reader = LogReader(str(tmp_path / "k.log"))
    for rec in reader:
        if rec.time_ns == 0:  # the index record, last
            continue
        types[rec.type] = types.get(rec.type, 0) + 1
        times.append(rec.time_ns)
    assert reader.warning is None and reader.index_offsets
    assert times == sorted(times)
    # 4 cameras at 60 Hz for 2 s, the referee, our commands (TYPE_TL_COMMANDS)
    assert types[TYPE_VISION_2014] >= 4 * 60 * 2
    assert types[TYPE_REFEREE_2013] >= 10
    assert types[TYPE_TL_COMMANDS] > 50
    assert (times[-1] - times[0]) / 1e9 == pytest.approx(2.0, abs=0.05)


def test_goals_collisions_violations_and_actions_are_recorded() -> None:
    res = _run("quick_goal", None)
    kinds = [(e["kind"], e["team"], e["detail"].split(":")[0]) for e in res["events"]]
    goal = next(e for e in res["events"] if e["kind"] == "goal")
    # 1.0 m to the goal line (4.5 m) at 3 m/s slowing by 0.4 m/s^2: ~0.35 s
    assert goal["detail"] == "theirs" and 0.3 < goal["t"] < 0.45
    assert ("collision", "ours", "") in kinds
    assert ("violation", "ours", "stop_distance") in kinds  # robot 1 at the ball at STOP
    checks = {c["name"]: c["passed"] for c in res["checks"]}
    assert checks == {"ball_in_goal": True, "no_collision": False, "no_violation": False}
    assert not res["passed"] and res["score"] == pytest.approx(1 / 3, abs=1e-3)


def test_a_bad_play_or_parameter_fails_the_run_with_the_reason() -> None:
    sc = load_scenario(DATA / "quick_keeper.toml")
    res = run_scenario_task(ScenarioTask(sc, 0, Entrant("nosuchplay"), None))
    assert not res["passed"] and "nosuchplay" in res["error"]
    res = run_scenario_task(ScenarioTask(
        sc, 0, Entrant(params={"strategy.kick_speed_mps": 99.0}), None))
    assert not res["passed"] and "strategy.kick_speed_mps" in res["error"]


def test_a_short_match_is_played_and_judged(tmp_path: Path) -> None:
    task = MatchTask("m", Entrant("match"), Entrant("simple"), 3, half_s=4.0,
                     interludes=False, log_path=str(tmp_path / "m.log"))
    a = run_match_task(task)
    assert a["error"] is None, a["error"]
    res = a["result"]
    assert res["finished"] and res["stage"] == "POST_GAME"
    assert set(res["score"]) == {"blue", "yellow"}
    assert (tmp_path / "m.log").stat().st_size > 100_000
    # the timeline's times count from the start on the virtual clock (which starts at 0)
    ts = [e["t"] for e in res["timeline"]]
    assert ts == sorted(ts) and ts[-1] == pytest.approx(a["sim_s"], abs=0.1), ts
    halves = [e["t"] for e in res["timeline"] if e["kind"] == "half_end"]
    assert len(halves) == 2 and halves[0] >= 4.0
    # the same match in another process, whose string hashes differ (PYTHONHASHSEED): the
    # same result and the same log, byte for byte (the referee's match id, the order of two
    # violations found in one frame once differed)
    other = tmp_path / "other.log"
    code = ("import json, sys; from evaluate.runner import Entrant, MatchTask, run_match_task; "
            "t = MatchTask('m', Entrant('match'), Entrant('simple'), 3, half_s=4.0, "
            "interludes=False, log_path=sys.argv[1]); "
            "print(json.dumps(run_match_task(t)['result']))")
    root = Path(__file__).resolve().parents[2]
    out = subprocess.run([sys.executable, "-c", code, str(other)], cwd=root, check=True,
                         capture_output=True, text=True, timeout=300,
                         env={**os.environ, "PYTHONPATH": str(root), "PYTHONHASHSEED": "4242"})
    assert json.loads(out.stdout.splitlines()[-1]) == json.loads(json.dumps(a["result"]))
    assert other.read_bytes() == (tmp_path / "m.log").read_bytes()


READY = """
title = "Kick-off when ready"
statement = "NORMAL_START once the robots are in place, as the game controller gives it."
duration_s = 4.5
seed = 3

[ours]
play = "match"

[[robots]]
team = "ours"
id = 0
x = -1.0
y = 0.0

[[robots]]
team = "theirs"
id = 0
x = THEIR_X
y = 1.0

[ball]
x = 0.0
y = 0.0

[[referee]]
at = 0.0
command = "STOP"

[[referee]]
at = 0.2
command = "PREPARE_KICKOFF"
team = "ours"

[[referee]]
at = 4.0
command = "NORMAL_START"
when = "ready"

[[check]]
name = "no_violation"
team = "theirs"
kinds = ["kickoff_position"]
"""


def _normal_start(their_x: float) -> tuple[float, dict[str, Any]]:
    from evaluate.scenario import parse_scenario_text

    sc = parse_scenario_text(READY.replace("THEIR_X", str(their_x)), "ready", "ready.toml")
    res = run_scenario_task(ScenarioTask(sc, 0, Entrant(), None))
    assert res["error"] is None, res["error"]
    starts = [e["t"] for e in res["events"]
              if e["kind"] == "referee" and e["detail"] == "NORMAL_START"]
    assert len(starts) == 1, res["events"]  # given once, early or at its time, never twice
    return starts[0], res


def test_normal_start_when_ready_comes_once_the_robots_are_in_place() -> None:
    """``when = "ready"``: the game controller's way (2 s after every robot is where the
    PREPARE_* wants it, its prepare timeout at the latest), judged by the judge's own rule."""
    from evaluate.runner import READY_HOLD_S

    t, res = _normal_start(1.5)  # their robot in its own half: ready from the start
    assert 0.2 + READY_HOLD_S <= t < 4.0
    assert {c["name"]: c["passed"] for c in res["checks"]} == {"no_violation": True}
    # their robot stands in our half (no play drives it): never ready, NORMAL_START at 4 s,
    # and the judge finds what kept it
    t, res = _normal_start(-1.5)
    assert t == pytest.approx(4.0)
    assert not res["checks"][0]["passed"] and "not in its own half" in res["checks"][0]["detail"]


def test_only_a_normal_start_waits_for_the_robots() -> None:
    from evaluate.scenario import ScenarioError, parse_scenario_text

    text = READY.replace("THEIR_X", "1.5").replace(
        'command = "STOP"', 'command = "STOP"\nwhen = "ready"', 1)
    with pytest.raises(ScenarioError) as err:
        parse_scenario_text(text, "ready", "ready.toml")
    assert err.value.field == "referee[0].when" and "only a NORMAL_START" in str(err.value)
    text = READY.replace("THEIR_X", "1.5").replace('when = "ready"', 'when = "soon"')
    with pytest.raises(ScenarioError) as err:
        parse_scenario_text(text, "ready", "ready.toml")
    assert err.value.field == "referee[2].when" and "not one of at, ready" in str(err.value)


def test_a_report_folder_with_runs_is_refused_before_anything_runs(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """Runs' logs are never overwritten: a second report into the same --out said before that
    every run failed (FileExistsError in each); now it is refused at once, saying why."""
    from evaluate.__main__ import main

    argv = ["suite", str(DATA), "--only", "quick_keeper", "--workers", "1", "--out",
            str(tmp_path / "rep")]
    assert main(argv) == 0
    logs = sorted((tmp_path / "rep" / "runs").iterdir())
    before = [p.stat().st_mtime_ns for p in logs]
    capsys.readouterr()
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert "holds the runs of an earlier report" in err and "--out" in err
    assert [p.stat().st_mtime_ns for p in sorted((tmp_path / "rep" / "runs").iterdir())] == before


def test_a_penalty_ends_ten_seconds_after_its_normal_start() -> None:
    """As the game controller ends it (PENALTY_KICK_FAILED, "Time run out"): a kicker that
    never kicks (their robots have no play here) ends the run then, not at its duration."""
    from evaluate.runner import PENALTY_S
    from evaluate.scenario import parse_scenario_text

    text = (READY.replace("THEIR_X", "2.0").replace("duration_s = 4.5", "duration_s = 13.0")
            .replace('command = "PREPARE_KICKOFF"\nteam = "ours"',
                     'command = "PREPARE_PENALTY"\nteam = "theirs"')
            .replace('at = 4.0\ncommand = "NORMAL_START"\nwhen = "ready"',
                     'at = 1.0\ncommand = "NORMAL_START"')
            .replace('x = 0.0\ny = 0.0\n\n[[referee]]', 'x = -1.5\ny = 0.0\n\n[[referee]]'))
    sc = parse_scenario_text(text, "pen", "pen.toml")
    assert sc.referee[1].command == "PREPARE_PENALTY" and sc.referee[2].at == 1.0
    res = run_scenario_task(ScenarioTask(sc, 0, Entrant(), None))
    assert res["error"] is None, res["error"]
    assert res["ended_by"] == "penalty_time"
    assert res["sim_s"] == pytest.approx(1.0 + PENALTY_S, abs=0.02)
