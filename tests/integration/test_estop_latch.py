"""The latched emergency stop through the real processes (launcher, relay, backend; a test
program is the camera and the simulator): pressed, it survives a backend crash and the
launcher's restart, the relay keeps every robot at zero throughout (it is latched there too),
the new backend says "e-stop active" from its first answer, a release without confirmation is
refused, and only a confirmed release drives again."""

from __future__ import annotations

import os
import signal
import threading
import time

import httpx

from .conftest import StationHandle, arm, wait_until
from .standins import CommandLog
from .test_hostile_vision import Camera


def _post(st: StationHandle, path: str, body: dict) -> httpx.Response:  # type: ignore[type-arg]
    return httpx.post(st.url + path, json=body, timeout=5)


def test_the_estop_survives_a_backend_crash_and_only_a_confirmed_release_drives(
        bare: StationHandle) -> None:
    p = bare.ports
    cam = Camera(p["vision_group"], p["vision"])
    threading.Thread(target=cam.run, daemon=True).start()
    sim = CommandLog(p["sim_blue"])
    try:
        wait_until(lambda: any(r["id"] == 0 for r in bare.get("/api/world")["robots"]), 20,
                   what="blue 0 seen")
        arm(bare)  # an external simulator: the station starts disarmed
        t0 = time.monotonic()
        assert _post(bare, "/api/robots/blue/0/target", {"x": 3000, "y": 0}).status_code == 200
        wait_until(lambda: sim.moving_since(t0), 10, what="blue 0 driven before the stop")

        assert _post(bare, "/api/estop", {"active": True}).status_code == 200
        t_press = time.monotonic()
        # (health.relay is null until the backend's first relay statistics arrive)
        wait_until(lambda: bare.get("/api/health")["estop"]["relay_latched"] is True, 5,
                   what="the relay latched")
        # from 0.2 s after the press on, nothing may drive blue 0, whatever happens
        t_quiet = t_press + 0.2

        old_pid = bare.pids["backend"]
        os.kill(old_pid, signal.SIGKILL)  # a crash: no last stop, no goodbye

        def restarted() -> dict | None:  # type: ignore[type-arg]
            try:
                h = httpx.get(bare.url + "/api/world", timeout=1).json()
            except httpx.HTTPError:
                return None
            return h if h.get("estop_info") else None
        w = wait_until(restarted, 30, what="the launcher's restarted backend")
        assert w["estop"] is True, "a restarted backend must come up with the stop active"
        assert "(operator at " in w["estop_info"]["by"]  # name (role at address)
        assert any("backend exited" in ln and "restarting" in ln for ln in bare.log)
        # every page's health says so too, and the relay's latch held through the crash
        def relay_heard() -> dict | None:  # type: ignore[type-arg]
            h = bare.get("/api/health")
            return h if h["estop"]["relay_latched"] is not None else None
        h = wait_until(relay_heard, 10, what="relay statistics in the new backend")
        assert h["estop"]["active"] is True and h["estop"]["relay_latched"] is True
        assert any(w.startswith("emergency stop active since") for w in h["warnings"])

        # an operator (or a stale page) tries to drive: nothing moves
        assert _post(bare, "/api/robots/blue/0/target", {"x": 3000, "y": 0}).status_code == 200
        n = cam.frames
        wait_until(lambda: cam.frames >= n + 60, 5, what="a second of frames")
        r = _post(bare, "/api/estop", {"active": False})
        assert r.status_code == 409
        n = cam.frames
        wait_until(lambda: cam.frames >= n + 30, 5, what="half a second of frames")
        assert not sim.moving_since(t_quiet), [e for e in sim.log if e[0] >= t_quiet and e[2]]
        assert bare.get("/api/world")["estop"] is True

        t_release = time.monotonic()
        r = _post(bare, "/api/estop", {"active": False, "confirm": True, "reason": "test"})
        assert r.status_code == 200 and r.json()["estop"] is False
        # the press disarmed the station (and a restarted backend starts disarmed): a
        # release alone drives nothing, arming again does
        assert bare.get("/api/world")["armed"] is False
        n = cam.frames
        wait_until(lambda: cam.frames >= n + 30, 5, what="half a second of frames")
        assert not sim.moving_since(t_quiet), [e for e in sim.log if e[0] >= t_quiet and e[2]]
        arm(bare)
        wait_until(lambda: sim.moving_since(t_release), 10, what="driving after the release")
        wait_until(lambda: bare.get("/api/health")["estop"]["relay_latched"] is False, 5,
                   what="the relay released")
    finally:
        cam.stop.set()
        sim.close()
        httpx.delete(bare.url + "/api/robots/blue/0/target", headers={"X-Touchline": "1"})
