"""What ``POST /api/arm`` answers, through the real processes (relay + backend, the test
program as the camera): ``relay_armed`` in the reply is the relay's state once it has taken
the change, not the statistics it sent before; a relay that does not answer (stopped) gives a
bounded reply that says so."""

from __future__ import annotations

import os
import signal
import time
from collections.abc import Iterator

import httpx
import pytest

from .conftest import StationHandle, launched, wait_until
from .standins import RobotBoxCamera


@pytest.fixture(scope="module")
def station() -> Iterator[StationHandle]:
    with launched("--sim", "none") as st:
        cam = RobotBoxCamera(st.ports)
        try:
            wait_until(lambda: st.get("/api/arm")["refusal"] is None, 20, what="vision seen")
            wait_until(lambda: st.get("/api/arm")["relay_armed"] is False, 10,
                       what="the relay's statistics")
            yield st
        finally:
            cam.stop()


def _arm(st: StationHandle, armed: bool) -> httpx.Response:
    return httpx.post(st.url + "/api/arm", json={"armed": armed},
                      headers={"X-Touchline": "1"}, timeout=10)


def test_the_reply_reports_the_relay_after_it_took_the_change(station: StationHandle) -> None:
    for armed in (True, False, True, False):
        r = _arm(station, armed)
        assert r.status_code == 200, r.text
        body = r.json()
        assert body["armed"] is armed and body["required"] is True
        assert body["relay_armed"] is armed, body
        assert body["relay_unconfirmed"] is None, body
        # and the relay says so on its own afterwards
        assert station.get("/api/health")["relay"]["armed"] is armed


def test_a_stuck_relay_is_reported_within_a_bound(station: StationHandle) -> None:
    """Stopped just now (its statistics still fresh): the reply waits its 2 s, then says the
    relay has not confirmed and what it last said. (Disarming: it always works, where arming
    needs vision, which comes through the relay.)"""
    assert _arm(station, True).json()["relay_armed"] is True
    relay = station.pids["relay"]
    os.kill(relay, signal.SIGSTOP)
    try:
        t0 = time.monotonic()
        r = _arm(station, False)
        took = time.monotonic() - t0
    finally:
        os.kill(relay, signal.SIGCONT)
    assert r.status_code == 200, r.text
    body = r.json()
    assert body["armed"] is False  # the station is disarmed, and repeats it to the relay
    assert body["relay_armed"] is True
    assert "not confirmed within 2 s" in body["relay_unconfirmed"], body
    assert "reports armed" in body["relay_unconfirmed"], body
    assert took < 8.0, took  # bounded by the reply's deadline, not the HTTP timeout
    # once it runs again it takes the station's state (repeated every 0.5 s)
    wait_until(lambda: station.get("/api/arm")["relay_unconfirmed"] is None, 10,
               what="the relay confirms after SIGCONT")
    assert station.get("/api/arm")["relay_armed"] is False


def test_a_relay_that_is_down_is_reported_at_once(station: StationHandle) -> None:
    """No statistics for 3 s: arming is refused for the missing vision (it comes through the
    relay), disarming is answered at once, saying the relay is not heard."""
    assert _arm(station, True).json()["relay_armed"] is True
    relay = station.pids["relay"]
    os.kill(relay, signal.SIGSTOP)
    try:
        # the station's own view: no statistics for 3 s
        wait_until(lambda: "is it running?" in (station.get("/api/arm")["relay_unconfirmed"]
                                                or ""), 10, what="the relay's stats stale")
        t0 = time.monotonic()
        r = _arm(station, False)
        took = time.monotonic() - t0
        assert r.status_code == 200, r.text
        body = r.json()
        assert body["armed"] is False and body["relay_armed"] is True
        assert "old (is it running?)" in body["relay_unconfirmed"], body
        assert took < 2.0, took  # not the 2 s wait: nothing alive to wait for
        r = _arm(station, True)
        assert r.status_code == 409 and "vision is missing" in r.json()["detail"], r.text
    finally:
        os.kill(relay, signal.SIGCONT)
    wait_until(lambda: station.get("/api/arm")["relay_unconfirmed"] is None, 10,
               what="the relay confirms after SIGCONT")
