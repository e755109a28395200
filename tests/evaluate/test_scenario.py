"""Scenario files: what loads, and a clear error naming the field for what does not."""

from __future__ import annotations

import math
from pathlib import Path

import pytest

from evaluate.scenario import (
    ScenarioError,
    load_scenario,
    load_suite,
    parse_scenario_text,
    shipped_suites,
)

GOOD = """
title = "Keeper"
statement = "Save the shot."
duration_s = 4.0
seed = 7
runs = 3
tags = ["keeper"]
end_on = ["goal"]

[field]
division = "B"
cameras = 2

[sim]
noise_mm = 3.0
vision_latency_ms = 4

[ours]
team = "yellow"
side = "positive-x"
play = "defend"
params = { "strategy.kick_speed_mps" = 4.0 }

[[robots]]
team = "ours"
id = 0
x = -4.3
y = 0.0
heading_deg = 90

[ball]
x = -1.0
y = 0.5
vx = -4.0
vy = 0.0

[[referee]]
at = 0.0
command = "FORCE_START"

[[referee]]
at = 2.0
command = "BALL_PLACEMENT"
team = "theirs"
designated = [1.0, 1.0]

[[actions]]
at = 1.0
ball = { x = 0.0, y = 0.0, vx = -3.0, vy = 0.0 }

[[check]]
name = "keeper_saved"

[[check]]
name = "reach"
robot = 0
target = [-4.3, 0.2]
tolerance_m = 0.2
weight = 2

[vary]
"ball.vy" = [-0.5, 0.5]
"""


def test_a_good_file_loads_with_every_field() -> None:
    sc = parse_scenario_text(GOOD, "keeper", "keeper.toml")
    assert sc.title == "Keeper" and sc.duration_s == 4.0 and sc.seed == 7 and sc.runs == 3
    assert sc.cameras == 2 and sc.sim == {"noise_mm": 3.0} and sc.vision_latency_ms == 4.0
    assert sc.our_team == "yellow" and sc.our_side == "positive-x" and sc.play == "defend"
    assert sc.params == {"strategy.kick_speed_mps": 4.0}
    assert sc.robots[0].heading == pytest.approx(math.pi / 2)
    assert sc.ball is not None and sc.ball.vx == -4.0
    assert [s.command for s in sc.referee] == ["FORCE_START", "BALL_PLACEMENT"]
    assert sc.referee[1].team == "theirs" and sc.referee[1].designated == (1.0, 1.0)
    assert sc.actions[0].ball is not None and sc.actions[0].ball.vx == -3.0
    assert [c.name for c in sc.checks] == ["keeper_saved", "reach"]
    assert sc.checks[1].params == {"robot": 0, "target": (-4.3, 0.2), "tolerance_m": 0.2}
    assert sc.checks[1].weight == 2.0
    assert sc.end_on == ("goal",)


def test_runs_draw_their_own_values_and_seeds() -> None:
    sc = parse_scenario_text(GOOD, "keeper", "keeper.toml")
    runs = [sc.for_run(i) for i in range(3)]
    assert [r.seed for r in runs] == [7, 8, 9]
    vys = [r.ball.vy for r in runs if r.ball is not None]
    assert len(set(vys)) == 3 and all(-0.5 <= v <= 0.5 for v in vys)
    assert sc.for_run(1).ball == sc.for_run(1).ball  # the same run draws the same


@pytest.mark.parametrize(("line", "replacement", "field", "says"), [
    ("duration_s = 4.0", "", "duration_s", "missing"),
    ("duration_s = 4.0", 'duration_s = "long"', "duration_s", "expected a number"),
    ("duration_s = 4.0", "duration_s = 4.0\nspeed = 3", "speed", "unknown field"),
    ("x = -4.3", "", "robots[0].x", "missing"),
    ("heading_deg = 90", 'heading_deg = "north"', "robots[0].heading_deg",
     "expected a number"),
    ("cameras = 2", "cameras = 3", "field.cameras", "1, 2, 4 or 8"),
    ("noise_mm = 3.0", "noise_mm = 300.0", "sim.noise_mm", "out of range"),
    ("designated = [1.0, 1.0]", "", "referee[1].designated", "BALL_PLACEMENT needs"),
    ('name = "keeper_saved"', 'name = "keeper_saves"', "check[0].name", "unknown check"),
    ("tolerance_m = 0.2", 'tolerance_m = "close"', "check[1].tolerance_m",
     "expected a number"),
    ("robot = 0", "", "check[1].robot", "missing"),
    ('"ball.vy" = [-0.5, 0.5]', '"ball.vz" = [-0.5, 0.5]', "vary.ball.vz", "no such field"),
    ('play = "defend"', 'play = "../x"', "ours.play", "expected a play name"),
    ('team = "yellow"', 'team = "red"', "ours.team", "not one of blue, yellow"),
])
def test_a_bad_field_is_named(line: str, replacement: str, field: str, says: str) -> None:
    assert line in GOOD
    text = GOOD.replace(line, replacement, 1)
    with pytest.raises(ScenarioError) as err:
        parse_scenario_text(text, "keeper", "keeper.toml")
    assert err.value.field == field, str(err.value)
    assert says in str(err.value) and str(err.value).startswith("keeper.toml: ")


def test_not_toml_and_no_check_and_no_robot(tmp_path: Path) -> None:
    f = tmp_path / "broken.toml"
    f.write_text("title = \n")
    with pytest.raises(ScenarioError, match=r"broken.toml: not valid TOML"):
        load_scenario(f)
    with pytest.raises(ScenarioError, match="check: no check"):
        parse_scenario_text(GOOD.split("[[check]]")[0].replace('"ball.vy"', "#"),
                            "k", "k.toml")
    no_robot = GOOD.replace('team = "ours"\nid = 0', 'team = "theirs"\nid = 0', 1)
    with pytest.raises(ScenarioError, match="robots: no robot of ours"):
        parse_scenario_text(no_robot, "k", "k.toml")
    f.write_bytes(b"title = \"\xff\"\n")
    with pytest.raises(ScenarioError, match="not UTF-8"):
        load_scenario(f)


def test_normal_start_needs_a_prepare() -> None:
    text = GOOD.replace('command = "FORCE_START"', 'command = "NORMAL_START"', 1)
    with pytest.raises(ScenarioError) as err:
        parse_scenario_text(text, "k", "k.toml")
    assert err.value.field == "referee[0].command"


def test_a_suite_with_its_own_check(tmp_path: Path) -> None:
    (tmp_path / "checks.py").write_text(
        "from evaluate.checks import Result\n"
        "def near_centre(run, robot: int, limit_m: float = 1.0):\n"
        "    return Result(True, 1.0, 'ok')\n")
    own = GOOD.replace('name = "keeper_saved"', 'name = "near_centre"\nrobot = 0')
    (tmp_path / "a.toml").write_text(own)
    (tmp_path / "b.toml").write_text(GOOD)
    suite = load_suite(str(tmp_path))
    assert [s.name for s in suite.scenarios] == ["a", "b"]
    assert suite.scenarios[0].checks[0].params == {"robot": 0}
    assert suite.checks_file == str(tmp_path / "checks.py")
    (tmp_path / "c.toml").write_text(own.replace("robot = 0", "robot = 0\nlimit = 3"))
    with pytest.raises(ScenarioError) as err:
        load_suite(str(tmp_path))
    assert err.value.field == "check[0].limit" and "c.toml" in str(err.value)


def test_the_shipped_suites_load() -> None:
    assert {"exercises", "regression"} <= set(shipped_suites())
    for name in ("exercises", "regression"):
        suite = load_suite(name)
        assert suite.scenarios, name


def _known_fields(text: str, field: str) -> list[str]:
    """The fields a table reads, as the parser says them for an unknown one."""
    with pytest.raises(ScenarioError) as err:
        parse_scenario_text(text, "keeper", "keeper.toml")
    assert err.value.field.endswith(field), str(err.value)
    return str(err.value).split("known here: ")[1].rstrip(")").split(", ")


def test_the_documentation_names_every_field_and_check() -> None:
    """docs/evaluate.md is where a scenario's author looks: every field the parser reads,
    every built-in check and every referee command a scenario may give are in it."""
    from evaluate.checks import BUILTIN
    from evaluate.scenario import LATENCY_FIELDS, PLAIN_COMMANDS, SIM_FIELDS, TEAM_COMMANDS

    doc = (Path(__file__).resolve().parents[2] / "docs" / "evaluate.md").read_text()
    top = _known_fields("zzz = 1\n" + GOOD, "zzz")
    ours = _known_fields(GOOD.replace('[ours]\n', '[ours]\nzzz = 1\n'), "ours.zzz")
    opponent = _known_fields(GOOD + '\n[opponent]\nzzz = 1\n', "opponent.zzz")
    fields = _known_fields(GOOD.replace('[field]\n', '[field]\nzzz = 1\n'), "field.zzz")
    assert len(top) >= 15 and "vary" in top and "operator_targets" in ours
    wanted = [*top, *ours, *opponent, *fields, *SIM_FIELDS, *LATENCY_FIELDS, *BUILTIN,
              *PLAIN_COMMANDS, *TEAM_COMMANDS]
    missing = [w for w in wanted if w not in doc]
    assert not missing, f"docs/evaluate.md does not mention {missing}"
    # and its example file is one the parser takes
    import re

    example = re.search(r"```toml\n(.*?)```", doc, re.S)
    assert example is not None
    sc = parse_scenario_text(example.group(1), "example", "docs/evaluate.md")
    assert sc.runs == 20 and [c.name for c in sc.checks] == ["keeper_saved"]


def test_a_shot_aimed_at_a_spot() -> None:
    """``aim`` and ``speed`` instead of vx, vy: the velocity towards the spot, and a ``vary`` of
    the spot keeps every run's shot on it (independent vx and vy ranges sent 12 of the
    goalkeeper exercise's 20 shots wide: a keeper doing nothing scored 0.75)."""
    text = GOOD.replace("vx = -4.0\nvy = 0.0", "aim = [-4.5, 0.2]\nspeed = 5.0", 1).replace(
        '"ball.vy" = [-0.5, 0.5]', '"ball.aim[1]" = [-0.4, 0.4]', 1)
    sc = parse_scenario_text(text, "keeper", "keeper.toml")
    assert sc.ball is not None
    assert math.hypot(sc.ball.vx, sc.ball.vy) == pytest.approx(5.0)
    assert sc.ball.vy / sc.ball.vx == pytest.approx((0.2 - 0.5) / (-4.5 + 1.0))
    for i in range(3):  # each run: a line from the ball through a spot inside the posts
        b = sc.for_run(i).ball
        assert b is not None
        y_at_goal = b.y + (-4.5 - b.x) * b.vy / b.vx
        assert -0.4 <= y_at_goal <= 0.4 and math.hypot(b.vx, b.vy) == pytest.approx(5.0)


@pytest.mark.parametrize(("change", "says"), [
    ("aim = [-4.5, 0.2]\nspeed = 5.0\nvx = -4.0\nvy = 0.0", "not both"),
    ("aim = [-4.5, 0.2]", "missing"),
    ("aim = [-1.0, 0.5]\nspeed = 5.0", "no direction"),
])
def test_a_bad_aim_is_named(change: str, says: str) -> None:
    text = GOOD.replace("vx = -4.0\nvy = 0.0", change, 1)
    with pytest.raises(ScenarioError) as err:
        parse_scenario_text(text, "keeper", "keeper.toml")
    assert err.value.field.startswith("ball.") and says in str(err.value), str(err.value)
