"""The launcher's station for a benchmark: started in its own ports (``--isolated``), with the
process ids, ports, state folder and URL the launcher prints (TOUCHLINE_PIDS, TOUCHLINE_PORTS,
TOUCHLINE_STATE_DIR, TOUCHLINE_READY; the words as ``launcher/started.py`` names them).

Every bench that starts the launcher reads those lines here: a thread reads the launcher's
output to its end (each line kept and, if asked, written to a log), so the pipe never fills
while a long run goes on."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import threading
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import IO, Any

from launcher.started import PIDS, PORTS, READY, STATE_DIR

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
    #: the launcher's own temporary state folder (None when it did not print one)
    state_dir: Path | None = None
    #: every line read from the launcher's output so far, appended to as they come
    lines: list[str] = field(default_factory=list)
    #: the thread reading that output (joined by ``stop``, so a log holds every line)
    reader: threading.Thread | None = None

    def text(self) -> str:
        return "".join(self.lines)

    def stop(self, timeout_s: float = 20.0) -> int | None:
        """SIGTERM (the launcher stops its children in order), then SIGKILL if it has not
        ended within ``timeout_s``: its exit status, None if it had to be killed."""
        self.proc.send_signal(signal.SIGTERM)
        try:
            code: int | None = self.proc.wait(timeout=timeout_s)
        except subprocess.TimeoutExpired:
            self.proc.kill()
            self.proc.wait()
            code = None
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
    lines: list[str] = []
    info: dict[str, str] = {}
    over = threading.Event()  # ready, or the output ended

    def pump() -> None:
        assert proc.stdout is not None
        for line in proc.stdout:
            lines.append(line)
            if log is not None:
                log.write(line)
                log.flush()
            word, _, rest = line.partition(" ")
            if word in (PORTS, STATE_DIR, PIDS, READY):
                info[word] = rest.strip()
                if word == READY:
                    over.set()
        over.set()

    reader = threading.Thread(target=pump, daemon=True)
    reader.start()
    if not over.wait(timeout_s) or READY not in info:
        proc.kill()
        proc.wait()
        raise RuntimeError("station did not start:\n" + "".join(lines[-40:]))
    own = info.get(STATE_DIR)
    return Station(proc, info[READY], json.loads(info.get(PIDS, "{}")),
                   json.loads(info.get(PORTS, "{}")), Path(own) if own else None, lines, reader)
