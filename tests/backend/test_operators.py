"""Several operators (issue 12): the driving lock and the action list (backend/operators.py),
and their routes with two operators on one station (backend/routes/operators.py)."""

from collections.abc import Iterator

import pytest
from fastapi.testclient import TestClient

from backend.api import create_app
from backend.config import Settings
from backend.operators import DrivingRefused, Operators, Who, clean_name
from backend.station import Station
from launcher.supervisor import free_tcp_port
from tests.waiting import wait_until


class Clock:
    def __init__(self) -> None:
        self.t = 100.0

    def __call__(self) -> float:
        return self.t


ALICE = Who("alice-session-1", "alice", "operator", "10.0.0.1")
BOB = Who("bob-session-22", "bob", "operator", "10.0.0.2")


@pytest.fixture
def ops() -> tuple[Operators, Clock]:
    clock = Clock()
    return Operators(release_after_s=5.0, max_actions=3, clock=clock, wall=lambda: 1e9), clock


def test_the_first_to_drive_holds_the_team_and_the_other_is_refused_with_its_name(ops) -> None:  # type: ignore[no-untyped-def]
    o, _ = ops
    assert o.drive(ALICE, "blue") is True  # taken now
    assert o.drive(ALICE, "blue") is False  # already hers
    with pytest.raises(DrivingRefused, match="alice") as exc:
        o.drive(BOB, "blue")
    assert exc.value.holder == ALICE
    assert o.drive(BOB, "yellow") is True  # one lock per team
    assert [(d["team"], d["name"]) for d in o.driving()] == [("blue", "alice"), ("yellow", "bob")]


def test_asking_then_giving_hands_driving_over(ops) -> None:  # type: ignore[no-untyped-def]
    o, _ = ops
    o.drive(ALICE, "blue")
    assert o.request(BOB, "blue") == ALICE
    assert o.driving()[0]["requested_by"] == "bob"
    with pytest.raises(ValueError, match="does not drive"):
        o.give(BOB, "blue")  # only the holder gives
    assert o.give(ALICE, "blue") == BOB
    assert o.holder("blue") == BOB
    with pytest.raises(ValueError, match="nobody asked"):
        o.give(BOB, "blue")


def test_asking_for_a_free_team_takes_it(ops) -> None:  # type: ignore[no-untyped-def]
    o, _ = ops
    assert o.request(BOB, "yellow") is None
    assert o.holder("yellow") == BOB


def test_take_over_and_release(ops) -> None:  # type: ignore[no-untyped-def]
    o, _ = ops
    o.drive(ALICE, "blue")
    assert o.take_over(BOB, "blue") == ALICE
    assert o.holder("blue") == BOB
    assert o.release(ALICE, "blue") is False  # not hers any more
    assert o.release(BOB, "blue") is True
    assert o.holder("blue") is None


def test_a_connected_holder_keeps_it_and_loses_it_a_while_after_disconnecting(ops) -> None:  # type: ignore[no-untyped-def]
    o, clock = ops
    sid = o.connect(ALICE)
    o.drive(ALICE, "blue")
    clock.t += 60  # idle, but her page is open
    assert o.holder("blue") == ALICE
    o.disconnect(sid)
    clock.t += 4.9
    assert o.holder("blue") == ALICE  # a reload keeps it
    assert o.driving()[0]["connected"] is False
    clock.t += 0.2
    assert o.holder("blue") is None
    assert o.drive(BOB, "blue") is True


def test_a_script_without_a_page_holds_it_while_it_keeps_driving(ops) -> None:  # type: ignore[no-untyped-def]
    o, clock = ops
    o.drive(ALICE, "blue")
    for _ in range(3):
        clock.t += 4.0
        o.drive(ALICE, "blue")  # each drive renews it
    with pytest.raises(DrivingRefused):
        o.drive(BOB, "blue")
    clock.t += 5.0
    assert o.drive(BOB, "blue") is True


def test_sessions_are_listed_until_they_disconnect(ops) -> None:  # type: ignore[no-untyped-def]
    o, _ = ops
    a = o.connect(ALICE)
    o.connect(BOB)
    assert [(s["name"], s["role"], s["address"]) for s in o.sessions()] == [
        ("alice", "operator", "10.0.0.1"), ("bob", "operator", "10.0.0.2")]
    o.disconnect(a)
    o.disconnect(a)  # twice: no harm
    assert [s["name"] for s in o.sessions()] == ["bob"]


def test_the_action_list_is_bounded_and_newest_first(ops) -> None:  # type: ignore[no-untyped-def]
    o, _ = ops
    for i in range(5):
        o.record("target", str(ALICE), {"team": "blue", "id": i, "x": 1234.5})
    acts = o.actions()
    assert [a["seq"] for a in acts] == [5, 4, 3]
    assert acts[0]["by"] == "alice (operator at 10.0.0.1)"
    assert acts[0]["details"] == "team=blue, id=4, x=1234"


@pytest.mark.parametrize("raw,name", [("  Ann  Lee ", "Ann Lee"), ("a\x00b\u202ec", "abc"),
                                      ("", None), ("\x07", None), ("x" * 50, "x" * 32)])
def test_names_are_cleaned(raw: str, name: str | None) -> None:
    assert clean_name(raw) == name


# ---------------------------------------------------------------------------- the routes


@pytest.fixture
def station(tmp_path) -> Iterator[tuple[TestClient, Station, Clock]]:  # type: ignore[no-untyped-def]
    settings = Settings(relay_pub=f"tcp://127.0.0.1:{free_tcp_port()}",
                        relay_sub=f"tcp://127.0.0.1:{free_tcp_port()}", static_dir=tmp_path,
                        state_dir=tmp_path / "state", allowed_hosts=["testserver"])
    st = Station(settings)
    clock = Clock()
    # the station's own Operators (its views were built with it), on the test's clock
    st.operators.clock, st.operators.release_after_s = clock, 5.0
    with TestClient(create_app(settings, st), headers={"X-Touchline": "1"}) as c:
        yield c, st, clock


def _as(name: str) -> dict[str, str]:
    return {"cookie": f"touchline_name={name}"}


A = _as("alice")
B = _as("bob")


def _target(c: TestClient, who: dict[str, str], team: str = "blue"):  # type: ignore[no-untyped-def]
    return c.post(f"/api/robots/{team}/1/target", json={"x": 100, "y": 0}, headers=who)


def test_a_second_operator_gets_409_naming_the_holder_until_taking_over(station) -> None:  # type: ignore[no-untyped-def]
    c, st, _ = station
    assert _target(c, A).status_code == 200
    r = _target(c, B)
    assert r.status_code == 409 and "alice" in r.json()["detail"], r.text
    # the play drives our team too
    r = c.patch("/api/params", json={"strategy": {"play": "halt"}}, headers=B)
    assert r.status_code == 409 and "alice" in r.json()["detail"], r.text
    # the e-stop is never locked
    assert c.post("/api/estop", json={"active": True}, headers=B).status_code == 200
    # taking over must be confirmed
    r = c.post("/api/driving/blue/take", json={}, headers=B)
    assert r.status_code == 409 and "confirm" in r.json()["detail"]
    r = c.post("/api/driving/blue/take", json={"confirm": True}, headers=B)
    assert r.status_code == 200, r.text
    assert [(d["team"], d["name"]) for d in r.json()["driving"]] == [("blue", "bob")]
    assert _target(c, B).status_code == 200
    assert _target(c, A).status_code == 409
    acts = [(a["action"], a["by"].split(" ")[0]) for a in c.get("/api/operators").json()["actions"]]
    assert acts[:3] == [("target", "bob"), ("driving-taken-over", "bob"), ("estop", "bob")]
    assert ("driving-taken", "alice") in acts and ("target", "alice") in acts
    assert st.browser.health()["operator_actions"][0]["action"] == "target"


def test_asking_for_driving_and_the_holder_giving_it(station) -> None:  # type: ignore[no-untyped-def]
    c, _, _ = station
    assert _target(c, A).status_code == 200
    r = c.post("/api/driving/blue/request", headers=B)
    assert r.status_code == 200
    d = r.json()["driving"][0]
    assert (d["name"], d["requested_by"], d["requested_key"]) == ("alice", "bob", "bob@testclient")
    assert c.post("/api/driving/blue/give", headers=B).status_code == 409  # not bob's to give
    r = c.post("/api/driving/blue/give", headers=A)
    assert r.status_code == 200 and r.json()["driving"][0]["name"] == "bob"
    assert _target(c, B).status_code == 200
    assert c.post("/api/driving/blue/release", headers=A).status_code == 409
    assert c.post("/api/driving/blue/release", headers=B).status_code == 200
    assert _target(c, A).status_code == 200  # free again


def test_the_holders_page_closing_releases_driving_after_a_few_seconds(station) -> None:  # type: ignore[no-untyped-def]
    c, st, clock = station
    with c.websocket_connect("/api/ws", headers=A) as ws:
        assert ws.receive_json()["type"] == "snapshot"
        ops = c.get("/api/operators", headers=A).json()
        assert [(o["name"], o["role"]) for o in ops["operators"]] == [("alice", "operator")]
        assert ops["me"]["name"] == "alice" and ops["me"]["key"] == "alice@testclient"
        assert _target(c, A).status_code == 200
        clock.t += 60  # her page is open: she keeps it however long she idles
        assert _target(c, B).status_code == 409
    wait_until(lambda: not st.operators.sessions(), 5.0, 0.01, "the session to close")
    assert _target(c, B).status_code == 409  # just closed: a reload would keep it
    clock.t += 5.0
    assert _target(c, B).status_code == 200


def test_login_takes_a_name(station) -> None:  # type: ignore[no-untyped-def]
    c, _, _ = station
    # on this (loopback) station /login needs a token still: the one the station made
    rule = c.app.state.access  # type: ignore[attr-defined]
    r = c.get(f"/login?token={rule.operator.token}&name=Ann%20Lee", follow_redirects=False)
    assert r.status_code == 303
    assert "touchline_name=Ann%20Lee" in r.headers["set-cookie"]
    assert c.get("/api/operators").json()["me"]["name"] == "Ann Lee"


def test_a_parameter_change_made_on_an_old_version_is_refused_with_the_value_now(station) -> None:  # type: ignore[no-untyped-def]
    c, st, _ = station
    v0 = c.get("/api/params").json()["version"]
    r = c.patch("/api/params", json={"strategy": {"kick_speed_mps": 4.5}},
                headers={**A, "x-touchline-params-version": str(v0)})
    assert r.status_code == 200, r.text
    v1 = r.json()["version"]
    # bob still sees v0: his change of the same value is refused, showing alice's
    r = c.patch("/api/params", json={"strategy": {"kick_speed_mps": 5.0}},
                headers={**B, "x-touchline-params-version": str(v0)})
    assert r.status_code == 409, r.text
    d = r.json()["detail"][0]
    assert d["loc"] == ["body", "strategy", "kick_speed_mps"] and d["value_now"] == 4.5
    assert "4.5" in d["msg"]
    assert st.params.current.strategy.kick_speed_mps == 4.5
    # another value, unchanged since v0: fine; and on the newest version, fine
    other = c.patch("/api/params", json={"stream": {"ws_max_hz": 20}},
                    headers={**B, "x-touchline-params-version": str(v0)})
    assert other.status_code == 200, other.text
    r = c.patch("/api/params", json={"strategy": {"kick_speed_mps": 5.0}},
                headers={**B, "x-touchline-params-version": str(v1)})
    assert r.status_code == 200, r.text
    r = c.patch("/api/params", json={"stream": {"ws_max_hz": 20}},
                headers={**B, "x-touchline-params-version": "old"})
    assert r.status_code == 422


def test_every_operator_action_is_listed_with_who(station) -> None:  # type: ignore[no-untyped-def]
    c, st, _ = station
    assert c.put("/api/presets/p1", headers=A).status_code == 200
    assert c.post("/api/presets/p1/load", headers=A).status_code == 200
    assert c.post("/api/params/import", json={"values": {}}, headers=A).status_code == 200
    assert c.post("/api/referee/internal/command", json={"command": "STOP"},
                  headers=A).status_code == 200
    assert c.post("/api/arm", json={"armed": False}, headers=A).status_code == 200
    assert c.post("/api/estop", json={"active": True}, headers=B).status_code == 200
    acts = [(a["action"], a["by"].split(" ")[0]) for a in st.browser.health()["operator_actions"]]
    assert acts == [("estop", "bob"), ("disarm", "alice"), ("referee", "alice"),
                    ("params-import", "alice"), ("preset-load", "alice")]
