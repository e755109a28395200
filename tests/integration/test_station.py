"""The whole loop through the real processes: fieldsim -> relay -> backend -> relay -> fieldsim."""

from __future__ import annotations

import math
import threading
import time
from typing import Any

import httpx

from backend.processors.publisher import FRAME_AGE_STAGE
from sslnet.multicast import open_multicast_sender
from sslpb.ssl_gc_referee_message_pb2 import Referee

from .conftest import StationHandle, wait_until


def _visible(world: dict[str, Any], team: str) -> list[dict[str, Any]]:
    return [r for r in world["robots"] if r["team"] == team and r["visible"]]


def _speed(r: dict[str, Any]) -> float:
    return math.hypot(r["vx"], r["vy"])


def test_station_sees_both_teams_ball_and_geometry(station: StationHandle) -> None:
    w = wait_until(lambda: (lambda w: w if len(_visible(w, "blue")) == 6 and
                            len(_visible(w, "yellow")) == 6 and w["ball"] else None)(
        station.get("/api/world")), 30, what="6 v 6 and a ball")
    assert {r["id"] for r in _visible(w, "blue")} == set(range(6))
    geo = wait_until(lambda: httpx.get(station.url + "/api/geometry").json()
                     if httpx.get(station.url + "/api/geometry").status_code == 200 else None,
                     10, what="geometry")
    assert geo["field_length"] == 9000 and geo["field_width"] == 6000
    assert len(geo["lines"]) >= 5 and len(geo["arcs"]) >= 1
    cams = {c["camera_id"] for c in w["cameras"]}
    assert len(cams) == 4


def test_health_reports_rates_of_every_stream_and_processor(station: StationHandle) -> None:
    # rates are measured over the last second(s): look once the station has run a while
    h = wait_until(lambda: (lambda h: h if h["ok"] and h["relay"] and
                            h["streams"]["vision"]["packets"] > 1000 else None)(
        station.get("/api/health")), 30, what="healthy station")
    # 4 cameras x 60 Hz; generous bounds for a loaded 2-core machine
    assert 150 < h["streams"]["vision"]["rate_hz"] < 330, h["streams"]["vision"]
    # nothing malformed; a frame the loaded machine delivered half a second late is dropped as
    # "time out of range" (backend/world/clock.py: right to drop it; 3 of 27806 were in one
    # fresh-clone run at load 6-8, 28 of 26551 in one at load 9), never more than one in a
    # hundred (a clock that lost its camera drops every frame for seconds: far more)
    v = h["streams"]["vision"]
    late = v["errors_by_reason"].get("time out of range", 0)
    assert v["errors"] == late and late <= v["packets"] / 100, v
    assert h["relay"]["output_rate_hz"] >= 90
    procs = {p["name"]: p for p in h["processors"]}
    # topic-triggered processors coalesce bursts of frames into one run, so they run at
    # least at the camera frame rate of one camera, not once per datagram
    assert procs["world-model"]["measured_hz"] > 40
    assert procs["control"]["measured_hz"] > 40
    assert procs["world-model"]["errors"] == 0 and procs["control"]["errors"] == 0
    # latency of each stage since the datagram reached the relay, in pipeline order
    stages = h["latency_stages"]
    assert [s["stage"] for s in stages[:3]] == [
        "decoded (vision ingest)", "world model written", "commands sent to relay"]
    assert all(s["n"] > 0 for s in stages[:3])
    # each stage's p50 over its own samples: a frame each for the first, a pass each for the
    # others (a pass's newest frame), so they are in order on a quiet machine only (at load 12
    # the frames waiting in a burst made the first 6.1 ms, the second 2.0 ms)
    assert all(0 < s["p50_ms"] < 100 for s in stages[:3]), stages[:3]
    # what the robots experience: each one's newest frame's age when its command is sent
    age = next(s for s in stages if s["stage"] == FRAME_AGE_STAGE)
    assert age["n"] > 0 and 0 < age["p50_ms"] < 100
    # and the relay's own, to the first datagram out: its p50 and p99 too, not only a mean
    relay = next(s for s in stages if s["stage"] == "sent to robots (relay)")
    assert relay["p50_ms"] is not None and 0 < relay["p50_ms"] <= relay["p99_ms"] < 100, relay
    assert procs["strategy"]["configured_hz"] == 20.0
    # what each process costs: both busy (a camera stream at 240 Hz), neither runaway
    cost = {p["name"]: p for p in h["processes"]}
    assert set(cost) == {"backend", "relay"}
    assert all(0 < p["cpu_percent"] < 400 and p["rss_mb"] > 10 for p in cost.values()), cost


def test_demo_moves_blue_robots_and_not_yellow(station: StationHandle) -> None:
    def positions(team: str) -> dict[int, tuple[float, float]]:
        return {r["id"]: (r["x"], r["y"]) for r in _visible(station.get("/api/world"), team)}

    wait_until(lambda: len(positions("blue")) == 6, 30)
    b0, y0 = positions("blue"), positions("yellow")
    # the formation moves every blue robot; wait for three (the first to pass 200 mm need not
    # be with others yet on a loaded machine)
    moved = wait_until(lambda: (lambda m: m if len(m) >= 3 else None)(
        [i for i, p in positions("blue").items() if math.dist(p, b0[i]) > 200]), 15,
        what="three blue robots moving")
    assert len(moved) >= 3
    y1 = positions("yellow")
    assert all(math.dist(y1[i], y0[i]) < 50 for i in y0)


def test_operator_target_drives_a_robot_there(station: StationHandle) -> None:
    target = {"x": 1200.0, "y": -1500.0, "orientation": 1.2}
    r = httpx.post(station.url + "/api/robots/blue/4/target", json=target)
    assert r.status_code == 200, r.text

    def close() -> dict[str, Any] | None:
        rb = next(r for r in station.get("/api/world")["robots"]
                  if r["team"] == "blue" and r["id"] == 4)
        ok = math.hypot(rb["x"] - target["x"], rb["y"] - target["y"]) < 60 and _speed(rb) < 100
        return rb if ok else None

    rb = wait_until(close, 20, what="robot 4 at its target")
    assert abs(math.remainder(rb["orientation"] - target["orientation"], 2 * math.pi)) < 0.15
    assert rb["target"]["source"] == "operator"
    httpx.delete(station.url + "/api/robots/blue/4/target", headers={"X-Touchline": "1"})


def test_bad_target_is_rejected_and_station_keeps_running(station: StationHandle) -> None:
    r = httpx.post(station.url + "/api/robots/blue/1/target", content='{"x": NaN, "y": 1}',
                   headers={"content-type": "application/json"})
    assert r.status_code == 422
    assert station.get("/api/health")["processors"]


class RefereeSender:
    """Plays the game controller: sends Referee multicast at 20 Hz."""

    def __init__(self, group: str, port: int) -> None:
        self.sock = open_multicast_sender("127.0.0.1")
        self.addr = (group, port)
        self.command = Referee.HALT
        self.counter = 0
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, daemon=True)

    def set(self, command: int) -> None:
        self.command = command
        self.counter += 1

    def _msg(self) -> bytes:
        m = Referee(packet_timestamp=int(time.time() * 1e6), stage=Referee.NORMAL_FIRST_HALF,
                    command=self.command, command_counter=self.counter,  # type: ignore[arg-type]
                    command_timestamp=int(time.time() * 1e6))
        for t in (m.yellow, m.blue):
            t.name, t.score, t.red_cards, t.yellow_cards = "t", 0, 0, 0
            t.timeouts, t.timeout_time, t.goalkeeper = 4, 300_000_000, 0
        return m.SerializeToString()

    def _run(self) -> None:
        while not self._stop.is_set():
            self.sock.sendto(self._msg(), self.addr)
            self._stop.wait(0.05)

    def __enter__(self) -> RefereeSender:
        self._thread.start()
        return self

    def __exit__(self, *_: object) -> None:
        self._stop.set()
        self._thread.join()
        self.sock.close()


def _all_blue_still(station: StationHandle) -> bool:
    w = station.get("/api/world")
    blues = _visible(w, "blue")
    return len(blues) == 6 and all(_speed(r) < 60 for r in blues)


def test_referee_halt_stops_our_robots_and_force_start_resumes(station: StationHandle) -> None:
    p = station.ports
    with RefereeSender(p["referee_group"], p["referee"]) as gc:
        gc.set(Referee.HALT)
        wait_until(lambda: station.get("/api/world")["referee"] and
                   station.get("/api/world")["referee"]["command"] == "HALT", 10)
        wait_until(lambda: _all_blue_still(station), 5, what="all blue robots stopped on HALT")
        w = station.get("/api/world")
        assert all(r["command"] is None or (r["command"]["forward_mps"] == 0 and
                   r["command"]["left_mps"] == 0) for r in _visible(w, "blue"))
        gc.set(Referee.FORCE_START)
        wait_until(lambda: any(_speed(r) > 200 for r in _visible(station.get("/api/world"),
                                                                  "blue")), 15,
                   what="blue robots moving again after FORCE_START")


def test_emergency_stop_stops_every_robot(station: StationHandle) -> None:
    wait_until(lambda: any(_speed(r) > 200 for r in _visible(station.get("/api/world"), "blue")),
               15, what="robots moving before the stop")
    assert httpx.post(station.url + "/api/estop", json={"active": True}).status_code == 200
    try:
        wait_until(lambda: _all_blue_still(station), 5, what="all robots stopped")
        assert station.get("/api/world")["estop"] is True
    finally:
        httpx.post(station.url + "/api/estop", json={"active": False, "confirm": True})


def test_internal_referee_halt_travels_as_real_multicast_and_stops_robots(
        station: StationHandle) -> None:
    # refused (409) while another referee source was heard in the last seconds
    wait_until(lambda: httpx.post(station.url + "/api/referee/internal/command",
                                  json={"command": "HALT"}).status_code == 200, 10,
               what="internal referee accepted once no other game controller is heard")
    try:
        ref = wait_until(lambda: (lambda w: w["referee"] if w["referee"] and
                                  w["referee"]["source"] == "internal" and
                                  w["referee"]["command"] == "HALT" else None)(
            station.get("/api/world")), 10, what="internal HALT received back from multicast")
        assert ref["stage"] == "NORMAL_FIRST_HALF_PRE"
        wait_until(lambda: _all_blue_still(station), 5, what="all blue robots stopped")
        # the relay reports its counters once a second
        wait_until(lambda: (lambda h: h if h["streams"].get("relay.referee_out", {}).get(
            "packets", 0) > 0 else None)(station.get("/api/health")), 5,
            what="relay counting referee-out packets")
        # the internal referee sends at 20 Hz; its rate is counted over the last seconds, so
        # right after it started (or on a loaded machine) wait for it rather than read it once
        wait_until(lambda: station.get("/api/health")["streams"]["referee"]["rate_hz"] > 5, 10,
                   what="the internal referee's messages counted at more than 5 Hz")
    finally:
        httpx.post(station.url + "/api/referee/internal/command", json={"command": "FORCE_START"})
        httpx.post(station.url + "/api/referee/internal/enabled", json={"enabled": False})
    # switched off, its last command no longer binds the robots
    wait_until(lambda: station.get("/api/world")["referee"] is None, 5,
               what="no referee once the internal one is off")
    wait_until(lambda: any(_speed(r) > 200 for r in _visible(station.get("/api/world"), "blue")),
               15, what="robots moving again")


def test_teleport_ball_through_the_simulation_protocol(station: StationHandle) -> None:
    assert httpx.post(station.url + "/api/sim/ball",
                      json={"x": 2500, "y": -2000}).status_code == 200
    wait_until(lambda: (lambda b: b and math.hypot(b["x"] - 2500, b["y"] + 2000) < 50)(
        station.get("/api/world")["ball"]), 5, what="ball at the teleported position")


def _robot(station: StationHandle, team: str, rid: int) -> dict[str, Any]:
    return next(r for r in station.get("/api/world")["robots"]
                if r["team"] == team and r["id"] == rid)


def test_per_robot_algorithm1_drives_to_a_point_and_reports_its_gain(
        station: StationHandle) -> None:
    r = httpx.patch(station.url + "/api/params",
                    json={"control": {"robots": {"blue/2": {"algorithm": "algorithm1"}}}})
    assert r.status_code == 200, r.text
    target = {"x": -800.0, "y": 2000.0, "orientation": 0.0}
    start = _robot(station, "blue", 2)
    d0_m = math.hypot(start["x"] - target["x"], start["y"] - target["y"]) / 1000.0
    assert d0_m > 0.5, start  # a real move (the demo formation keeps blue 2 away from there)
    try:
        # the demo drives blue 2: its controller reports already (restarts: new targets so far)
        restarts0 = wait_until(lambda: (lambda c: c if c and c["algorithm"] == "algorithm1"
                                        else None)(_robot(station, "blue", 2)["control"]),
                               5, what="algorithm1 telemetry")["restarts"]
        assert httpx.post(station.url + "/api/robots/blue/2/target", json=target).status_code == 200
        rb = wait_until(lambda: (lambda rb: rb if math.hypot(rb["x"] - target["x"],
                                                             rb["y"] - target["y"]) < 60
                                 and _speed(rb) < 100 else None)(_robot(station, "blue", 2)),
                        20, what="blue 2 at its target under algorithm1")
        tel = rb["control"]
        # fieldsim's generation-2 robots have C = 1: the estimate must be near it by now
        assert 0.7 < tel["c_estimate"] < 1.3, tel
        # the move's line A-B is the whole way, unless the profile restarted on the way from
        # where the robot was (seen again after vision stalled, blocked, or held by a stale
        # stop: a loaded machine; each counts a restart)
        assert tel["path_length_m"] <= d0_m + 0.1, tel
        assert tel["path_length_m"] > 0.3 or tel["restarts"] > restarts0 + 1, tel
    finally:
        httpx.delete(station.url + "/api/robots/blue/2/target", headers={"X-Touchline": "1"})
        httpx.patch(station.url + "/api/params", json={"control": {"robots": {"blue/2": None}}})


def test_filter_switched_live_per_robot(station: StationHandle) -> None:
    assert _robot(station, "yellow", 1)["filter"] == "adaptive"  # the default
    r = httpx.patch(station.url + "/api/params",
                    json={"filters": {"robot_overrides": {"yellow/1": "paper"}}})
    assert r.status_code == 200, r.text
    try:
        wait_until(lambda: _robot(station, "yellow", 1)["filter"] == "paper", 5,
                   what="yellow 1 on the paper filter")
        rb = _robot(station, "yellow", 1)
        assert rb["visible"] and abs(rb["x"] - rb["raw_x"]) < 30  # standing robot: no lag
    finally:
        httpx.patch(station.url + "/api/params",
                    json={"filters": {"robot_overrides": {"yellow/1": None}}})
