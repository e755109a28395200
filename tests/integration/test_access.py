"""The access rule through the real processes (the launcher starts relay and backend, no
simulator): ``--require-token`` on the launcher reaches the backend, which prints the login
URL (in the launcher's output) and writes the token file 0600; a change without the token is
401, with the Bearer token or the login cookie 200; a viewer's e-stop is 403 unless the
station was started with ``--estop-for-all``."""

from __future__ import annotations

import json
import stat
from collections.abc import Iterator

import httpx
import pytest
from websockets.exceptions import InvalidStatus
from websockets.sync.client import connect

from .conftest import StationHandle, launched, wait_until

TARGET = ("/api/robots/blue/1/target", {"x": 100, "y": 200})


def _login_url(st: StationHandle) -> str:
    def find() -> str | None:
        for line in st.log:
            if line.startswith("TOUCHLINE_LOGIN "):
                info = json.loads(line.split(" ", 1)[1])
                if info["role"] == "operator":
                    return str(info["url"])
        return None
    return str(wait_until(find, 10.0, what="the login URL in the launcher's output"))


@pytest.fixture(scope="module")
def guarded() -> Iterator[StationHandle]:
    with launched("--sim", "none", "--require-token") as st:
        yield st


def test_the_token_is_printed_and_kept_private(guarded: StationHandle) -> None:
    url = _login_url(guarded)
    token = url.split("token=", 1)[1]
    assert url.startswith(guarded.url + "/login?token=")
    assert any("operator login" in line and url in line for line in guarded.log)
    assert any("Changes need the operator token" in line for line in guarded.log)
    assert guarded.state_dir is not None
    path = guarded.state_dir / "token"
    assert path.read_text().strip() == token
    assert stat.S_IMODE(path.stat().st_mode) == 0o600


def test_control_needs_the_token_by_bearer_or_the_login_cookie(guarded: StationHandle) -> None:
    token = _login_url(guarded).split("token=", 1)[1]
    with httpx.Client(base_url=guarded.url, timeout=5.0) as c:
        r = c.post(TARGET[0], json=TARGET[1])
        assert r.status_code == 401 and "operator token" in r.json()["detail"]
        assert c.get("/api/world").status_code == 200  # viewing stays open
        r = c.post(TARGET[0], json=TARGET[1], headers={"authorization": f"Bearer {token}"})
        assert r.status_code == 200, r.text
        r = c.post(TARGET[0], json=TARGET[1], headers={"authorization": "Bearer wrong"})
        assert r.status_code == 401
    with httpx.Client(base_url=guarded.url, timeout=5.0) as browser:
        r = browser.get(f"/login?token={token}", follow_redirects=False)
        assert r.status_code == 303 and "samesite=strict" in r.headers["set-cookie"].lower()
        assert browser.post(TARGET[0], json=TARGET[1]).status_code == 200
        r = browser.delete(TARGET[0], headers={"x-touchline": "1"})
        assert r.status_code == 200
    # the websocket by the token in its query (scripts)
    ws_url = guarded.url.replace("http://", "ws://") + "/api/ws"
    with connect(f"{ws_url}?token={token}", open_timeout=10) as ws:
        assert json.loads(ws.recv(timeout=10))["type"] == "snapshot"
    with connect(ws_url, open_timeout=10) as ws:  # viewing: open without --view-token
        assert json.loads(ws.recv(timeout=10))["type"] == "snapshot"


def test_a_viewer_cannot_stop_the_robots(guarded: StationHandle) -> None:
    token = _login_url(guarded).split("token=", 1)[1]
    r = httpx.post(guarded.url + "/api/estop", json={"active": True}, timeout=5.0)
    assert r.status_code == 403 and "--estop-for-all" in r.json()["detail"]
    assert guarded.get("/api/estop")["active"] is False
    op = {"authorization": f"Bearer {token}"}
    r = httpx.post(guarded.url + "/api/estop", json={"active": True}, headers=op, timeout=5.0)
    assert r.status_code == 200
    r = httpx.post(guarded.url + "/api/estop", json={"active": False, "confirm": True},
                   headers=op, timeout=5.0)
    assert r.status_code == 200 and r.json()["active"] is False


def test_with_estop_for_all_a_viewer_presses_the_stop_and_a_view_token_guards_reading() -> None:
    with launched("--sim", "none", "--estop-for-all", "--view-token") as st:
        r = httpx.get(st.url + "/api/world", timeout=5.0)
        assert r.status_code == 401 and "token to view" in r.json()["detail"]
        view = next(json.loads(line.split(" ", 1)[1])["url"] for line in st.log
                    if line.startswith("TOUCHLINE_LOGIN ") and '"viewer"' in line)
        vt = view.split("token=", 1)[1]
        assert st.state_dir is not None
        assert stat.S_IMODE((st.state_dir / "view-token").stat().st_mode) == 0o600
        ws_url = st.url.replace("http://", "ws://") + "/api/ws"
        with pytest.raises(InvalidStatus) as refused:
            connect(ws_url, open_timeout=10)
        assert refused.value.response.status_code == 401
        with httpx.Client(base_url=st.url, timeout=5.0) as viewer:
            assert viewer.get(f"/login?token={vt}", follow_redirects=False).status_code == 303
            assert viewer.get("/api/world").status_code == 200
            assert viewer.post(TARGET[0], json=TARGET[1]).status_code == 401
            r = viewer.post("/api/estop", json={"active": True})
            assert r.status_code == 200 and "(viewer at " in r.json()["by"]
            r = viewer.post("/api/estop", json={"active": False, "confirm": True})
            assert r.status_code == 403
