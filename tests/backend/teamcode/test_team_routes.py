"""GET /api/team and the team files through the app: reading for viewers; saving atomically,
refused on a conflict, too large or a bad name; allowed on loopback, and from another machine
only for operators of a station started with --allow-code-edit."""

from __future__ import annotations

import os
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest
from fastapi.testclient import TestClient

from backend.access import AccessRule
from backend.api import create_app
from backend.config import Settings
from backend.routes.deps import CODE_EDIT_REFUSED
from backend.station import Station
from backend.teamcode.discovery import version_of
from backend.teamcode.files import MAX_FILE_BYTES
from launcher.supervisor import free_tcp_port
from touchline import API_VERSION

PLAY = "TITLE = 'Ring'\ndef play(game):\n    return {}\n"
LOOPBACK = ("127.0.0.1", 50000)
LAN = ("192.168.1.20", 50000)


def _settings(tmp_path: Path, **kw: Any) -> Settings:
    team = tmp_path / "team"
    team.mkdir(exist_ok=True)
    (team / "ring.py").write_text(PLAY)
    return Settings(relay_pub=f"tcp://127.0.0.1:{free_tcp_port()}",
                    relay_sub=f"tcp://127.0.0.1:{free_tcp_port()}", static_dir=tmp_path,
                    state_dir=tmp_path / "state", allowed_hosts=["testserver"], team_dir=team,
                    **kw)


def _client(tmp_path: Path, client: tuple[str, int] = LOOPBACK, **kw: Any) -> TestClient:
    cfg = _settings(tmp_path, **kw)
    rule = AccessRule.from_settings(cfg.host, cfg.state_dir, cfg.require_token,
                                    cfg.view_token, cfg.estop_for_all)
    return TestClient(create_app(cfg, Station(cfg), access=rule),
                      headers={"X-Touchline": "1"}, client=client)


@pytest.fixture
def local(tmp_path: Path) -> Iterator[TestClient]:
    with _client(tmp_path) as c:
        yield c


def _token(c: TestClient) -> str:
    rule: AccessRule = c.app.state.access  # type: ignore[attr-defined]
    return rule.operator.token


def test_the_team_folder_is_listed(local: TestClient, tmp_path: Path) -> None:
    body = local.get("/api/team").json()
    assert body["dir"] == str(tmp_path / "team")
    assert body["api_version"] == API_VERSION
    assert body["edit"] == {"allowed": True, "reason": None}
    (f,) = body["files"]
    assert (f["name"], f["kind"], f["language"], f["play"], f["title"], f["state"]) == \
        ("ring.py", "play", "python", "ring", "Ring", "idle")
    assert f["version"] == version_of(PLAY.encode())
    assert f["size_bytes"] == len(PLAY) and f["error"] is None
    # the team's plays are offered beside the built-in ones
    plays = {p["name"]: p for p in local.get("/api/strategy").json()["plays"]}
    assert plays["ring"] == {"name": "ring", "title": "Ring", "description": "",
                             "source": "team", "file": "ring.py", "language": "python"}
    assert plays["match"]["source"] == "builtin" and plays["match"]["file"] is None
    # and health carries the same list
    assert [x["name"] for x in local.get("/api/health").json()["team_code"]] == ["ring.py"]


def test_read_and_save(local: TestClient, tmp_path: Path) -> None:
    r = local.get("/api/team/files/ring.py")
    assert r.status_code == 200
    got = r.json()
    assert got == {"name": "ring.py", "text": PLAY, "version": version_of(PLAY.encode()),
                   "language": "python"}
    new = PLAY.replace("Ring", "Ring 2")
    r = local.put("/api/team/files/ring.py", json={"text": new, "base_version": got["version"]})
    assert r.status_code == 200, r.text
    assert r.json()["version"] == version_of(new.encode())
    assert (tmp_path / "team" / "ring.py").read_text() == new
    # the station knows at once (the same reload path as an editor's save)
    (f,) = local.get("/api/team").json()["files"]
    assert f["title"] == "Ring 2" and f["version"] == version_of(new.encode())
    # no temporary file left behind
    assert sorted(os.listdir(tmp_path / "team")) == ["ring.py"]
    # a new file, in lib/ too
    r = local.put("/api/team/files/lib/util.m", json={"text": "function y = util(x)\n"
                                                              "  y = x;\nend\n"})
    assert r.status_code == 200
    names = [f["name"] for f in local.get("/api/team").json()["files"]]
    assert names == ["lib/util.m", "ring.py"]
    actions = local.get("/api/health").json()["operator_actions"]
    assert actions[0]["action"] == "team-save" and "lib/util.m" in actions[0]["details"]


def test_a_save_over_a_changed_file_is_refused(local: TestClient, tmp_path: Path) -> None:
    base = local.get("/api/team/files/ring.py").json()["version"]
    (tmp_path / "team" / "ring.py").write_text(PLAY + "# edited in an editor\n")
    r = local.put("/api/team/files/ring.py", json={"text": "x = 1\n", "base_version": base})
    assert r.status_code == 409 and "changed on disk" in r.json()["detail"]
    assert (tmp_path / "team" / "ring.py").read_text().endswith("# edited in an editor\n")
    # a "new" file that exists
    r = local.put("/api/team/files/ring.py", json={"text": "x = 1\n", "base_version": None})
    now = local.get("/api/team/files/ring.py").json()["version"]
    assert r.status_code == 409 and "exists already" in r.json()["detail"]
    assert f'send base_version "{now}"' in r.json()["detail"]  # how to save it, from a script
    # a base for a file that is gone
    r = local.put("/api/team/files/gone.py", json={"text": "x = 1\n", "base_version": base})
    assert r.status_code == 409 and not (tmp_path / "team" / "gone.py").exists()


@pytest.mark.parametrize("name", ["../escape.py", "sub/x.py", "lib/sub/x.py", "x.txt",
                                  ".hidden.py", "1x.py", "x-y.py", "/etc/passwd", "lib/.py",
                                  "x.py/", "X.PY"])
def test_names_outside_the_rules_are_refused(local: TestClient, tmp_path: Path,
                                             name: str) -> None:
    r = local.put(f"/api/team/files/{name}", json={"text": "x = 1\n"})
    assert r.status_code in (404, 422), (name, r.status_code)
    assert local.get(f"/api/team/files/{name}").status_code in (404, 422)
    assert sorted(os.listdir(tmp_path / "team")) == ["ring.py"]
    assert not (tmp_path / "escape.py").exists()


def test_too_large_and_missing(local: TestClient) -> None:
    r = local.put("/api/team/files/big.py", json={"text": "#" * (MAX_FILE_BYTES + 1)})
    assert r.status_code == 413
    assert local.get("/api/team/files/nothing.py").status_code == 404


def test_editing_from_another_machine(tmp_path: Path) -> None:
    """Off loopback: refused without --allow-code-edit even for the operator; with it, the
    operator token is needed (the station requires it off loopback)."""
    with _client(tmp_path, client=LAN, host="0.0.0.0") as c:
        token = _token(c)
        auth = {"authorization": f"Bearer {token}"}
        edit = c.get("/api/team", headers=auth).json()["edit"]
        assert edit == {"allowed": False, "reason": CODE_EDIT_REFUSED}
        r = c.put("/api/team/files/new.py", json={"text": "x = 1\n"}, headers=auth)
        assert r.status_code == 403 and r.json()["detail"] == CODE_EDIT_REFUSED
        r = c.put("/api/team/files/new.py", json={"text": "x = 1\n"})
        assert r.status_code == 401  # no token: the operator's rule first
        assert c.get("/api/team").json()["edit"]["allowed"] is False
    assert not (tmp_path / "team" / "new.py").exists()
    with _client(tmp_path, client=LAN, host="0.0.0.0", allow_code_edit=True) as c:
        auth = {"authorization": f"Bearer {_token(c)}"}
        assert c.put("/api/team/files/new.py", json={"text": "x = 1\n"}).status_code == 401
        assert c.get("/api/team").json()["edit"]["allowed"] is False  # a viewer
        assert c.get("/api/team", headers=auth).json()["edit"] == {"allowed": True,
                                                                    "reason": None}
        r = c.put("/api/team/files/new.py", json={"text": "x = 1\n"}, headers=auth)
        assert r.status_code == 200
    assert (tmp_path / "team" / "new.py").read_text() == "x = 1\n"


def test_loopback_on_a_lan_station_may_edit(tmp_path: Path) -> None:
    """The station's own machine: an operator there may edit without --allow-code-edit."""
    with _client(tmp_path, client=LOOPBACK, host="0.0.0.0") as c:
        auth = {"authorization": f"Bearer {_token(c)}"}
        r = c.put("/api/team/files/new.py", json={"text": "x = 1\n"}, headers=auth)
        assert r.status_code == 200


def test_viewing_needs_the_view_token_when_asked(tmp_path: Path) -> None:
    with _client(tmp_path, view_token=True) as c:
        assert c.get("/api/team").status_code == 401
        assert c.get("/api/team/files/ring.py").status_code == 401


def test_plays_are_chosen_among_the_known_ones(local: TestClient, tmp_path: Path) -> None:
    schema = local.get("/api/params/schema").json()
    play = schema["$defs"]["StrategyParams"]["properties"]["play"]
    assert play["enum"][:6] == ["match", "defend", "attack-drill", "formation", "simple",
                                "idle"] and "ring" in play["enum"]
    r = local.patch("/api/params", json={"strategy": {"play": "ring"}})
    assert r.status_code == 200 and r.json()["values"]["strategy"]["play"] == "ring"
    r = local.patch("/api/params", json={"strategy": {"play": "no_such_play"}})
    assert r.status_code == 422
    assert r.json()["detail"][0]["loc"] == ["body", "strategy", "play"]
    assert "no play named 'no_such_play'" in r.json()["detail"][0]["msg"]
    # per robot
    r = local.patch("/api/params", json={"strategy": {"robot_plays": {"3": "match",
                                                                       "4": "ring"}}})
    assert r.status_code == 200
    assert r.json()["values"]["strategy"]["robot_plays"] == {"3": "match", "4": "ring"}
    r = local.patch("/api/params", json={"strategy": {"robot_plays": {"5": "nothing"}}})
    assert r.status_code == 422 and r.json()["detail"][0]["loc"][-1] == "5"
    assert local.patch("/api/params", json={"strategy": {"robot_plays": {"16": "ring"}}}
                       ).status_code == 422
    r = local.patch("/api/params", json={"strategy": {"robot_plays": {"3": None}}})
    assert r.json()["values"]["strategy"]["robot_plays"] == {"4": "ring"}
    # the file goes: the play in force stays chosen (its robots stop, error "missing"), but
    # it can no longer be chosen anew
    (tmp_path / "team" / "ring.py").unlink()
    local.put("/api/team/files/other.py", json={"text": "x = 1\n"})  # (a rescan)
    assert "ring" not in local.get("/api/params/schema").json()["$defs"]["StrategyParams"][
        "properties"]["play"]["enum"]
    r = local.patch("/api/params", json={"strategy": {"kick_speed_mps": 5.0}})
    assert r.status_code == 200 and r.json()["values"]["strategy"]["play"] == "ring"
    r = local.patch("/api/params", json={"strategy": {"robot_plays": {"6": "ring"}}})
    assert r.status_code == 422


def test_the_team_folder_is_a_station_folder(local: TestClient, tmp_path: Path) -> None:
    """Set when the station starts (--team-dir, TOUCHLINE_TEAM_DIR), shown read-only with the
    other folders, never a parameter."""
    folders = {f["name"]: f for f in local.get("/api/folders").json()["folders"]}
    team = folders["team_dir"]
    assert team["paths"] == [str(tmp_path / "team")]
    assert (team["flag"], team["env"], team["label"]) == ("--team-dir", "TOUCHLINE_TEAM_DIR",
                                                          "Team code")
    env = Settings.from_env({"TOUCHLINE_TEAM_DIR": str(tmp_path / "elsewhere")})
    assert env.team_dir == tmp_path / "elsewhere"
    flag = Settings.from_env({"TOUCHLINE_TEAM_DIR": str(tmp_path / "elsewhere")},
                             team_dir=tmp_path / "flag")
    assert flag.team_dir == tmp_path / "flag"
    r = local.patch("/api/params", json={"strategy": {"team_dir": "/tmp/x"}})
    assert r.status_code == 422
