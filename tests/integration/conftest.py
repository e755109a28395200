"""Starts the real station (fieldsim + larcmacs_relay + backend) through the launcher on
free, non-standard ports, once for the integration tests."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import threading
import time
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import httpx
import pytest

ROOT = Path(__file__).resolve().parents[2]


@dataclass
class StationHandle:
    url: str
    ports: dict[str, Any]
    log: list[str]
    pids: dict[str, int]
    state_dir: Path | None = None

    def get(self, path: str) -> Any:
        r = httpx.get(self.url + path, timeout=5.0)
        r.raise_for_status()
        return r.json()


@contextmanager
def launched(*extra_args: str, state_dir: Path | None = None) -> Iterator[StationHandle]:
    """The whole station through ``python -m launcher --isolated`` with ``extra_args``;
    stopped (SIGTERM, then kill) on exit. ``state_dir``: the station keeps its state there
    (it stays after the stop: a later start on it is the same station started anew); by
    default a temporary folder of the launcher's, removed at its stop."""
    keep = ["--state-dir", str(state_dir)] if state_dir is not None else []
    proc = subprocess.Popen(
        [sys.executable, "-m", "launcher", "--isolated", *keep, *extra_args],
        cwd=ROOT, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
        env={**os.environ, "PYTHONUNBUFFERED": "1"},
    )
    lines: list[str] = []
    ready = threading.Event()
    info: dict[str, Any] = {}

    def pump() -> None:
        assert proc.stdout is not None
        for line in proc.stdout:
            lines.append(line.rstrip())
            if line.startswith("TOUCHLINE_PORTS "):
                info["ports"] = json.loads(line.split(" ", 1)[1])
            if line.startswith("TOUCHLINE_PIDS "):
                info["pids"] = json.loads(line.split(" ", 1)[1])
            if line.startswith("TOUCHLINE_STATE_DIR "):
                info["state_dir"] = line.split(" ", 1)[1].strip()
            if line.startswith("TOUCHLINE_READY "):
                info["url"] = line.split(" ", 1)[1].strip()
                ready.set()

    threading.Thread(target=pump, daemon=True).start()
    if not ready.wait(90):
        proc.kill()
        raise RuntimeError("station did not start:\n" + "\n".join(lines[-40:]))
    try:
        own = info.get("state_dir")
        yield StationHandle(info["url"], info["ports"], lines, info.get("pids", {}),
                            Path(own) if own else state_dir)
    finally:
        proc.send_signal(signal.SIGTERM)
        try:
            proc.wait(timeout=15)
        except subprocess.TimeoutExpired:
            proc.kill()
        else:
            if state_dir is None:
                # an orderly stop leaves no temporary state folder behind
                assert "state_dir" in info, "the launcher did not say where its state went"
                assert not Path(info["state_dir"]).exists(), info["state_dir"]


@pytest.fixture(scope="session")
def station() -> Iterator[StationHandle]:
    with launched() as st:
        yield st


@pytest.fixture(scope="module")
def bare() -> Iterator[StationHandle]:
    """Relay + backend and no simulator: the test program is the camera and the robots."""
    with launched("--sim", "none") as st:
        yield st


def stop_process(proc: subprocess.Popen[str], timeout_s: float = 10.0) -> None:
    """SIGTERM, then SIGKILL if it does not end within ``timeout_s``."""
    proc.terminate()
    try:
        proc.wait(timeout=timeout_s)
    except subprocess.TimeoutExpired:
        proc.kill()
        proc.wait(timeout=timeout_s)


def wait_until(cond, timeout_s: float, interval_s: float = 0.1, what: str = "") -> Any:  # type: ignore[no-untyped-def]
    """Polls ``cond`` until it returns a truthy value; bounded."""
    deadline = time.monotonic() + timeout_s
    last = None
    while time.monotonic() < deadline:
        last = cond()
        if last:
            return last
        time.sleep(interval_s)
    raise AssertionError(f"timed out after {timeout_s} s waiting for {what or cond}: {last!r}")


def next_relay_stats(st: StationHandle, span_s: float = 0.5,
                     timeout_s: float = 5.0) -> dict[str, Any]:
    """Returns the health once the relay's statistics, stamped by the relay at least
    ``span_s`` after this call (the same machine's clock), have arrived: a stretch of the
    relay's own running time, for checks that it did nothing meanwhile (every datagram it
    sent before those statistics is in the receiver's socket by then)."""
    t = time.time_ns() + int(span_s * 1e9)

    def newer() -> dict[str, Any] | None:
        h: dict[str, Any] = st.get("/api/health")
        return h if (h["relay"] or {}).get("time_ns", 0) >= t else None
    health: dict[str, Any] = wait_until(newer, timeout_s, what="the relay's next statistics")
    return health


def arm(st: StationHandle, timeout_s: float = 10.0) -> dict[str, Any]:
    """Arms a station whose relay requires arming (``--sim none``, real robots): retried
    until accepted (it is refused until vision arrives); returns the arming state."""
    def accepted() -> dict[str, Any] | None:
        r = httpx.post(st.url + "/api/arm", json={"armed": True}, timeout=5.0)
        if r.status_code == 409:
            return None
        r.raise_for_status()
        body: dict[str, Any] = r.json()
        return body
    result: dict[str, Any] = wait_until(accepted, timeout_s, what="arming accepted")
    return result
