"""The result table and files, and the runner's command lines (no processes started)."""

from __future__ import annotations

import csv
import json
import re
from pathlib import Path

from launcher.supervisor import Ports
from match.config import MatchConfig
from match.report import format_result, table, write_outputs
from match.runner import Options, build
from match.stats import VIOLATION_KINDS

from .fake import Harness


def _spans(dash_line: str) -> list[tuple[int, int]]:
    return [(m.start(), m.end()) for m in re.finditer(r"-+", dash_line)]


def test_table_aligns_columns() -> None:
    text = table(["team", "goals", "possession"], [["blue", "12", "54.1 %"],
                                                   ["yellow", "3", "45.9 %"]])
    head, dashes, *rows = text.splitlines()
    spans = _spans(dashes)
    assert [head[a:b].strip() for a, b in spans] == ["team", "goals", "possession"]
    for row in rows:
        cells = [row[a:b] for a, b in spans]
        assert cells[0].rstrip() == cells[0].strip()  # left-aligned
        assert all(c.lstrip() == c.strip() for c in cells[1:])  # right-aligned


def _played() -> Harness:
    h = Harness(MatchConfig(half_s=6.0, interludes=False))
    h.to_running()
    h.robot("blue", 5, 100.0, 0.0)
    h.run(2.0)
    h.w.ball = [4600.0, 0.0, 0.0, 0.0]
    h.w.emit("goal", side="positive", x=4521.5, y=0.0, last_touch={"team": "blue", "id": 5})
    h.until(lambda: h.d.finished, 120, "end")
    return h


def test_result_table_has_a_row_per_team_and_every_violation_kind() -> None:
    h = _played()
    res = h.d.result()
    res["options"] = {"minutes": 0.2, "seed": 3, "division": "B"}
    text = format_result(res)
    assert "blue (match) 1 : 0 yellow (simple)" in text and "finished" in text
    lines = text.splitlines()
    blue = next(line for line in lines if line.startswith("blue "))
    assert re.search(r"blue\s+match\s+1\s+100\.0 %\s+n/a\s+0 / 0\s+-", blue), blue
    start = next(i for i, line in enumerate(lines) if line.startswith("violations"))
    assert lines[start].split()[-4:] == ["blue", "(match)", "yellow", "(simple)"]
    kinds = lines[start + 2: start + 2 + len(VIOLATION_KINDS)]
    assert [k.split(":")[0].split()[0] for k in kinds[:3]] == ["HALT", "STOP", "STOP"]
    assert all(re.search(r"\d+( \(\d+\.\d s\))?\s+\d+( \(\d+\.\d s\))?$", k) for k in kinds)
    assert any(line.startswith("PREPARE_KICKOFF_YELLOW") for line in lines)
    assert "division B, 0.2 min" in text


def test_outputs_are_result_json_and_an_events_csv(tmp_path: Path) -> None:
    h = _played()
    res = h.d.result()
    write_outputs(tmp_path, res, h.d.timeline)
    back = json.loads((tmp_path / "result.json").read_text())
    assert back["score"] == {"blue": 1, "yellow": 0}
    assert set(back["teams"]["blue"]["violations"]) == set(VIOLATION_KINDS)
    with (tmp_path / "events.csv").open() as f:
        rows = list(csv.DictReader(f))
    assert rows[0]["kind"] == "match"
    assert next(r["detail"] for r in rows if r["kind"] == "goal").startswith("into the positive")
    assert (tmp_path / "result.txt").read_text().startswith("Touchline match")


def test_runner_builds_fieldsim_one_relay_and_two_backends_on_isolated_ports() -> None:
    ports = Ports.isolated(None)
    http = {"blue": 50001, "yellow": 50002}
    dirs = {"blue": "/tmp/b", "yellow": "/tmp/y"}
    kids = build(Options(engine="octave", division="A", seed=7), ports, "tcp://127.0.0.1:5999",
                 http, dirs)
    names = [c.name for c in kids]
    assert names == ["fieldsim", "relay", "backend-blue", "backend-yellow"]
    fs, relay, blue, yellow = (c.argv for c in kids)
    assert fs[1:3] == ["-m", "fieldsim"]
    for flag, value in (("--truth-pub", "tcp://127.0.0.1:5999"), ("--blue", "6"),
                        ("--yellow", "6"), ("--division", "A"), ("--seed", "7"),
                        ("--vision-port", str(ports.vision)),
                        ("--control-port", str(ports.sim_control))):
        assert fs[fs.index(flag) + 1] == value
    assert relay[relay.index("--referee") + 1] == f"{ports.referee_group}:{ports.referee}"
    for argv, team, port, play in ((blue, "blue", 50001, "match"),
                                   (yellow, "yellow", 50002, "simple")):
        assert argv[argv.index("--our-team") + 1] == team
        assert argv[argv.index("--port") + 1] == str(port)
        assert argv[argv.index("--play") + 1] == play
        assert argv[argv.index("--relay-pub") + 1] == ports.relay_pub
        assert argv[argv.index("--state-dir") + 1] == dirs[team]
    def sets(argv: list[str]) -> list[str]:
        return [argv[i + 1] for i, a in enumerate(argv) if a == "--set"]
    speed = [f"control.params.{c}.v_mps=2.0" for c in ("algorithm1", "algorithm2",
                                                        "proportional")]
    assert sets(blue) == ["strategy.engine=octave", *speed]
    assert sets(yellow) == ["tracker.publish=false", *speed]  # one tracker source: blue's
    # --robot-speed station: the backends keep their own speed limits
    kids = build(Options(robot_speed_mps=None), ports, "tcp://127.0.0.1:5999", http, dirs)
    assert [sets(c.argv) for c in kids[2:]] == [[], ["tracker.publish=false"]]
