"""Issue 30.1: no path from the web to the file system through the parameters. No string
parameter can hold a path; the folders the station reads code from or writes to are set when it
starts (flags, TOUCHLINE_* variables: backend/config.py) and shown read-only; a PATCH, an import
or a preset that carries one is refused (422, the field, where it is set instead); the files a
station wrote before (tests/data/state-before-issue30/, written by e7af98a's own ParamStore and
export) still load with the old fields dropped and one log line."""

from __future__ import annotations

import json
import logging
import re
import shutil
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest
from fastapi.testclient import TestClient

from backend.api import create_app
from backend.config import ROOT, Settings
from backend.engine.switch import EngineSwitch
from backend.params.model import StationParams, StrategyParams
from backend.params.store import ParamError, ParamStore
from backend.station import Station
from launcher.supervisor import free_tcp_port

OLD_STATE = ROOT / "tests" / "data" / "state-before-issue30"
#: what a path may look like: any of these matched by a pattern lets a path through
PATH_PROBES = ("a/b", "/etc", "..", "../x", "a\\b", "C:\\x", "~/x", "x/..", "./x",
               "engine_scripts/goalkeeper")


# ---- the schema ----------------------------------------------------------------------------

def _strings(schema: dict[str, Any], node: Any, path: str,
             seen: frozenset[str] = frozenset()) -> Iterator[tuple[str, dict[str, Any]]]:
    """Every string-valued schema node under ``node`` (refs, unions, maps, lists followed)."""
    if isinstance(node, list):
        for n in node:
            yield from _strings(schema, n, path, seen)
        return
    if not isinstance(node, dict):
        return
    if "$ref" in node:
        name = node["$ref"].split("/")[-1]
        if name not in seen:
            yield from _strings(schema, schema["$defs"][name], path, seen | {name})
        return
    types = node.get("type")
    if types == "string" or (isinstance(types, list) and "string" in types):
        yield path, node
    for key in ("anyOf", "oneOf", "allOf"):
        yield from _strings(schema, node.get(key, []), path, seen)
    for name, prop in node.get("properties", {}).items():
        yield from _strings(schema, prop, f"{path}.{name}".lstrip("."), seen)
    for key in ("additionalProperties", "items"):
        if isinstance(node.get(key), dict):
            yield from _strings(schema, node[key], f"{path}[]", seen)


def test_no_string_parameter_can_hold_a_path() -> None:
    """Every string parameter is an enum (a Literal) or carries a pattern that refuses '/',
    '\\' and '..': a future path parameter (a team-code folder ...) fails here."""
    schema = StationParams.model_json_schema()
    found = list(_strings(schema, schema, ""))
    assert len(found) >= 5, found  # the walk reaches the string parameters
    bad = []
    for path, node in found:
        if "enum" in node or "const" in node:
            continue
        pattern = node.get("pattern")
        if pattern is None:
            bad.append(f"{path}: a free string (no enum, no pattern)")
            continue
        # pydantic matches a pattern anywhere in the value (search), as re.search does
        let_through = [p for p in PATH_PROBES if re.search(pattern, p)]
        if let_through:
            bad.append(f"{path}: pattern {pattern!r} lets {let_through} through")
    assert bad == []


def _maps(schema: dict[str, Any], node: dict[str, Any], path: tuple[str, ...]
          ) -> Iterator[tuple[tuple[str, ...], dict[str, Any]]]:
    if "$ref" in node:
        node = schema["$defs"][node["$ref"].split("/")[-1]]
    for name, prop in node.get("properties", {}).items():
        if isinstance(prop.get("additionalProperties"), dict):
            yield (*path, name), prop["additionalProperties"]
        yield from _maps(schema, prop, (*path, name))


@pytest.mark.parametrize("key", ["../etc", "/tmp/x", "blue\\3", "blue/../3"])
def test_a_map_of_parameters_takes_no_path_as_its_key(tmp_path: Path, key: str) -> None:
    """The maps (per-robot overrides) are keyed by robot, "blue/3": anything else, a path
    included, is refused; the same value under a robot's key is taken (the test can fail)."""
    schema = StationParams.model_json_schema()
    maps = list(_maps(schema, schema, ()))
    assert len(maps) >= 2, maps
    for path, value_schema in maps:
        value: Any = value_schema["enum"][0] if "enum" in value_schema else {}

        def patch(k: str, p: tuple[str, ...] = path, v: Any = value) -> dict[str, Any]:
            out: dict[str, Any] = {k: v}
            for part in reversed(p):
                out = {part: out}
            return out
        store = ParamStore(tmp_path)
        store.patch(patch("blue/3"))
        with pytest.raises(ParamError):
            store.patch(patch(key))


# ---- refusals ------------------------------------------------------------------------------

@pytest.fixture
def client(tmp_path: Path) -> Iterator[tuple[TestClient, Station]]:
    settings = Settings(relay_pub=f"tcp://127.0.0.1:{free_tcp_port()}",
                        relay_sub=f"tcp://127.0.0.1:{free_tcp_port()}", static_dir=tmp_path,
                        state_dir=tmp_path / "state", scripts_dir=tmp_path / "scripts",
                        record_dir=tmp_path / "rec", log_dirs=[tmp_path / "more-logs"],
                        allowed_hosts=["testserver"])
    st = Station(settings)
    with TestClient(create_app(settings, st), headers={"X-Touchline": "1"}) as c:
        yield c, st


def _refused(r: Any, loc: list[str], says: str) -> None:
    assert r.status_code == 422, r.text
    detail = r.json()["detail"]
    hit = [d for d in detail if d["loc"] == ["body", *loc]]
    assert hit and says in hit[0]["msg"], detail


@pytest.mark.parametrize("change,loc,says", [
    ({"strategy": {"scripts_dir": "/tmp/evil"}}, ["strategy", "scripts_dir"],
     "folders are set when the station starts (--scripts-dir or TOUCHLINE_SCRIPTS_DIR)"),
    ({"recording": {"folder": "/home/someone/.ssh"}}, ["recording", "folder"],
     "folders are set when the station starts (--record-dir or TOUCHLINE_RECORD_DIR)"),
    # any path-like key, present or future (a team-code folder, a file ...)
    ({"strategy": {"team_code_dir": "/tmp/x"}}, ["strategy", "team_code_dir"],
     "set when the station starts"),
    ({"recording": {"file_path": "/tmp/x.log"}}, ["recording", "file_path"],
     "set when the station starts"),
    ({"log_folder": "/tmp"}, ["log_folder"], "set when the station starts"),
])
def test_a_patch_carrying_a_folder_is_refused_and_nothing_applied(
        client: tuple[TestClient, Station], change: dict[str, Any], loc: list[str],
        says: str) -> None:
    c, st = client
    v0 = c.get("/api/params").json()["version"]
    # next to a good change: neither is applied
    r = c.patch("/api/params", json={**change, "world": {"drop_timeout_s": 9.0}})
    _refused(r, loc, says)
    assert c.get("/api/params").json()["version"] == v0
    assert st.params.current.world.drop_timeout_s == 3.0
    assert st.recording.folder() == st.settings.record_dir  # where it was set at start


def test_an_unknown_key_that_is_no_path_keeps_its_own_refusal(
        client: tuple[TestClient, Station]) -> None:
    c, _ = client
    r = c.patch("/api/params", json={"strategy": {"no_such": 1}})
    assert r.status_code == 422 and r.json()["detail"][0]["type"] == "extra_forbidden"


def test_importing_an_export_from_before_is_refused_naming_both_fields(
        client: tuple[TestClient, Station]) -> None:
    c, st = client
    old_export = (OLD_STATE / "touchline-params.json").read_text()
    assert '"scripts_dir"' in old_export  # a real export of the station before the change
    v0 = st.params.version
    r = c.post("/api/params/import", content=old_export,
               headers={"content-type": "application/json"})
    _refused(r, ["strategy", "scripts_dir"], "--scripts-dir")
    _refused(r, ["recording", "folder"], "--record-dir")
    assert st.params.version == v0
    # without them the same file imports, every other value kept
    values = json.loads(old_export)["values"]
    del values["strategy"]["scripts_dir"], values["recording"]["folder"]
    r = c.post("/api/params/import", json={"values": values})
    assert r.status_code == 200, r.text
    assert st.params.current.strategy.formation_period_s == 7.5
    assert st.params.current.recording.max_mb == 512


def test_a_preset_carrying_an_unknown_path_is_refused(
        client: tuple[TestClient, Station], tmp_path: Path) -> None:
    c, st = client
    presets = tmp_path / "state" / "presets"
    presets.mkdir(parents=True)
    values = st.params.values()
    values["strategy"]["team_code_dir"] = "/tmp/their-code"
    (presets / "edited.json").write_text(json.dumps({"values": values}))
    v0 = st.params.version
    r = c.post("/api/presets/edited/load")
    _refused(r, ["strategy", "team_code_dir"], "set when the station starts")
    assert st.params.version == v0


def test_a_start_up_override_of_a_folder_parameter_is_refused(tmp_path: Path) -> None:
    """--set strategy.scripts_dir=... names the flag instead of starting half right."""
    settings = Settings(state_dir=tmp_path, set_params=["strategy.scripts_dir=/tmp/x"])
    with pytest.raises(ParamError, match=r"strategy\.scripts_dir: folders are set when the "
                                         r"station starts \(--scripts-dir"):
        Station(settings)


# ---- files from before ---------------------------------------------------------------------

def _old_state(tmp_path: Path) -> Path:
    state = tmp_path / "state"
    shutil.copytree(OLD_STATE, state)
    return state


def test_a_params_file_from_before_loads_without_the_folders(
        tmp_path: Path, caplog: pytest.LogCaptureFixture) -> None:
    state = _old_state(tmp_path)
    raw = json.loads((state / "params.json").read_text())["values"]
    assert raw["strategy"]["scripts_dir"] == "/home/team/octave"  # the old format indeed
    with caplog.at_level(logging.INFO, logger="touchline.params"):
        store = ParamStore(state)
    assert store.warnings == [] and store.version == 2
    values = store.values()
    assert "scripts_dir" not in values["strategy"] and "folder" not in values["recording"]
    # nothing else lost: every other value is the file's
    for group, fields in raw.items():
        for key, v in fields.items():
            if (group, key) not in (("strategy", "scripts_dir"), ("recording", "folder")):
                assert values[group][key] == v, f"{group}.{key}"
    assert values["strategy"]["formation_period_s"] == 7.5
    assert values["control"]["robots"]["blue/3"]["algorithm"] == "algorithm1"
    dropped = [r for r in caplog.records if "dropped" in r.getMessage()]
    assert len(dropped) == 1, [r.getMessage() for r in caplog.records]
    msg = dropped[0].getMessage()
    assert "strategy.scripts_dir='/home/team/octave' (now --scripts-dir)" in msg
    assert "recording.folder='/media/usb/logs' (now --record-dir)" in msg
    assert list(state.glob("params.invalid-*")) == []  # not set aside: it was usable


def test_a_preset_from_before_loads_without_the_folders(
        tmp_path: Path, caplog: pytest.LogCaptureFixture) -> None:
    state = _old_state(tmp_path)
    store = ParamStore(state)
    assert store.list_presets() == ["match day"]
    raw = json.loads((state / "presets" / "match day.json").read_text())["values"]
    assert "scripts_dir" in raw["strategy"]
    caplog.clear()
    with caplog.at_level(logging.INFO, logger="touchline.params"):
        store.load_preset("match day")
    assert [r.getMessage() for r in caplog.records if "dropped" in r.getMessage()] == [
        "preset 'match day': dropped strategy.scripts_dir='/home/team/octave' (now "
        "--scripts-dir), recording.folder='/media/usb/logs' (now --record-dir): folders are "
        "set when the station starts"]
    values = store.values()
    assert values["safety"]["vision_stale_s"] == raw["safety"]["vision_stale_s"] == 0.3
    assert values["strategy"]["formation_period_s"] == 7.5
    assert values["strategy"]["engine"] == "octave" and values["team"]["our_team"] == "yellow"


def test_the_page_sees_a_preset_from_before_without_the_folders(
        tmp_path: Path) -> None:
    state = _old_state(tmp_path)
    settings = Settings(relay_pub=f"tcp://127.0.0.1:{free_tcp_port()}",
                        relay_sub=f"tcp://127.0.0.1:{free_tcp_port()}", static_dir=tmp_path,
                        state_dir=state, allowed_hosts=["testserver"])
    with TestClient(create_app(settings), headers={"X-Touchline": "1"}) as c:
        d = c.get("/api/presets/match day").json()
        paths = {x["path"] for x in d["diff_from_defaults"]}
        assert "strategy.formation_period_s" in paths
        assert not {"strategy.scripts_dir", "recording.folder"} & paths
        assert c.post("/api/presets/match day/load").status_code == 200


# ---- the folders, set at start -------------------------------------------------------------

def test_the_folders_come_from_flags_then_environment_then_defaults(tmp_path: Path) -> None:
    env = {"TOUCHLINE_SCRIPTS_DIR": str(tmp_path / "s"), "TOUCHLINE_RECORD_DIR": "",
           "TOUCHLINE_LOG_DIRS": f"{tmp_path / 'a'}:{tmp_path / 'b'}",
           "TOUCHLINE_STATE_DIR": str(tmp_path / "st")}
    s = Settings.from_env(env)
    assert s.scripts_dir == tmp_path / "s" and s.state_dir == tmp_path / "st"
    assert s.log_dirs == [tmp_path / "a", tmp_path / "b"]
    assert s.record_dir is None and s.recording_folder() == tmp_path / "st" / "logs"
    # the command line wins
    s = Settings.from_env(env, scripts_dir=tmp_path / "flag")
    assert s.scripts_dir == tmp_path / "flag"
    d = Settings.from_env({})
    assert d.scripts_dir == ROOT / "engine_scripts" and d.state_dir == ROOT / "var"
    assert d.recording_folder() == ROOT / "var" / "logs"


def test_get_folders_answers_every_station_folder_read_only(
        client: tuple[TestClient, Station], tmp_path: Path) -> None:
    c, _ = client
    r = c.get("/api/folders")
    assert r.status_code == 200
    folders = {f["name"]: f for f in r.json()["folders"]}
    assert list(folders) == list(Settings.folder_fields())  # each declared folder, one line
    assert folders["scripts_dir"]["paths"] == [str(tmp_path / "scripts")]
    assert folders["scripts_dir"]["flag"] == "--scripts-dir"
    assert folders["scripts_dir"]["env"] == "TOUCHLINE_SCRIPTS_DIR"
    assert folders["record_dir"]["paths"] == [str(tmp_path / "rec")]
    assert folders["log_dirs"]["paths"] == [str(tmp_path / "more-logs")]
    assert folders["state_dir"]["paths"] == [str(tmp_path / "state")]
    # read-only: no route takes it
    assert c.post("/api/folders", json={}).status_code == 405
    assert c.patch("/api/folders", json={}).status_code == 405


async def test_the_octave_engine_runs_the_scripts_folder_set_at_start(tmp_path: Path) -> None:
    """The engine switch starts Octave on the folder given when the station started."""
    if shutil.which("octave-cli") is None:
        pytest.skip("GNU Octave is not installed")
    from backend.bus import DataBus
    from backend.processors import StrategyProcessor

    scripts = tmp_path / "team scripts"
    shutil.copytree(ROOT / "engine_scripts", scripts)
    strategy = StrategyProcessor(DataBus(), "blue", StrategyParams())
    switch = EngineSwitch(strategy, scripts)
    switch.configure(StrategyParams(engine="octave", engine_timeout_s=2.0))
    try:
        for task in list(switch._tasks):
            await task
        assert switch.error == "" and strategy.engine is not None
        assert getattr(strategy.engine, "scripts_dir", None) == scripts.resolve()
    finally:
        await switch.close()
