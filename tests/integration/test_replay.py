"""Record and replay through the real processes: a live session (fieldsim, relay, backend)
records into its folder; the file is a real SSL log with the expected messages; the station
replays it (nothing sent to robots meanwhile), seeks, steps, jumps, and goes back to live."""

from __future__ import annotations

import json
import math
from collections import Counter
from pathlib import Path
from typing import Any

import httpx

from ssllog.reader import LogReader
from ssllog.seek import read_index

from .conftest import StationHandle, launched, wait_until

JSON = {"content-type": "application/json"}


def post(st: StationHandle, path: str, body: dict[str, Any]) -> httpx.Response:
    return httpx.post(st.url + path, json=body, headers=JSON, timeout=10.0)


def player(st: StationHandle, body: dict[str, Any]) -> dict[str, Any]:
    r = post(st, "/api/player", body)
    assert r.status_code == 200, r.text
    return r.json()  # type: ignore[no-any-return]


def test_a_live_session_is_recorded_and_replays(tmp_path: Path) -> None:
    logs = tmp_path / "logs"
    with launched("--record-dir", str(logs),
                  "--backend-arg=--set=recording.rotate_on_stage=false") as st:
        wait_until(lambda: len(st.get("/api/world")["robots"]) >= 6, 20, what="robots")
        rec = st.get("/api/health")["recording"]
        assert rec["enabled"] and rec["recording"] and rec["folder"] == str(logs)
        # a fresh file for this test, then operator actions in it; the answer names the new
        # file (it named the one just closed)
        r = post(st, "/api/recording", {"action": "new-file"})
        assert r.status_code == 200 and r.json()["file"] not in ("", rec["file"]), r.json()
        wait_until(lambda: st.get("/api/health")["recording"]["file"] != rec["file"], 10,
                   what="a new file")
        for cmd in ("STOP", "FORCE_START"):
            assert post(st, "/api/referee/internal/command", {"command": cmd}).status_code \
                == 200
            wait_until(lambda c=cmd: (st.get("/api/world")["referee"] or {}).get("command")
                       == c, 10, what=cmd)
        assert post(st, "/api/robots/blue/1/target", {"x": 500, "y": 500}).status_code == 200
        wait_until(lambda: st.get("/api/health")["recording"]["duration_s"] > 2.5, 20,
                   what="2.5 s recorded")
        name = st.get("/api/health")["recording"]["file"]
        assert post(st, "/api/recording", {"action": "new-file"}).status_code == 200
        wait_until(lambda: st.get("/api/health")["recording"]["file"] != name, 10,
                   what="the file finished")
        path = logs / name

        # a real SSL log: the league's types, bytes unchanged, and Touchline's own records
        wait_until(lambda: read_index(str(path)) is not None, 10, what="the index record")
        reader = LogReader(str(path))
        records = list(reader)
        counts = Counter(r.type for r in records)
        assert reader.warning is None and not reader.unknown_types
        # tracked vision at most tracker.max_hz (100) for the ~2.5 s
        assert counts[4] > 100 and counts[3] > 20 and counts[5] > 50, counts
        assert counts[1001] > 100 and counts[1004] >= 2, counts
        # the operator's actions with who: two referee commands, and the target, which took
        # driving our team first (backend/operators.py)
        actions = [json.loads(r.payload)["action"] for r in records if r.type == 1003]
        assert actions == ["referee", "referee", "driving-taken", "target"], actions
        assert counts[1005] == 1, counts
        listed = {f["name"] for f in st.get("/api/logs")["files"]}
        assert name in listed

        # replay it from the page's API
        opened = player(st, {"action": "open", "path": str(path)})
        assert opened["loading"] is not None or opened["source"] == "log"
        p = wait_until(lambda: (lambda v: v if v["source"] == "log" else None)(
            st.get("/api/player")), 20, what="the log open")
        assert p["duration_s"] > 2.5 and not p["playing"]
        assert {"STOP", "FORCE_START"} <= {e["label"] for e in p["events"]
                                           if e["kind"] == "command"}
        assert sum(e["kind"] == "operator" for e in p["events"]) == len(actions)
        # nothing goes to robots while replaying: the relay's table empties
        wait_until(lambda: (st.get("/api/health")["relay"] or {}).get("active_robots") == 0,
                   5, what="no robot commanded by the relay")
        r = post(st, "/api/sim/ball", {"x": 0, "y": 0})
        assert r.status_code == 409 and "replaying" in r.text

        # seek: the robots are where the log has them (its own recorded estimate)
        mid = round(p["duration_s"] * 0.6, 3)
        player(st, {"action": "seek", "position_s": mid})
        w = wait_until(lambda: (lambda w: w if w["replay"] and w["recorded"] and w["robots"]
                                and abs(w["replay"]["position_s"] - mid) < 1e-3 else None)(
            st.get("/api/world")), 10, what="the world at the seek")
        rec_robots = {(r["team"], r["id"]): r for r in w["recorded"]["robots"]}
        for rb in w["robots"]:
            ref = rec_robots.get((rb["team"], rb["id"]))
            if ref is not None and rb["visible"]:
                assert math.hypot(rb["x"] - ref["x"], rb["y"] - ref["y"]) < 30, (rb, ref)
        assert w["halt_reason"] in ("", "HALT") or "vision" not in w["halt_reason"], w[
            "halt_reason"]

        # the plots' past before the playhead, on the log's clock
        h = st.get("/api/player/history?seconds=1")
        assert h["epoch"] == st.get("/api/player")["epoch"] and len(h["samples"]) >= 20
        assert h["samples"][-1]["t_unix"] <= w["replay"]["t_unix"] + 1e-6
        assert h["samples"][-1]["world"]["robots"]
        assert httpx.get(st.url + "/api/player/history?seconds=0", timeout=5).status_code == 422

        # step one camera frame forward and back
        here = st.get("/api/player")["position_s"]
        after = player(st, {"action": "step", "frames": 1})["position_s"]
        after = wait_until(lambda: st.get("/api/player")["position_s"] > here, 5,
                           what="a step forward") and st.get("/api/player")["position_s"]
        assert 0 < after - here <= 0.02
        player(st, {"action": "step", "frames": -1})
        back = wait_until(lambda: (lambda v: v if v < after else None)(
            st.get("/api/player")["position_s"]), 5, what="a step back")
        assert 0 < after - back <= 0.02

        # jump back to the previous command, then play fast to the end
        t_cmd = player(st, {"action": "jump", "kind": "command", "direction": "prev"})
        assert t_cmd["position_s"] < mid
        r = post(st, "/api/player", {"action": "play", "speed": 50})
        assert r.status_code == 422 and "speed" in r.text
        player(st, {"action": "play", "speed": 0})
        end = wait_until(lambda: (lambda v: v if not v["playing"] else None)(
            st.get("/api/player")), 20, what="the end of the log")
        assert end["position_s"] == end["duration_s"]

        # back to live: the world follows the simulator again and commands flow
        player(st, {"action": "live"})
        wait_until(lambda: st.get("/api/world")["replay"] is None and len(
            st.get("/api/world")["robots"]) >= 6, 10, what="live again")
        wait_until(lambda: (st.get("/api/health")["relay"] or {}).get("active_robots", 0) > 0,
                   10, what="commands to the robots again")


def test_player_refuses_what_it_cannot_do(station: StationHandle) -> None:
    """Live, with nothing open: a clear reason, never a 500."""
    r = post(station, "/api/player", {"action": "play", "speed": 1})
    assert r.status_code == 409 and "no log is open" in r.text
    r = post(station, "/api/player", {"action": "open", "path": "/etc/passwd"})
    assert r.status_code == 422 and "not in a log folder" in r.text
    r = httpx.post(station.url + "/api/player", headers=JSON, timeout=10.0,
                   content=b'{"action": "seek", "position_s": NaN}')
    assert r.status_code == 422
    r = post(station, "/api/player", {"action": "fly"})
    assert r.status_code == 422
    assert station.get("/api/player")["source"] == "live"


def test_a_full_disk_stops_recording_and_the_station_goes_on(tmp_path: Path) -> None:
    """The recording folder on a 256 KiB file system (a real ENOSPC from the kernel): the
    recorder stops with the reason in health (a warning line and Health.recording.error);
    the loop keeps running and commanding robots."""
    import os
    import subprocess

    if os.geteuid() != 0:
        import pytest

        pytest.skip("mounting a small tmpfs needs root (make test and CI run as root)")
    disk = tmp_path / "small"
    disk.mkdir()
    subprocess.run(["mount", "-t", "tmpfs", "-o", "size=256k", "tmpfs", str(disk)], check=True)
    try:
        with launched("--record-dir", str(disk)) as st:
            h = wait_until(lambda: (lambda h: h if h["recording"]["error"] else None)(
                st.get("/api/health")), 30, what="the recorder's disk-full error")
            assert "disk full" in h["recording"]["error"] and not h["recording"]["recording"]
            assert any(w.startswith("recording stopped: disk full") for w in h["warnings"])
            seq = st.get("/api/world")["seq"]
            wait_until(lambda: st.get("/api/world")["seq"] > seq + 10, 10,
                       what="the world going on")
            wait_until(lambda: (st.get("/api/health")["relay"] or {}).get(
                "active_robots", 0) > 0, 10, what="robots commanded")
            assert st.get("/api/health")["ok"]
    finally:
        subprocess.run(["umount", "-l", str(disk)], check=False)


def test_make_run_log_opens_the_station_on_a_log() -> None:
    """`make run LOG=...` (launcher --log): no simulator, the log open from the start, no
    recording, and nothing to robots."""
    fixture = Path(__file__).resolve().parents[1] / "data" / "fieldsim-2s.log.gz"
    with launched("--log", str(fixture)) as st:
        assert "fieldsim" not in st.pids and {"relay", "backend"} <= set(st.pids)
        p = wait_until(lambda: (lambda v: v if v["source"] == "log" else None)(
            st.get("/api/player")), 20, what="the log open")
        assert p["file"] == str(fixture) and p["duration_s"] > 2.5
        h = st.get("/api/health")
        assert not h["recording"]["enabled"] and not h["recording"]["recording"]
        assert any(w.startswith("replaying ") for w in h["warnings"])
        player(st, {"action": "play", "speed": 0})
        wait_until(lambda: not st.get("/api/player")["playing"], 20, what="played to the end")
        assert (st.get("/api/health")["relay"] or {}).get("active_robots", 0) == 0


def _commands_at(fixture: Path, t_ns: int, ttl_ns: int) -> list[dict[str, Any]]:
    """The commands the log sent each robot at ``t_ns``, read straight from the file: the
    newest of each robot not older than the relay's command timeout (zero after a stop_all)."""
    from sslpb import touchline_pb2 as tl

    latest: dict[tuple[int, int], tuple[int, Any]] = {}
    for rec in LogReader(str(fixture)):
        if rec.time_ns > t_ns:
            break
        if rec.type != 1001:
            continue
        cs = tl.RobotCommandSet.FromString(rec.payload)
        if cs.stop_all:
            latest = {k: (rec.time_ns, tl.RobotCommand(team=k[0], id=k[1])) for k in latest}
        for c in cs.commands:
            latest[(c.team, c.id)] = (rec.time_ns, c)
    out = [{"team": "blue" if team == tl.TEAM_BLUE else "yellow", "id": rid,
            "forward_mps": c.forward_mps, "left_mps": c.left_mps,
            "angular_radps": c.angular_radps, "kick_speed_mps": c.kick_speed_mps,
            "chip": c.chip, "dribbler_rpm": c.dribbler_rpm}
           for (team, rid), (t, c) in latest.items() if t_ns - t <= ttl_ns]
    return sorted(out, key=lambda c: (c["team"], c["id"]))


def test_a_replay_shows_the_commands_the_log_sent() -> None:
    """What-if: beside the commands the station computes on a replay, the page gets the ones
    the live station sent at that moment (type 1001 records): at a seek, exactly the newest
    the log holds for each robot up to the playhead."""
    from backend.replay.control import RECORDED_COMMAND_TTL_S
    from larcmacs_relay.config import RelayConfig

    # the relay's own default: a robot sent nothing newer was being sent zero
    assert RelayConfig().command_timeout_s == RECORDED_COMMAND_TTL_S
    fixture = Path(__file__).resolve().parents[1] / "data" / "fieldsim-2s.log.gz"
    t_first = next(iter(LogReader(str(fixture)))).time_ns
    times = [r.time_ns for r in LogReader(str(fixture)) if r.type == 1001]
    ttl = round(RECORDED_COMMAND_TTL_S * 1e9)
    # a playhead no record is within 1 ms of (either side of it, or of its timeout), so a
    # float's rounding of the position cannot change which commands count
    pos_s = next(p / 100 for p in range(200, 240)
                 if all(abs(t - (t_first + p * 10_000_000)) > 1_000_000
                        and abs(t - (t_first + p * 10_000_000 - ttl)) > 1_000_000
                        for t in times))
    expected = _commands_at(fixture, t_first + round(pos_s * 1e9), ttl)
    assert len(expected) >= 6 and any(c["forward_mps"] != 0 for c in expected)
    with launched("--log", str(fixture)) as st:
        wait_until(lambda: st.get("/api/player")["source"] == "log", 20, what="the log open")
        player(st, {"action": "seek", "position_s": pos_s})

        ages: list[float] = []

        def at_seek() -> list[dict[str, Any]] | None:
            w = st.get("/api/world")
            if not (w["replay"] and abs(w["replay"]["position_s"] - pos_s) < 1e-6
                    and w["recorded"]):
                return None
            got: list[dict[str, Any]] = w["recorded"]["commands"]
            ages[:] = [c.pop("age_s") for c in got]
            return got if got == expected else None
        # (the pre-roll comes a batch at a time: equal once the feed caught up)
        wait_until(at_seek, 10, what=f"the recorded commands at the seek: {expected}")
        assert all(0 <= a <= RECORDED_COMMAND_TTL_S for a in ages)
        # back to live: no recorded anything
        player(st, {"action": "live"})
        wait_until(lambda: st.get("/api/world")["recorded"] is None, 10, what="live again")
