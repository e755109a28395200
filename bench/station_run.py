"""The launcher's station for a benchmark: started in its own ports (``--isolated``), with the
process ids, ports and URL the launcher prints (TOUCHLINE_PIDS, TOUCHLINE_PORTS,
TOUCHLINE_READY)."""

from __future__ import annotations

import json
import subprocess
import sys
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import IO, Any

ROOT = Path(__file__).resolve().parent.parent


def full_scale_args(cameras: int = 8, hz: float = 75.0,
                    relay_args: list[str] | None = None, robots: int = 11,
                    camera_phases: str = "spread") -> list[str]:
    """The launcher's arguments for issue 11's load: the built-in simulator at ``cameras`` x
    ``hz``, division A, 11 v 11 (``robots`` a team), the "match" play; ``camera_phases``:
    fieldsim's (spread: each camera its own phase; together: all at once, in one burst)."""
    sim = ["--division", "A", "--blue", str(robots), "--yellow", str(robots), "--cameras",
           str(cameras), "--camera-hz", str(hz), "--camera-phases", camera_phases]
    return [*(f"--sim-arg={x}" for x in sim), "--backend-arg=--set",
            "--backend-arg=strategy.play=match", *(f"--relay-arg={x}" for x in relay_args or [])]


@dataclass
class Station:
    proc: subprocess.Popen[str]
    url: str
    pids: dict[str, int] = field(default_factory=dict)
    ports: dict[str, Any] = field(default_factory=dict)


def start_station(launcher_args: list[str], stderr: int | IO[str] = subprocess.DEVNULL,
                  timeout_s: float = 90.0) -> Station:
    """Starts ``python -m launcher --isolated *launcher_args`` and waits until it is ready
    (RuntimeError, the launcher killed, if it ends or takes longer than ``timeout_s``)."""
    proc = subprocess.Popen([sys.executable, "-m", "launcher", "--isolated", *launcher_args],
                            cwd=ROOT, stdout=subprocess.PIPE, stderr=stderr, text=True)
    assert proc.stdout is not None
    pids: dict[str, int] = {}
    ports: dict[str, Any] = {}
    deadline = time.monotonic() + timeout_s
    for line in proc.stdout:
        if line.startswith("TOUCHLINE_PIDS "):
            pids = json.loads(line.split(" ", 1)[1])
        elif line.startswith("TOUCHLINE_PORTS "):
            ports = json.loads(line.split(" ", 1)[1])
        elif line.startswith("TOUCHLINE_READY "):
            return Station(proc, line.split()[1], pids, ports)
        if time.monotonic() > deadline:
            break
    proc.kill()
    proc.wait()
    raise RuntimeError("station did not start")
