"""`python -m match` for real: fieldsim, relay and two backends on isolated ports, real
ZeroMQ and multicast, the director in between. These run in `make test` (bounded: a 0.5 min
match takes about 2-3 minutes on a 2-core machine). The assertions do not depend on how well
the strategies play."""

from __future__ import annotations

import csv
import json
import os
import signal
import subprocess
import sys
import threading
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import httpx
import pytest

from match.stats import VIOLATION_KINDS
from sslnet.multicast import loopback_multicast_ok

ROOT = Path(__file__).resolve().parents[2]
MATCH_BOUND_S = 420.0  # the 0.5 min match must end (and tear down) within this

pytestmark = [
    pytest.mark.match,
    pytest.mark.timeout(900),
    pytest.mark.skipif(not loopback_multicast_ok(), reason="multicast on loopback is not set up"),
]


class MatchProcess:
    """`python -m match ...` with its stdout read line by line on a thread."""

    def __init__(self, *args: str) -> None:
        self.proc = subprocess.Popen(
            [sys.executable, "-m", "match", *args], cwd=ROOT, stdout=subprocess.PIPE,
            stderr=subprocess.STDOUT, text=True, env={**os.environ, "PYTHONUNBUFFERED": "1"})
        self.lines: list[str] = []
        self.info: dict[str, Any] = {}
        self._thread = threading.Thread(target=self._pump, daemon=True)
        self._thread.start()

    def _pump(self) -> None:
        assert self.proc.stdout is not None
        for line in self.proc.stdout:
            line = line.rstrip("\n")
            self.lines.append(line)
            for key in ("MATCH_PORTS", "MATCH_PIDS"):
                if line.startswith(key + " "):
                    self.info[key] = json.loads(line.split(" ", 1)[1])
            if line == "MATCH_STARTED":
                self.info["started"] = True

    def wait_for(self, cond: Callable[[], Any], timeout_s: float, what: str) -> Any:
        deadline = time.monotonic() + timeout_s
        while time.monotonic() < deadline:
            value = cond()
            if value:
                return value
            if self.proc.poll() is not None and not cond():
                break
            time.sleep(0.1)
        raise AssertionError(f"{what}: not within {timeout_s} s; output:\n" +
                             "\n".join(self.lines[-40:]))

    def finish(self, timeout_s: float) -> int:
        try:
            return self.proc.wait(timeout=timeout_s)
        except subprocess.TimeoutExpired:
            self.proc.kill()
            self.proc.wait()
            raise
        finally:
            self._thread.join(5)

    def kill(self) -> None:
        if self.proc.poll() is None:
            self.proc.kill()
            self.proc.wait()


def _pid_gone(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return True
    # still there: a zombie not reaped by anyone would also show up here
    return False


def _world(port: int) -> dict[str, Any] | None:
    try:
        r = httpx.get(f"http://127.0.0.1:{port}/api/world", timeout=3.0)
        return r.json() if r.status_code == 200 else None
    except httpx.HTTPError:
        return None


def _serving(port: int) -> bool:
    try:
        return httpx.get(f"http://127.0.0.1:{port}/api/health", timeout=5.0).status_code == 200
    except httpx.HTTPError:
        return False


def test_a_short_match_runs_to_the_end_with_the_director_as_referee(tmp_path: Path) -> None:
    out = tmp_path / "out"
    m = MatchProcess("--minutes", "0.5", "--seed", "3", "--out", str(out))
    try:
        m.wait_for(lambda: m.info.get("started"), 150, "match started")
        http = m.info["MATCH_PORTS"]["http"]
        pids = m.info["MATCH_PIDS"]
        assert set(pids) == {"fieldsim", "relay", "backend-blue", "backend-yellow"}
        # the director's Referee multicast reaches both backends through the relay
        seen: dict[str, dict[str, Any]] = {}

        def referee_everywhere() -> bool:
            for team, port in http.items():
                w = _world(port)
                ref = (w or {}).get("referee")
                if ref and ref["source_identifier"].startswith("touchline-match-"):
                    seen[team] = ref
            return len(seen) == 2

        m.wait_for(referee_everywhere, 30, "both backends hearing the director")
        for ref in seen.values():
            assert ref["source"] == "game-controller"  # a foreign referee for the backends
            assert ref["command"] in ("HALT", "STOP", "PREPARE_KICKOFF_BLUE", "NORMAL_START",
                                      "FORCE_START")
        assert seen["blue"]["source_identifier"] == seen["yellow"]["source_identifier"]
        # both backends keep serving while the match is played (the runner also watches them)
        checks = 0
        while m.proc.poll() is None and checks < 5:
            assert all(_serving(p) for p in http.values()) or m.proc.poll() is not None
            checks += 1
            time.sleep(2.0)
        code = m.finish(MATCH_BOUND_S)
    finally:
        m.kill()
    assert code == 0, "\n".join(m.lines[-60:])
    # every child is gone after the teardown
    assert all(_pid_gone(pid) for pid in pids.values()), pids

    res = json.loads((out / "result.json").read_text())
    assert res["finished"] is True and res["exit_code"] == 0 and res["stage"] == "POST_GAME"
    assert all(p["alive_throughout"] for p in res["processes"].values())
    assert set(res["processes"]) == set(pids)
    assert res["truth_frames"] > 1000 and res["referee"]["sent"] > 100
    for team in ("blue", "yellow"):
        t = res["teams"][team]
        assert set(t) >= {"play", "goals", "possession_pct", "possession_s", "kicks",
                          "placements", "violations"}
        assert set(t["placements"]) == {"ok", "failed", "mean_time_s", "times_s"}
        assert set(t["violations"]) == set(VIOLATION_KINDS)
        assert all(set(v) == {"count", "seconds"} for v in t["violations"].values())
    assert res["teams"]["blue"]["play"] == "match" and res["teams"]["yellow"]["play"] == "simple"
    assert res["score"] == {t: res["teams"][t]["goals"] for t in ("blue", "yellow")}
    # the start sequence, then every scripted command (exercised in every match)
    with (out / "events.csv").open() as f:
        commands = [row["detail"] for row in csv.DictReader(f) if row["kind"] == "command"]
    assert [c.split()[0] for c in commands[:4]] == [
        "HALT", "STOP", "PREPARE_KICKOFF_BLUE", "NORMAL_START"]
    for c in ("TIMEOUT_BLUE", "TIMEOUT_YELLOW", "PREPARE_PENALTY_BLUE", "PREPARE_PENALTY_YELLOW",
              "DIRECT_FREE_BLUE", "DIRECT_FREE_YELLOW", "BALL_PLACEMENT_BLUE",
              "BALL_PLACEMENT_YELLOW", "PREPARE_KICKOFF_YELLOW", "FORCE_START"):
        assert res["commands"][c]["count"] >= 1, c
    assert all(res["interludes"].values())
    # the printed table
    text = "\n".join(m.lines)
    assert "Touchline match: blue (match)" in text and "-- finished" in text
    assert any(line.startswith("violations (episodes, robot-seconds)") for line in m.lines)


def test_ctrl_c_tears_everything_down() -> None:
    m = MatchProcess("--minutes", "3")
    try:
        m.wait_for(lambda: m.info.get("started"), 150, "match started")
        pids = m.info["MATCH_PIDS"]
        assert all(not _pid_gone(p) for p in pids.values())
        m.proc.send_signal(signal.SIGINT)
        code = m.finish(60)
    finally:
        m.kill()
    assert code == 130, "\n".join(m.lines[-40:])
    assert all(_pid_gone(pid) for pid in pids.values()), pids
    assert "NOT FINISHED (interrupted by SIGINT)" in "\n".join(m.lines)


def test_a_process_that_fails_to_start_gives_a_non_zero_exit_and_no_orphans() -> None:
    m = MatchProcess("--minutes", "0.5", "--backend-arg=--no-such-flag", "--startup-timeout",
                     "60")
    try:
        code = m.finish(120)
    finally:
        m.kill()
    assert code == 2, "\n".join(m.lines[-40:])
    text = "\n".join(m.lines)
    assert "match could not start" in text and "backend-" in text
    pids = m.info["MATCH_PIDS"]
    assert all(_pid_gone(pid) for pid in pids.values()), pids
