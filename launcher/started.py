"""The whole station started from a program (the integration tests, the fuzzer, benchmarks):
``python -m launcher --isolated`` on free ports, its announced lines read back.

The launcher writes machine-readable lines on standard output once the backend answers
(``announce`` in ``__main__.py``): ``TOUCHLINE_PORTS {json}``, ``TOUCHLINE_STATE_DIR path``
(with its own temporary state folder), ``TOUCHLINE_PIDS {json}`` and last
``TOUCHLINE_READY url``. ``start_isolated`` reads them with ``AnnouncedLines``, a thread that
keeps reading to the end (every line kept, so the pipe never fills and a failure can show the
log); the benchmarks' ``bench/station_run.py`` reads them with it too."""

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
from typing import IO, Any

from .supervisor import ROOT

PORTS, STATE_DIR, PIDS, READY = ("TOUCHLINE_PORTS", "TOUCHLINE_STATE_DIR", "TOUCHLINE_PIDS",
                                 "TOUCHLINE_READY")


class AnnouncedLines:
    """A started launcher's output read on a thread to its end: every line kept in ``lines``
    (without its line break; written to ``log`` as it comes), the announced ones in ``info``
    by their word."""

    def __init__(self, proc: subprocess.Popen[str], log: IO[str] | None = None) -> None:
        self.lines: list[str] = []
        self.info: dict[str, str] = {}
        self._proc, self._log = proc, log
        self._over = threading.Event()  # ready, or the output ended
        self.thread = threading.Thread(target=self._pump, daemon=True)
        self.thread.start()

    def _pump(self) -> None:
        assert self._proc.stdout is not None
        for line in self._proc.stdout:
            if self._log is not None:
                self._log.write(line)
                self._log.flush()
            self.lines.append(line.rstrip())
            word, _, rest = line.partition(" ")
            if word in (PORTS, STATE_DIR, PIDS, READY):
                self.info[word] = rest.strip()
                if word == READY:
                    self._over.set()
        self._over.set()

    def wait_ready(self, timeout_s: float) -> None:
        """Returns once the launcher announced its URL; RuntimeError with the last 40 lines,
        the launcher killed, if its output ended first or ``timeout_s`` passed."""
        if not self._over.wait(timeout_s) or READY not in self.info:
            self._proc.kill()
            self._proc.wait()
            raise RuntimeError("station did not start:\n" + "\n".join(self.lines[-40:]))

    @property
    def state_dir(self) -> Path | None:
        own = self.info.get(STATE_DIR)
        return Path(own) if own else None


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
    read = AnnouncedLines(proc)
    read.wait_ready(timeout_s)
    info = read.info
    return Started(proc, info[READY], json.loads(info[PORTS]), json.loads(info.get(PIDS, "{}")),
                   read.state_dir, read.lines)
