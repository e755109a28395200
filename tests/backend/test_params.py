import json
import math
import os
from pathlib import Path

import pytest

from backend.params.model import StationParams
from backend.params.store import ParamError, ParamStore


def _leaves(schema: dict, node: dict, path: str = "") -> list[tuple[str, dict]]:  # type: ignore[type-arg]
    out = []
    if "$ref" in node:
        node = schema["$defs"][node["$ref"].split("/")[-1]]
    for name, prop in node.get("properties", {}).items():
        if "$ref" in prop or "properties" in prop:
            out += _leaves(schema, prop, f"{path}{name}.")
        else:
            out.append((f"{path}{name}", prop))
    return out


def test_every_number_has_range_unit_step_and_description() -> None:
    schema = StationParams.model_json_schema()
    leaves = _leaves(schema, schema)
    assert len(leaves) > 20
    for path, prop in leaves:
        assert prop.get("description"), path
        if prop.get("type") in ("number", "integer"):
            assert "minimum" in prop and "maximum" in prop, path
            assert "unit" in prop and "step" in prop, path


def test_patch_is_validated_applied_versioned_and_persisted(tmp_path: Path) -> None:
    store = ParamStore(tmp_path)
    seen: list[int] = []
    store.subscribe(lambda p, v: seen.append(v))
    store.patch({"strategy": {"formation_period_s": 3.5}})
    assert store.current.strategy.formation_period_s == 3.5 and store.version == 1 and seen == [1]
    on_disk = json.loads((tmp_path / "params.json").read_text())
    assert on_disk["version"] == 1 and on_disk["values"]["strategy"]["formation_period_s"] == 3.5
    again = ParamStore(tmp_path)  # a restart
    assert again.current.strategy.formation_period_s == 3.5 and again.version == 1


@pytest.mark.parametrize("change,loc", [
    ({"strategy": {"formation_period_s": math.nan}}, ["body", "strategy", "formation_period_s"]),
    ({"strategy": {"formation_period_s": math.inf}}, ["body", "strategy", "formation_period_s"]),
    ({"strategy": {"formation_period_s": 99}}, ["body", "strategy", "formation_period_s"]),
    ({"control": {"default_algorithm": "fast"}}, ["body", "control", "default_algorithm"]),
    ({"team": {"our_team": "green"}}, ["body", "team", "our_team"]),
    ({"world": {"no_such": 1}}, ["body", "world", "no_such"]),
])
def test_bad_changes_are_refused_whole(tmp_path: Path, change: dict, loc: list) -> None:  # type: ignore[type-arg]
    store = ParamStore(tmp_path)
    store.patch({"processors": {"strategy_hz": 10}})
    before = (tmp_path / "params.json").read_text()
    # a good field next to a bad one: neither is applied
    with pytest.raises(ParamError) as exc:
        store.patch({**change, "processors": {"control_max_wait_s": 0.02}})
    assert any(e["loc"] == loc for e in exc.value.errors), exc.value.errors
    assert all(e["msg"] for e in exc.value.errors)
    assert store.version == 1 and store.current.processors.control_max_wait_s == 0.05
    assert (tmp_path / "params.json").read_text() == before


def test_a_crash_while_writing_leaves_the_old_file(tmp_path: Path, monkeypatch) -> None:  # type: ignore[no-untyped-def]
    store = ParamStore(tmp_path)
    store.patch({"strategy": {"formation_period_s": 1.0}})
    good = (tmp_path / "params.json").read_text()

    def boom(src: str, dst: str) -> None:
        raise OSError("disk gone")

    monkeypatch.setattr(os, "replace", boom)
    with pytest.raises(OSError):
        store.patch({"strategy": {"formation_period_s": 2.0}})
    monkeypatch.undo()
    assert (tmp_path / "params.json").read_text() == good
    assert not [p for p in tmp_path.iterdir() if p.name.endswith(".tmp")]
    assert ParamStore(tmp_path).current.strategy.formation_period_s == 1.0


def test_corrupt_file_falls_back_to_defaults_and_is_kept(tmp_path: Path) -> None:
    (tmp_path / "params.json").write_text(
        '{"version": 3, "values": {"strategy": {"formation_period_s": -5}}}')
    store = ParamStore(tmp_path)
    assert store.current == StationParams()
    assert len(list(tmp_path.glob("params.invalid-*.json"))) == 1


def test_presets_save_load_diff_delete(tmp_path: Path) -> None:
    store = ParamStore(tmp_path)
    store.patch({"strategy": {"formation_period_s": 4.0}})
    store.save_preset("fast robots")
    store.patch({"strategy": {"formation_period_s": 1.0}})
    assert store.list_presets() == ["fast robots"]
    store.load_preset("fast robots")
    assert store.current.strategy.formation_period_s == 4.0
    assert store.diff_from_defaults() == [
        {"path": "strategy.formation_period_s", "from": 5.0, "to": 4.0}]
    store.delete_preset("fast robots")
    assert store.list_presets() == []
    with pytest.raises(ParamError):
        store.save_preset("../escape")
    with pytest.raises(KeyError):
        store.load_preset("missing")


def test_import_fills_missing_keys_with_defaults(tmp_path: Path) -> None:
    store = ParamStore(tmp_path)
    store.patch({"strategy": {"formation_period_s": 4.0}, "world": {"merge_window_s": 0.002}})
    store.replace({"strategy": {"formation_period_s": 3.0}})
    assert store.current.strategy.formation_period_s == 3.0
    assert store.current.world.merge_window_s == 0.005


def test_groups_of_an_older_version_are_dropped_on_load(tmp_path: Path) -> None:
    (tmp_path / "params.json").write_text(json.dumps({"version": 4, "values": {
        "goto": {"kp_per_s": 3.0}, "team": {"demo": False, "our_team": "yellow"},
        "strategy": {"formation_period_s": 9.0}}}))
    store = ParamStore(tmp_path)
    assert store.current.strategy.formation_period_s == 9.0 and store.version == 4
    assert store.current.team.our_team == "yellow"  # a removed key does not lose the group


def test_null_removes_a_per_robot_override(tmp_path: Path) -> None:
    store = ParamStore(tmp_path)
    store.patch({"control": {"robots": {"blue/3": {"algorithm": "algorithm1"}}},
                 "filters": {"robot_overrides": {"blue/3": "paper"}}})
    assert store.current.control.algorithm_for("blue", 3) == "algorithm1"
    assert store.current.filters.robot_kind("blue", 3) == "paper"
    store.patch({"control": {"robots": {"blue/3": None}},
                 "filters": {"robot_overrides": {"blue/3": None}}})
    assert store.current.control.robots == {} and store.current.filters.robot_overrides == {}


# ---- start-up with whatever the state folder holds ------------------------------------------

from tests.backend.params_startup_cases import BAD_FILES, write_bad  # noqa: E402


@pytest.mark.parametrize("name,content", BAD_FILES, ids=[n for n, _ in BAD_FILES])
def test_a_bad_params_file_leaves_defaults_a_warning_and_the_file_set_aside(
        tmp_path, name: str, content: bytes | None) -> None:  # type: ignore[no-untyped-def]
    f = write_bad(tmp_path, content)
    store = ParamStore(tmp_path)
    assert store.current == StationParams() and store.version == 0, "defaults, nothing of the file"
    assert len(store.warnings) == 1 and "default parameters in use" in store.warnings[0]
    assert not f.exists()
    aside = list(tmp_path.glob("params.invalid-*.json"))
    assert len(aside) == 1, "set aside, never deleted"
    # the station keeps working: a change is stored as a fresh file
    store.patch({"safety": {"stop_speed_mps": 1.0}})
    assert ParamStore(tmp_path).current.safety.stop_speed_mps == 1.0


def test_a_bad_preset_file_is_a_422_not_a_crash(tmp_path) -> None:  # type: ignore[no-untyped-def]
    store = ParamStore(tmp_path)
    (tmp_path / "presets").mkdir()
    (tmp_path / "presets" / "junk.json").write_bytes(b"\xff[[")
    with pytest.raises(ParamError):
        store.read_preset("junk")
