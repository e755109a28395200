"""``make run TEAM=~/my-team`` as docs/team-code.md writes it: zsh (macOS's shell) passes the
``~`` on as it is, and the launcher refused "no such team folder: ~/my-team"."""

from __future__ import annotations

import os
import socket
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]


def launch(home: Path, *args: str) -> subprocess.CompletedProcess[str]:
    """The launcher with HOME=home on a taken web port: it checks its flags, then stops
    there before it starts anything (tests/launcher/test_port_taken.py)."""
    with socket.socket() as taken:
        taken.bind(("127.0.0.1", 0))
        taken.listen()
        port = taken.getsockname()[1]
        return subprocess.run(
            [sys.executable, "-m", "launcher", "--isolated", "--port", str(port),
             "--no-standby", *args], cwd=ROOT, capture_output=True, text=True, timeout=120,
            env={**os.environ, "HOME": str(home)})


def test_a_team_folder_under_the_home_folder_is_found_with_a_tilde(tmp_path: Path) -> None:
    (tmp_path / "my-team").mkdir()
    out = launch(tmp_path, "--team-dir", "~/my-team")
    said = out.stdout + out.stderr
    assert "no such team folder" not in said, said[-2000:]
    assert out.returncode == 2 and "is taken" in said, said[-2000:]  # past the flags' checks
    missing = launch(tmp_path, "--team-dir", "~/other", "--log", "~/x.log")
    said = missing.stdout + missing.stderr
    assert f"no such log file: {tmp_path}/x.log" in said, said[-2000:]  # the path it looked at
