"""The whole station started from a program (the integration tests, the fuzzer, benchmarks):
``python -m launcher --isolated`` on free ports, its announced lines read back.

The launcher writes machine-readable lines on standard output once the backend answers
(``announce`` in ``__main__.py``): ``TOUCHLINE_PORTS {json}``, ``TOUCHLINE_STATE_DIR path``
(with its own temporary state folder), ``TOUCHLINE_PIDS {json}`` and last
``TOUCHLINE_READY url``. ``start_isolated`` reads them on a thread that keeps reading to the
end (every line kept, so the pipe never fills and a failure can show the log)."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import threading
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from .supervisor import ROOT

PORTS, STATE_DIR, PIDS, READY = ("TOUCHLINE_PORTS", "TOUCHLINE_STATE_DIR", "TOUCHLINE_PIDS",
                                 "TOUCHLINE_READY")


@dataclass
class Started:
    proc: subprocess.Popen[str]
    url: str
    ports: dict[str, Any]
    #: the children's process ids by name ("backend", "relay", "fieldsim")
    pids: dict[str, int]
    #: the launcher's own temporary state folder (None when the caller named one)
    state_dir: Path | None
    #: every line the launcher and its children printed, appended to as they come
    lines: list[str]

    def stop(self, timeout_s: float = 15.0) -> int | None:
        """SIGTERM (the launcher stops its children in order), then SIGKILL if it has not
        ended within ``timeout_s``: its exit status, None if it had to be killed."""
        self.proc.send_signal(signal.SIGTERM)
        try:
            return self.proc.wait(timeout=timeout_s)
        except subprocess.TimeoutExpired:
            self.proc.kill()
            self.proc.wait()
            return None


def start_isolated(args: Sequence[str] = (), timeout_s: float = 90.0) -> Started:
    """Starts ``python -m launcher --isolated *args`` (its standard error with its output)
    and returns once it announced its URL. RuntimeError with the last 40 lines, the launcher
    killed, if it ended first or did not within ``timeout_s``."""
    proc = subprocess.Popen(
        [sys.executable, "-m", "launcher", "--isolated", *args], cwd=ROOT,
        stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
        env={**os.environ, "PYTHONUNBUFFERED": "1"})
    lines: list[str] = []
    info: dict[str, str] = {}
    over = threading.Event()  # ready, or the output ended

    def pump() -> None:
        assert proc.stdout is not None
        for line in proc.stdout:
            lines.append(line.rstrip())
            word, _, rest = line.partition(" ")
            if word in (PORTS, STATE_DIR, PIDS, READY):
                info[word] = rest.strip()
                if word == READY:
                    over.set()
        over.set()

    threading.Thread(target=pump, daemon=True).start()
    if not over.wait(timeout_s) or READY not in info:
        proc.kill()
        proc.wait()
        raise RuntimeError("station did not start:\n" + "\n".join(lines[-40:]))
    own = info.get(STATE_DIR)
    return Started(proc, info[READY], json.loads(info[PORTS]), json.loads(info.get(PIDS, "{}")),
                   Path(own) if own else None, lines)
