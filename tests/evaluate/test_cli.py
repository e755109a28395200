"""``python -m evaluate`` as a teacher types it: a real process, its exit code and its words."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
pytestmark = pytest.mark.timeout(120)


def evaluate(*args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, "-m", "evaluate", *args], cwd=ROOT,
                          capture_output=True, text=True, timeout=100)


def test_only_with_a_name_the_suite_lacks_is_refused_with_its_names(tmp_path: Path) -> None:
    """``--only drive_to_point`` (the exercise, not a scenario: they are drive_to_point_1 ..)
    ran nothing and said "0/0 runs passed, mean score None" with exit code 0."""
    out = tmp_path / "rep"
    p = evaluate("suite", "exercises", "--only", "drive_to_point", "--out", str(out))
    assert p.returncode == 2, (p.returncode, p.stdout, p.stderr)
    assert "--only 'drive_to_point': no such scenario in the suite exercises" in p.stderr
    assert "drive_to_point_1" in p.stderr and "stop_rules_5" in p.stderr
    assert not out.exists()  # nothing ran, no empty report


def test_a_suite_without_a_play_names_it_in_the_report(tmp_path: Path) -> None:
    """Without ``--play`` each scenario runs its own play: the report said "quick: ?"."""
    out = tmp_path / "rep"
    p = evaluate("suite", str(ROOT / "tests" / "evaluate" / "quick"), "--only", "quick_goal",
                 "--workers", "1", "--no-logs", "--out", str(out))
    assert p.returncode == 0, (p.stdout, p.stderr)
    rep = json.loads((out / "report.json").read_text())
    assert rep["title"] == "quick: each scenario's play", rep["title"]
    assert rep["entrant"] == "each scenario's play"
    assert [r["play"] for r in rep["runs"]] == ["idle"]  # the scenario's own


def test_a_team_folder_with_a_tilde_is_the_home_folders(tmp_path: Path) -> None:
    """``make evaluate TEAM=~/ann`` from zsh passes the ``~`` as it is: every run failed with
    "no team folder ~/ann"."""
    (tmp_path / "ann").mkdir()
    (tmp_path / "ann" / "drive_to_point.py").write_text(
        "from touchline import Target\n"
        "def play(game):\n"
        "    x, y = game.task['target_mm']\n"
        "    return {game.task['robot']: Target(x, y)}\n")
    p = subprocess.run([sys.executable, "-m", "evaluate", "suite", "exercises", "--only",
                        "drive_to_point_1", "--team-dir", "~/ann", "--workers", "1",
                        "--no-logs", "--out", str(tmp_path / "rep")], cwd=ROOT, capture_output=True,
                       text=True, timeout=100, env={**os.environ, "HOME": str(tmp_path)})
    assert p.returncode == 0, (p.stdout, p.stderr)
    rep = json.loads((tmp_path / "rep" / "report.json").read_text())
    assert [(r["passed"], r["error"]) for r in rep["runs"]] == [(True, None)], rep["runs"]


def test_a_failed_run_says_why_on_its_progress_line(tmp_path: Path) -> None:
    """A teacher reads the progress lines: a run that failed said only "FAIL drive_to_point_1
    0.6 s" (the play's error came once, on a log line of its own, and a failed check not at
    all)."""
    for who, body in (("crash", "    x, y = game.task['target']\n"),
                      ("slow", "    x, y = game.task['target_mm']\n"
                               "    return {0: Target(x, y, max_speed_mps=0.2)}\n")):
        (tmp_path / who).mkdir()
        (tmp_path / who / "drive_to_point.py").write_text(
            f"from touchline import Target\ndef play(game):\n{body}")
    lines = {}
    for who in ("crash", "slow"):
        p = evaluate("suite", "exercises", "--only", "drive_to_point_1", "--team-dir",
                     str(tmp_path / who), "--workers", "1", "--no-logs", "--out",
                     str(tmp_path / f"rep-{who}"))
        assert p.returncode == 0, (p.stdout, p.stderr)
        lines[who] = [ln for ln in p.stdout.splitlines() if "FAIL drive_to_point_1" in ln]
    assert len(lines["crash"]) == 1 and lines["crash"][0].endswith(
        "(exception at drive_to_point.py:3: KeyError: 'target')"), lines
    assert len(lines["slow"]) == 1 and lines["slow"][0].endswith(
        "(failed: there within 6 s)"), lines
