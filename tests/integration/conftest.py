"""Starts the real station (fieldsim + larcmacs_relay + backend) through the launcher on
free, non-standard ports, once for the integration tests."""

from __future__ import annotations

import socket
import subprocess
import time
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import httpx
import pytest

from launcher.started import start_isolated
from tests.waiting import wait_until

__all__ = ["StationHandle", "arm", "launched", "next_relay_stats", "stop_process",
           "wait_until"]

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
    started = start_isolated([*keep, *extra_args])
    try:
        yield StationHandle(started.url, started.ports, started.lines, started.pids,
                            started.state_dir or state_dir)
    finally:
        if started.stop() is not None and state_dir is None:
            # an orderly stop leaves no temporary state folder behind
            assert started.state_dir is not None, \
                "the launcher did not say where its state went"
            assert not started.state_dir.exists(), started.state_dir


@pytest.fixture(scope="session")
def station() -> Iterator[StationHandle]:
    with launched() as st:
        yield st


@pytest.fixture(scope="module")
def bare() -> Iterator[StationHandle]:
    """Relay + backend and no simulator: the test program is the camera and the robots."""
    with launched("--sim", "none") as st:
        yield st


@pytest.fixture(scope="module")
def box_station() -> Iterator[tuple[StationHandle, socket.socket]]:
    """Relay + backend in robot-box mode (real robots: the seed's 13-byte datagram per robot,
    no team field) and no simulator, the test's socket as the robot box (non-blocking)."""
    box = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    box.bind(("127.0.0.1", 0))
    box.setblocking(False)
    try:
        with launched("--sim", "none", "--output", "robot-box",
                      f"--relay-arg=--robot-box=127.0.0.1:{box.getsockname()[1]}") as st:
            yield st, box
    finally:
        box.close()


def stop_process(proc: subprocess.Popen[str], timeout_s: float = 10.0) -> None:
    """SIGTERM, then SIGKILL if it does not end within ``timeout_s``."""
    proc.terminate()
    try:
        proc.wait(timeout=timeout_s)
    except subprocess.TimeoutExpired:
        proc.kill()
        proc.wait(timeout=timeout_s)


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
