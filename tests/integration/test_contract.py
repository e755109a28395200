"""The browser contract (backend/contract.py) against what the real station sends: every HTTP
answer and websocket message of a running station (built-in simulator, a strategy, an operator
target, the internal referee, the numpy engine) validates, and no key is sent that the contract
does not declare (so the generated TypeScript types cannot drift from the wire)."""

from __future__ import annotations

import json
import time
from collections.abc import Iterator
from typing import Any

import httpx
import pytest
from pydantic import TypeAdapter
from websockets.sync.client import connect

from backend import contract

from .conftest import StationHandle, launched, wait_until


@pytest.fixture(scope="module")
def busy() -> Iterator[StationHandle]:
    with launched("--backend-arg=--set", "--backend-arg=strategy.engine=numpy",
                  "--log-dir", "tests/data") as st:
        yield st


def _valid(kind: Any, payload: Any, what: str) -> None:
    try:
        TypeAdapter(kind).validate_python(payload, strict=True)
    except Exception as exc:  # the message names the path of every mismatch
        raise AssertionError(f"{what} does not match the contract:\n{exc}") from None


def _post(st: StationHandle, path: str, body: dict[str, Any]) -> Any:
    r = httpx.post(st.url + path, json=body, timeout=5)
    assert r.status_code == 200, r.text
    return r.json()


def test_every_answer_and_message_matches_the_contract(busy: StationHandle) -> None:
    st = busy
    _valid(contract.RefereeView, _post(st, "/api/referee/internal/command",
                                       {"command": "FORCE_START"}), "POST referee command")
    _valid(contract.TargetAnswer, _post(st, "/api/robots/blue/0/target",
                                        {"x": 1000.0, "y": 500.0}), "POST target")

    def rich() -> Any:
        w = st.get("/api/world")
        robots = w["robots"]
        full = (w["ball"] is not None and w["referee"] is not None and w["cameras"]
                and any(r["control"] for r in robots)
                and any(r["target"] and r["target"]["source"] == "operator" for r in robots)
                and any(r["target"] and r["target"]["source"] == "strategy" for r in robots))
        return w if full else None
    world = wait_until(rich, 30, 0.2, what="a world with ball, referee, cameras, targets, "
                                           "controller telemetry")
    _valid(contract.World, world, "GET /api/world")

    def engine_running() -> Any:
        h = st.get("/api/health")
        return h if h["engine"] and h["engine"]["running"] and h["relay"] else None
    _valid(contract.Health, wait_until(engine_running, 30, 0.2, what="the numpy engine"),
           "GET /api/health")
    _valid(contract.Geometry, st.get("/api/geometry"), "GET /api/geometry")
    _valid(contract.StrategyView, st.get("/api/strategy"), "GET /api/strategy")
    _valid(contract.RefereeView, st.get("/api/referee"), "GET /api/referee")
    _valid(contract.EstopInfo, st.get("/api/estop"), "GET /api/estop")
    _valid(contract.ParamsState, st.get("/api/params"), "GET /api/params")
    _valid(contract.ParamsDiff, st.get("/api/params/diff"), "GET /api/params/diff")
    for method, path, kind in (("PUT", "/api/presets/contract", contract.PresetList),
                               ("GET", "/api/presets", contract.PresetList),
                               ("GET", "/api/presets/contract", contract.PresetDetail),
                               ("POST", "/api/presets/contract/load", contract.ParamsState),
                               ("DELETE", "/api/presets/contract", contract.PresetList)):
        r = httpx.request(method, st.url + path, headers={"x-touchline": "1"}, timeout=5)
        assert r.status_code == 200, (method, path, r.text)
        _valid(kind, r.json(), f"{method} {path}")
    _valid(contract.EstopAnswer, _post(st, "/api/estop", {"active": True}), "POST /api/estop")
    _valid(contract.EstopAnswer, _post(st, "/api/estop", {"active": False, "confirm": True}),
           "POST /api/estop (release)")

    _valid(contract.Recording, _post(st, "/api/recording", {"action": "new-file"}),
           "POST /api/recording")
    _valid(contract.LogList, st.get("/api/logs"), "GET /api/logs")
    _valid(contract.Player, st.get("/api/player"), "GET /api/player (live)")

    seen: set[str] = set()
    ws_url = st.url.replace("http://", "ws://") + "/api/ws"
    with connect(ws_url, open_timeout=10) as ws:
        deadline = time.monotonic() + 20
        while seen != {"snapshot", "world", "health", "params"}:
            assert time.monotonic() < deadline, f"only {sorted(seen)} arrived"
            msg = json.loads(ws.recv(timeout=5))
            _valid(contract.ServerMessage, msg, f"websocket {msg.get('type')!r} message")
            seen.add(msg["type"])
            if msg["type"] == "snapshot":  # a parameter change, to see its message
                r = httpx.patch(st.url + "/api/params", json={"strategy": {"kick_speed_mps": 5.0}},
                                timeout=5)
                assert r.status_code == 200, r.text

    # replaying: the player's answers and message, a world with its replay clock and the
    # estimate recorded in the log
    with connect(ws_url, open_timeout=10) as ws:
        _valid(contract.Player, _post(st, "/api/player", {
            "action": "open", "path": "fieldsim-2s.log.gz"}), "POST /api/player")
        deadline = time.monotonic() + 20
        replayed: dict[str, Any] = {}
        while not ("player" in replayed and "world" in replayed):
            assert time.monotonic() < deadline, f"only {sorted(replayed)} arrived in replay"
            msg = json.loads(ws.recv(timeout=5))
            _valid(contract.ServerMessage, msg, f"websocket {msg.get('type')!r} in replay")
            if msg["type"] == "player" and msg["player"]["source"] == "log":
                replayed["player"] = msg
            if msg["type"] == "world" and msg["world"]["replay"] and msg["world"]["recorded"]:
                replayed["world"] = msg
    _valid(contract.Player, _post(st, "/api/player", {"action": "seek", "position_s": 1.0}),
           "POST /api/player seek")
    _valid(contract.Player, _post(st, "/api/player", {"action": "live"}), "POST player live")


def test_the_contract_refuses_an_undeclared_key() -> None:
    """The check above can fail: a key the contract does not declare is refused."""
    geo = {"field_length": 9000.0, "field_width": 6000.0, "goal_width": 1000.0,
           "goal_depth": 180.0, "boundary_width": 300.0, "penalty_area_depth": 1000.0,
           "penalty_area_width": 2000.0, "goal_center_to_penalty_mark": 6000.0,
           "center_circle_radius": 500.0, "ball_radius": 21.5,
           "max_robot_radius": 90.0, "lines": [], "arcs": [], "cameras": []}
    _valid(contract.Geometry, geo, "a geometry")
    with pytest.raises(AssertionError, match="extra"):
        _valid(contract.Geometry, {**geo, "goal_colour": "blue"}, "a geometry with more")
    with pytest.raises(AssertionError, match="target"):
        _valid(contract.RobotTarget, {"x": 0.0, "y": 0.0, "orientation": None,
                                      "source": "demo"}, "a target from the demo")
