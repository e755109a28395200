"""Robot feedback through the real processes: fieldsim answers every command with
RobotFeedback (ball contact at the kicker face) -> relay "feedback" -> backend ->
GET /api/world robots[].feedback."""

from __future__ import annotations

import math
from typing import Any

import httpx

from .conftest import StationHandle, arm, launched, wait_until

TOUCH_MM = 90.0 + 21.5 + 4.0  # robot radius + ball radius + a few mm: at the kicker face


def _blue0(station: StationHandle) -> dict[str, Any]:
    return next(r for r in station.get("/api/world")["robots"]
                if r["team"] == "blue" and r["id"] == 0)


def test_ball_contact_reported_and_cleared(station: StationHandle) -> None:
    _ball_contact_on_and_off(station, "sim")


def test_grsim_status_reports_ball_contact() -> None:
    """The same through grSim's legacy path: fieldsim's Robots_Status (infrared) on the
    status ports -> the relay in --output grsim -> the backend."""
    with launched("--output", "grsim") as st:
        assert st.get("/api/world")["arming_required"] is True  # grSim: arming required
        wait_until(lambda: _blue0(st), 20, what="blue 0 seen")
        arm(st)
        _ball_contact_on_and_off(st, "grsim")


def _ball_contact_on_and_off(station: StationHandle, transport: str) -> None:
    r0 = wait_until(lambda: _blue0(station), 20, what="blue 0 seen")
    # hold blue 0 where it is (commanded: fieldsim answers for it)
    hold = {"x": r0["x"], "y": r0["y"], "orientation": r0["orientation"]}
    assert httpx.post(station.url + "/api/robots/blue/0/target", json=hold).status_code == 200
    try:
        def touching() -> dict[str, Any] | None:
            r = _blue0(station)
            fb = r["feedback"]
            if fb is not None and fb["ball_contact"]:
                return r
            # the ball right in front of its kicker (again, should it have been pushed away)
            x = r["x"] + TOUCH_MM * math.cos(r["orientation"])
            y = r["y"] + TOUCH_MM * math.sin(r["orientation"])
            httpx.post(station.url + "/api/sim/ball", json={"x": x, "y": y}).raise_for_status()
            return None

        r = wait_until(touching, 5, interval_s=0.3, what="blue 0 reports the ball at its kicker")
        fb = r["feedback"]
        assert fb["transport"] == transport and not fb["no_answer"]
        assert fb["age_s"] is not None
        if transport == "sim":  # answers every command: a fresh answer and its round trip
            assert fb["age_s"] < 0.5
            assert fb["round_trip_ms"] is not None and 0.0 <= fb["round_trip_ms"] < 100.0
            assert fb["commands_sent"] is not None and fb["commands_sent"] > 10
            assert fb["loss"] is not None and fb["loss"] < 0.2  # loopback: next to none
        assert fb["battery_v"] is None and fb["kicker_v"] is None
        httpx.post(station.url + "/api/sim/ball",
                   json={"x": r["x"] + 1500.0 * (1 if r["x"] < 0 else -1),
                         "y": -r["y"]}).raise_for_status()
        wait_until(lambda: _blue0(station)["feedback"]["ball_contact"] is False, 5,
                   what="no contact once the ball is teleported away")
    finally:
        httpx.delete(station.url + "/api/robots/blue/0/target", headers={"X-Touchline": "1"})
