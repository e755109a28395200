"""Class mode: every student's folder through a suite on the pool; a student's play that
crashes or never returns fails that student's run only (its worker process, the station's
team-code host, stops it), and the grade table says why."""

from __future__ import annotations

import re
from dataclasses import replace
from pathlib import Path

import pytest

from evaluate.jobs import run_class
from evaluate.pool import LocalPool
from evaluate.runner import Entrant, ScenarioTask, run_scenario_task
from evaluate.scenario import load_suite

HERE = Path(__file__).parent
pytestmark = pytest.mark.timeout(180)


def test_a_crash_and_a_spin_fail_only_their_own_runs(tmp_path: Path) -> None:
    suite = load_suite(str(HERE / "class_suite"))
    rep = run_class(HERE / "class", suite, tmp_path / "r", LocalPool(2))
    grades = {g["student"]: g for g in rep["grades"]}
    assert list(grades) == ["crash", "good", "spin"]
    good, crash, spin = grades["good"], grades["crash"], grades["spin"]
    assert good["cells"]["drive"]["passed"] and good["score"] == 1.0
    assert not crash["cells"]["drive"]["passed"] and not spin["cells"]["drive"]["passed"]
    assert crash["cells"]["drive"]["note"].startswith(
        "exception at drive_to_point.py:7: ZeroDivisionError")
    # stopped in its loop (line 8 or 9: wherever the CPU limit caught it)
    assert re.match(r"budget at drive_to_point.py:[89]: spinning: over its CPU limit in one "
                    r"call \(0.25 s of CPU time", spin["cells"]["drive"]["note"])
    runs = {r["student"]: r for r in rep["runs"]}
    for who in grades:  # every run went its whole length and kept its log
        assert runs[who]["error"] is None and runs[who]["sim_s"] == 3.0
        assert Path(runs[who]["log"]).is_file()
        assert Path(runs[who]["log"]).parent.name == who
    assert (tmp_path / "r" / "report.html").read_text().count("<tr>") >= 4


def test_a_team_play_run_is_repeatable_and_gets_its_task() -> None:
    suite = load_suite(str(HERE / "class_suite"))
    task = ScenarioTask(suite.scenarios[0], 0, Entrant(None, {}, str(HERE / "class" / "good")),
                        None, suite.checks_file)
    a, b = run_scenario_task(task), run_scenario_task(task)
    assert a["passed"], a
    # the suite's own check (its checks.py) ran in the worker beside the built-in one
    assert [c["name"] for c in a["checks"]] == ["reach", "stopped"]
    strip = ("wall_s",)
    assert {k: v for k, v in a.items() if k not in strip} == \
        {k: v for k, v in b.items() if k not in strip}


def test_a_missing_play_is_a_failed_run_that_says_so(tmp_path: Path) -> None:
    suite = load_suite(str(HERE / "class_suite"))
    (tmp_path / "other.py").write_text("def play(game):\n    return {}\n")
    res = run_scenario_task(ScenarioTask(suite.scenarios[0], 0,
                                         Entrant(None, {}, str(tmp_path)), None))
    assert not res["passed"]
    assert res["error"].startswith("missing: no play 'drive_to_point'") and "other" in res["error"]


def test_a_play_that_fails_fails_its_run_whatever_its_checks_say(tmp_path: Path) -> None:
    """Robot 0 starts on its target: a play that raises on its first tick leaves it there, and
    both checks (reach, stopped) pass. Such a run passed with score 1.0 before; in the
    exercises a crashing keeper scored 0.75 (standing at the goal centre, it "saved" the
    shots that missed). The docs say a crash fails the student's run."""
    suite = load_suite(str(HERE / "class_suite"))
    sc = suite.scenarios[0]
    sc = replace(sc, robots=tuple(replace(r, x=0.0, y=0.0) for r in sc.robots))  # on target
    (tmp_path / "drive_to_point.py").write_text(
        "def play(game):\n    return {0: game.nothing}\n")
    res = run_scenario_task(ScenarioTask(sc, 0, Entrant(None, {}, str(tmp_path)), None,
                                         suite.checks_file))
    assert [c["passed"] for c in res["checks"]] == [True, True]  # what the robot "did"
    assert res["team_error"].startswith("exception at drive_to_point.py:2: AttributeError")
    assert (res["passed"], res["score"]) == (False, 0.0)
