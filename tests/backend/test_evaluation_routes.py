"""The Evaluate tab's routes on a real station: a job on a real process pool, its progress in
health, the report, its page, a run's log into the player; names only from the web."""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest
from fastapi.testclient import TestClient

from backend.api import create_app
from backend.config import Settings
from backend.station import Station
from launcher.supervisor import free_tcp_port
from tests.waiting import wait_until

QUICK = Path(__file__).resolve().parents[1] / "evaluate" / "quick"
pytestmark = pytest.mark.timeout(240)


@pytest.fixture
def client(tmp_path: Path) -> Iterator[tuple[TestClient, Station]]:
    settings = Settings(relay_pub=f"tcp://127.0.0.1:{free_tcp_port()}",
                        relay_sub=f"tcp://127.0.0.1:{free_tcp_port()}", static_dir=tmp_path,
                        state_dir=None, record_dir=tmp_path / "rec",
                        reports_dir=tmp_path / "reports", suite_dirs=[QUICK],
                        allowed_hosts=["testserver"], eval_workers=2)
    st = Station(settings)
    with TestClient(create_app(settings, st), headers={"X-Touchline": "1"}) as c:
        yield c, st


def _wait_job(c: TestClient, state: str = "done", timeout_s: float = 180.0) -> dict[str, Any]:
    def ended() -> dict[str, Any] | None:
        job: dict[str, Any] = c.get("/api/evaluate").json()["job"]
        assert job["state"] in ("running", state), job
        return job if job["state"] == state else None

    found: dict[str, Any] = wait_until(ended, timeout_s, 0.2, f"the job {state}")
    return found


def _wait_log(c: TestClient) -> dict[str, Any]:
    """The player on the log (it indexes it in a worker first)."""
    def opened() -> dict[str, Any] | None:
        p: dict[str, Any] = c.get("/api/player").json()
        assert not p["error"], p["error"]
        return p if p["source"] == "log" else None

    found: dict[str, Any] = wait_until(opened, 60, 0.1, "the log in the player")
    return found


def test_a_suite_runs_and_a_failed_run_opens_in_the_player(
        client: tuple[TestClient, Station], tmp_path: Path) -> None:
    c, _ = client
    view = c.get("/api/evaluate").json()
    assert view["available"] and view["job"]["state"] == "idle" and view["reports"] == []
    suites = {s["name"]: s for s in view["suites"]}
    assert {"exercises", "regression", "quick"} <= set(suites)
    assert {s["name"] for s in suites["quick"]["scenarios"]} == {"quick_goal", "quick_keeper"}
    r = c.post("/api/evaluate", json={"action": "start", "suite": "quick"})
    assert r.status_code == 200, r.text
    assert r.json()["state"] == "running" and r.json()["total"] == 3
    again = c.post("/api/evaluate", json={"action": "start", "suite": "quick"})
    assert again.status_code == 409 and "a job runs" in again.json()["detail"]
    job = _wait_job(c)
    assert (job["done"], job["total"], job["passed"] + job["failed"]) == (3, 3, 3)
    assert c.get("/api/health").json()["evaluation"]["id"] == job["id"]
    reports = c.get("/api/evaluate").json()["reports"]
    assert [x["name"] for x in reports] == [job["report"]] and reports[0]["runs"] == 3
    rep = c.get(f"/api/evaluate/reports/{job['report']}").json()
    runs = {x["id"]: x for x in rep["runs"]}
    assert set(runs) == {"quick_goal", "quick_keeper#1", "quick_keeper#2"}
    failed = runs["quick_goal"]
    assert not failed["passed"] and failed["replay"]
    assert {ch["name"]: ch["passed"] for ch in failed["checks"]} == {
        "ball_in_goal": True, "no_collision": False, "no_violation": False}
    assert failed["team_error"] == ""  # built-in plays: no team code to fail
    page = c.get(f"/api/evaluate/reports/{job['report']}/html")
    assert page.status_code == 200 and "default-src 'none'" in \
        page.headers["content-security-policy"] and "quick_goal" in page.text
    r = c.post("/api/evaluate/replay", json={"report": job["report"], "run": "quick_goal"})
    assert r.status_code == 200, r.text
    p = _wait_log(c)
    assert p["file"].endswith("quick_goal.log")
    assert Path(p["file"]).is_relative_to(tmp_path / "reports")


def test_names_only_and_clear_refusals(client: tuple[TestClient, Station]) -> None:
    c, _ = client
    bad = c.post("/api/evaluate", json={"action": "start", "suite": "../etc"})
    assert bad.status_code == 422
    assert c.post("/api/evaluate", json={"action": "start", "suite": "nosuch"}).status_code \
        == 404
    assert c.post("/api/evaluate", json={"action": "cancel"}).status_code == 409
    assert c.post("/api/evaluate", json={"action": "start", "kind": "class",
                                         "suite": "quick"}).status_code == 409  # no class
    assert c.get("/api/evaluate/reports/nosuch").status_code == 404
    assert c.get("/api/evaluate/reports/..%2F..%2Fetc").status_code in (404, 422)
    r = c.post("/api/evaluate/replay", json={"report": "x", "run": "/etc/passwd"})
    assert r.status_code == 422
    r = c.post("/api/evaluate/replay", json={"report": "nosuch", "run": "a"})
    assert r.status_code == 404


def test_an_ab_report_from_the_cli_names_each_side_s_runs(
        client: tuple[TestClient, Station], tmp_path: Path) -> None:
    """An A/B of two plays on a suite, written into the reports folder as python -m evaluate
    does: listed, its verdict, each side's run by its own id (both sides run every scenario
    under the same name), B's failed run opened in the player."""
    from evaluate.jobs import run_ab_suite
    from evaluate.pool import LocalPool
    from evaluate.runner import Entrant
    from evaluate.scenario import load_suite

    c, _ = client
    run_ab_suite(load_suite(str(QUICK)), Entrant("match", label="A:match"),
                 Entrant("simple", label="B:simple"), tmp_path / "reports" / "ab-quick",
                 LocalPool(2))
    [info] = c.get("/api/evaluate").json()["reports"]
    assert info["name"] == "ab-quick" and info["kind"] == "ab-suite" and info["runs"] == 6
    rep = c.get("/api/evaluate/reports/ab-quick").json()
    assert "A:match minus B:simple (pass rates)" in rep["verdict"]
    ids = [r["id"] for r in rep["runs"]]
    assert sorted(ids) == sorted(f"{side}-{n}" for side in "AB"
                                 for n in ("quick_goal", "quick_keeper#1", "quick_keeper#2"))
    r = c.post("/api/evaluate/replay", json={"report": "ab-quick", "run": "B-quick_goal"})
    assert r.status_code == 200, r.text
    p = _wait_log(c)
    assert p["file"].endswith("B-quick_goal.log")
