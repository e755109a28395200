"""The launcher restarts a crashed child and the station says so: the relay killed with
SIGKILL comes back, its restart shows in health (supervisor, a warning line), and the station
is healthy again with the new relay's data: frames captured after it started, in the backend's
world, and its statistics (how soon: bench/restart_bench.py)."""

from __future__ import annotations

import os
import signal
import time

from .conftest import launched, wait_until


def test_a_killed_relay_is_restarted_and_reported() -> None:
    with launched() as st:
        wait_until(lambda: st.get("/api/health")["ok"], 30, what="a healthy station")
        sup = {c["name"]: c for c in st.get("/api/health")["supervisor"]}
        assert set(sup) == {"fieldsim", "relay", "backend"}
        assert all(c["restarts"] == 0 for c in sup.values())
        old = sup["relay"]["pid"]
        os.kill(old, signal.SIGKILL)
        killed = time.monotonic()
        h = wait_until(lambda: (lambda h: h if any(
            c["name"] == "relay" and c["restarts"] == 1 for c in h["supervisor"] or [])
            else None)(st.get("/api/health")), 20, what="the relay restarted")
        relay = next(c for c in h["supervisor"] if c["name"] == "relay")
        assert relay["pid"] != old and relay["last_exit"] == -signal.SIGKILL
        assert any(w.startswith("relay restarted 1 time by the launcher") for w in h["warnings"])
        # the new relay's data: vision captured after it started (only it can have carried
        # that) in the backend's world, and its own statistics
        started_unix = time.time() - relay["up_s"]
        wait_until(lambda: st.get("/api/world")["t_capture"] > started_unix, 20,
                   what="a frame through the new relay in the backend's world")
        wait_until(lambda: (lambda h: h if h["ok"] and h["relay"] and h["relay"]["alive"]
                            and h["relay"]["time_ns"] > started_unix * 1e9 else None)(
                                st.get("/api/health")),
                   20, what="the station healthy with the new relay's statistics")
        assert time.monotonic() - killed < 25
