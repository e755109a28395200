"""docs/team-api.md is what scripts/gen_team_api.py makes of the touchline package today
(regenerate: make contract), and it documents every field a team's code sees."""

from __future__ import annotations

import dataclasses
import subprocess
import sys
from pathlib import Path

import touchline
from touchline import octave

ROOT = Path(__file__).resolve().parents[3]


def test_the_team_api_page_is_up_to_date() -> None:
    r = subprocess.run([sys.executable, "scripts/gen_team_api.py", "--check"], cwd=ROOT,
                       capture_output=True, text=True, timeout=120)
    assert r.returncode == 0, r.stdout + r.stderr


def test_every_field_and_column_is_documented() -> None:
    doc = (ROOT / "docs" / "team-api.md").read_text()
    assert f"API version {touchline.API_VERSION}" in doc
    for cls in (touchline.Game, touchline.Robot, touchline.Ball, touchline.Kick,
                touchline.Referee, touchline.FieldSize, touchline.Target, touchline.Velocity):
        assert f"### `{cls.__name__}`" in doc
        for f in dataclasses.fields(cls):
            row = next((ln for ln in doc.splitlines() if ln.startswith(f"| `{f.name}` |")),
                       None)
            assert row is not None, (cls.__name__, f.name)
            assert not row.rstrip().endswith("|  |"), f"{cls.__name__}.{f.name} says nothing"
    for cols in (octave.OURS_COLUMNS, octave.ORDER_COLUMNS):
        for c in cols:
            assert f":`{c}`" in doc
