"""A second station on a taken web port: the launcher says so and exits at once, before it
starts anything (its backend failed to bind and was restarted again and again, and the page
that answered was the other station's)."""

from __future__ import annotations

import socket
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]


def test_a_taken_web_port_is_said_and_nothing_is_started() -> None:
    with socket.socket() as taken:
        taken.bind(("127.0.0.1", 0))
        taken.listen()
        port = taken.getsockname()[1]
        out = subprocess.run(
            [sys.executable, "-m", "launcher", "--isolated", "--port", str(port),
             "--no-standby"], cwd=ROOT, capture_output=True, text=True, timeout=120)
    assert out.returncode == 2, out.stderr[-2000:]
    said = out.stdout + out.stderr
    assert f"the web port 127.0.0.1:{port} is taken" in said and "--port" in said, said[-2000:]
    # nothing was started: no child's line, no ready line
    assert "fieldsim" not in said and "larcmacs_relay" not in said and "TOUCHLINE_READY" not in said
