"""The launcher's station for a benchmark: started in its own ports (``--isolated``), with the
process ids, ports, state folder and URL the launcher prints (TOUCHLINE_PIDS, TOUCHLINE_PORTS,
TOUCHLINE_STATE_DIR, TOUCHLINE_READY; the words as ``launcher/started.py`` names them).

Every bench that starts the launcher reads those lines here, with launcher/started.py's reader:
a thread reads the launcher's output to its end (each line kept and, if asked, written to a
log), so the pipe never fills while a long run goes on."""

from __future__ import annotations

import json
import os
import subprocess
import sys
import threading
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import IO

from launcher.started import PIDS, PORTS, READY, AnnouncedLines, Started

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
class Station(Started):
    """launcher/started.py's ``Started``, with the thread reading the output."""

    #: the thread reading the launcher's output (joined by ``stop``: a log then holds every
    #: line)
    reader: threading.Thread | None = None

    def text(self) -> str:
        return "\n".join(self.lines)

    def stop(self, timeout_s: float = 20.0) -> int | None:
        code = super().stop(timeout_s)
        if self.reader is not None:  # bounded: a child left behind may hold the pipe open
            self.reader.join(5.0)
        return code


def start_station(launcher_args: list[str], stderr: int | IO[str] = subprocess.DEVNULL,
                  timeout_s: float = 90.0, env: Mapping[str, str] | None = None,
                  log: IO[str] | None = None) -> Station:
    """Starts ``python -m launcher --isolated *launcher_args`` and waits until it is ready
    (RuntimeError with the last lines, the launcher killed, if it ends or takes longer than
    ``timeout_s``). ``stderr``: where the launcher's standard error goes
    (``subprocess.STDOUT``: with its output, into ``lines`` and ``log``); ``env``: added to
    this process's environment; ``log``: a file each output line is written to as it comes."""
    proc = subprocess.Popen([sys.executable, "-m", "launcher", "--isolated", *launcher_args],
                            cwd=ROOT, stdout=subprocess.PIPE, stderr=stderr, text=True,
                            env=None if env is None else {**os.environ, **env})
    read = AnnouncedLines(proc, log)
    read.wait_ready(timeout_s)
    info = read.info
    return Station(proc, info[READY], json.loads(info[PORTS]), json.loads(info.get(PIDS, "{}")),
                   read.state_dir, read.lines, read.thread)
