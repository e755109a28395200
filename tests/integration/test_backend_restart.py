"""A backend killed during play, through the real processes (launcher, relay, backend; issue
30): the supervisor's new backend (its warm spare, or a cold start with ``--no-standby``)
sends its first command before the slow parts of its start (the session recorder's file, the
compute engine, the web side) have started, as its own start timeline in health says; the
operator's arming survives that restart and commands reach the robots again without arming
anew, but a station started anew is disarmed; a pressed e-stop survives both. How soon:
bench/restart_bench.py --target backend (a benchmark, not a timed test)."""

from __future__ import annotations

import json
import os
import signal
import threading
import time
from pathlib import Path
from typing import Any

import httpx
import pytest

from sslnet.multicast import open_multicast_sender

from .conftest import StationHandle, arm, launched, next_relay_stats, wait_until
from .standins import CommandLog, frame


class StillCamera:
    """Camera 0 at 60 Hz: blue 0 and blue 1 where no command moves them (the test is the
    camera; nothing simulates the robots), off any formation spot, so the strategy keeps
    driving them for as long as the test runs."""

    ROBOTS = ((0, -1234.0, 567.0), (1, 1357.0, -864.0))

    def __init__(self, group: str, port: int) -> None:
        self.group, self.port = group, port
        self.stop = threading.Event()
        threading.Thread(target=self._run, daemon=True).start()

    def _run(self) -> None:
        sock = open_multicast_sender("127.0.0.1")
        end = time.monotonic() + 300  # bounded
        k = 0
        try:
            while not self.stop.is_set() and time.monotonic() < end:
                sock.sendto(frame(k, time.time(), blue=self.ROBOTS, ball=(0.0, 1500.0)),
                            (self.group, self.port))
                k += 1
                self.stop.wait(1 / 60)
        finally:
            sock.close()


def _supervised(st: StationHandle, name: str = "backend") -> dict[str, Any]:
    assert st.state_dir is not None
    status = json.loads((st.state_dir / "supervisor.json").read_text())
    child: dict[str, Any] = next(c for c in status["children"] if c["name"] == name)
    return child


def _kill_backend(st: StationHandle) -> tuple[int, float]:
    """SIGKILLs the running backend (a crash: no last stop); (its pid, the kill's time)."""
    pid = int(_supervised(st)["pid"])
    os.kill(pid, signal.SIGKILL)
    return pid, time.monotonic()


def _new_backend(st: StationHandle, old_pid: int) -> dict[str, Any]:
    """The health of the backend that replaced ``old_pid`` once it answers."""
    def answered() -> dict[str, Any] | None:
        try:
            h: dict[str, Any] = httpx.get(st.url + "/api/health", timeout=2).json()
        except (httpx.HTTPError, ValueError):
            return None
        pids = {c["name"]: c["pid"] for c in h.get("supervisor") or []}
        return h if pids.get("backend") not in (None, old_pid) else None
    health: dict[str, Any] = wait_until(answered, 60, what="the restarted backend")
    return health


@pytest.mark.parametrize("spare", [True, False], ids=["warm-spare", "cold"])
def test_the_first_command_after_a_crash_leaves_before_the_slow_parts_start(
        spare: bool) -> None:
    args = ["--backend-arg=--set=strategy.engine=numpy", *([] if spare else ["--no-standby"])]
    with launched(*args) as st:
        wait_until(lambda: st.get("/api/health")["ok"], 60, what="a healthy station")
        if spare:
            # the supervisor's spare has imported and waits for its word (its log line)
            spare_pid = wait_until(lambda: _supervised(st).get("spare_pid"), 60,
                                   what="the warm spare started")
            wait_until(lambda: any(f"standby (pid {spare_pid}): imported" in ln
                                   for ln in st.log), 90, what="the warm spare ready")
        first = st.get("/api/health")["startup"]
        assert first["restarted"] is False and first["standby"] is False
        old, _ = _kill_backend(st)
        h = _new_backend(st, old)
        startup = h["startup"]
        assert startup["restarted"] is True and startup["standby"] is spare

        def later_steps() -> dict[str, float] | None:
            steps: dict[str, float] = st.get("/api/health")["startup"]["steps_s"]
            return steps if "engine started" in steps else None
        steps = wait_until(later_steps, 60, what="the compute engine of the new backend")
        # the first command's path, in order, and everything slow only after it
        order = ["station built", "station running", "first frame", "first targets",
                 "first command"]
        assert [steps[k] for k in order] == sorted(steps[k] for k in order), steps
        for slow in ("recorder open", "engine started", "web imports", "web serving"):
            assert steps["first command"] < steps[slow], (slow, steps)
        assert (st.get("/api/health")["engine"] or {}).get("workers", 0) >= 1
        assert any("its warm spare took over" in ln for ln in st.log) is spare


def test_arming_survives_the_supervisors_restart_not_a_new_start_and_the_estop_both(
        tmp_path: Path) -> None:
    state = tmp_path / "state"

    def camera(st: StationHandle) -> StillCamera:
        return StillCamera(st.ports["vision_group"], st.ports["vision"])

    # 1. armed by the operator, then a crash: the restart is armed, the robots driven again
    with launched("--sim", "none", state_dir=state) as st:
        cam, sim = camera(st), CommandLog(st.ports["sim_blue"])
        try:
            wait_until(lambda: any(r["id"] == 0 for r in st.get("/api/world")["robots"]), 30,
                       what="blue 0 seen")
            by = arm(st)["by"]
            t0 = time.monotonic()
            wait_until(lambda: sim.moving_since(t0), 20, what="the robots driven when armed")
            old, t_kill = _kill_backend(st)
            h = _new_backend(st, old)
            assert h["arming"]["armed"] is True and h["arming"]["by"] == by, h["arming"]
            assert h["startup"]["restarted"] is True
            # the relay repeats the old commands for 0.1 s after the kill, then zeros: a
            # command that moves a robot after that is the new backend's, through a relay
            # that was never disarmed (the crash's restart came up disarmed before)
            wait_until(lambda: sim.moving_since(t_kill + 0.2), 30,
                       what="the new backend driving without arming again")
            # and the relay says so itself (its next statistics)
            wait_until(lambda: st.get("/api/arm")["relay_armed"] is not None, 10,
                       what="the relay's statistics in the new backend")
            assert st.get("/api/arm")["relay_armed"] is True
        finally:
            cam.stop.set()
            sim.close()
    # (an orderly stop, armed: the file says armed)
    assert json.loads((state / "arming.json").read_text())["armed"] is True

    # 2. the station started anew on that state: disarmed, nothing driven; then the e-stop,
    # pressed, survives a crash
    with launched("--sim", "none", state_dir=state) as st:
        cam, sim = camera(st), CommandLog(st.ports["sim_blue"])
        try:
            wait_until(lambda: any(r["id"] == 0 for r in st.get("/api/world")["robots"]), 30,
                       what="blue 0 seen")
            t_ready = time.monotonic()
            a = st.get("/api/arm")
            assert a["armed"] is False and a["required"] is True, a
            assert not (state / "arming.json").exists()
            # the relay's own statistics from a while later: it was never armed meanwhile,
            # and no command moved a robot
            h = next_relay_stats(st, span_s=0.5)
            assert h["relay"]["armed"] is False
            assert not sim.moving_since(t_ready)

            arm(st)
            r = httpx.post(st.url + "/api/estop", json={"active": True}, timeout=5)
            assert r.status_code == 200 and st.get("/api/arm")["armed"] is False
            old, _ = _kill_backend(st)
            h = _new_backend(st, old)
            assert h["estop"]["active"] is True and h["arming"]["armed"] is False
        finally:
            cam.stop.set()
            sim.close()

    # 3. and the station started anew again: the stop is still pressed
    with launched("--sim", "none", state_dir=state) as st:
        h = st.get("/api/health")
        assert h["startup"]["restarted"] is False
        assert h["estop"]["active"] is True and h["arming"]["armed"] is False
        assert any(w.startswith("emergency stop active since") for w in h["warnings"])
