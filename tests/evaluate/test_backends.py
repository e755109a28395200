"""The local pool and a real two-worker Dask cluster (a scheduler and two workers started
here, on loopback) give the same report for the same seeds, logs and all."""

from __future__ import annotations

import json
import os
import re
import subprocess
import sys
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest

from evaluate.jobs import run_suite
from evaluate.pool import DaskCluster, LocalPool
from evaluate.runner import Entrant
from evaluate.scenario import load_suite
from evaluate.series import strip_volatile
from tests.waiting import wait_until

ROOT = Path(__file__).resolve().parents[2]
DATA = Path(__file__).parent / "quick"
pytestmark = pytest.mark.timeout(240)


@pytest.fixture(scope="module")
def cluster(tmp_path_factory: pytest.TempPathFactory) -> Iterator[str]:
    """``dask scheduler`` and two ``dask worker`` processes (each under its nanny, which
    starts a killed worker again) on 127.0.0.1, shared by this module's tests (a cluster
    takes ~15 s to start on this machine)."""
    tmp_path = tmp_path_factory.mktemp("cluster")
    dask = Path(sys.executable).with_name("dask")
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    sched_file = tmp_path / "scheduler.json"
    logs = [open(tmp_path / f"{n}.log", "wb") for n in ("scheduler", "w1", "w2")]  # noqa: SIM115
    procs = [subprocess.Popen(
        [str(dask), "scheduler", "--host", "127.0.0.1", "--port", "0", "--no-dashboard",
         "--scheduler-file", str(sched_file)], cwd=ROOT, env=env, stdout=logs[0],
        stderr=subprocess.STDOUT)]
    try:
        from dask.distributed import Client

        for log in logs[1:]:
            procs.append(subprocess.Popen(
                [str(dask), "worker", "--scheduler-file", str(sched_file), "--nthreads", "1",
                 "--host", "127.0.0.1", "--no-dashboard", "--death-timeout", "60"],
                cwd=ROOT, env=env, stdout=log, stderr=subprocess.STDOUT))
        with Client(scheduler_file=str(sched_file), timeout=60) as c:
            c.wait_for_workers(2, timeout=90)
            address = c.scheduler.address
        yield address
    finally:
        # the workers first, the scheduler after: a worker that lost its scheduler waits
        # for it a while before it exits
        for p in reversed(procs):
            p.terminate()
            try:
                p.wait(timeout=20)
            except subprocess.TimeoutExpired:
                p.kill()
                p.wait()
        for log in logs:
            log.close()


def _two_workers(address: str) -> None:
    """Wait (bounded) for both workers: one the other test killed comes back by its nanny."""
    from dask.distributed import Client

    with Client(address, timeout=60) as c:
        c.wait_for_workers(2, timeout=90)


def test_a_lost_worker_s_runs_are_run_again(tmp_path: Path, cluster: str) -> None:
    """A worker killed while it runs: its runs are retried on the other (retries=2) and the
    series completes with every result."""
    import signal
    import threading

    suite = load_suite(str(DATA))
    _two_workers(cluster)
    dc = DaskCluster(cluster)
    results: list[dict[str, object]] = []
    try:
        client = dc.client
        pids = client.run(os.getpid)  # worker address -> its process id
        box: dict[str, object] = {}

        def series() -> None:
            try:
                box["rep"] = run_suite(suite, Entrant(), tmp_path / "lost", dc)
            except BaseException as exc:  # (shown by the assertion below)
                box["rep"] = exc

        thread = threading.Thread(target=series)
        thread.start()
        busy = wait_until(lambda: [w for w, keys in client.processing().items() if keys],
                          60, 0.05, "a worker with a run in hand")
        victim = pids[busy[0]]
        os.kill(victim, signal.SIGKILL)
        thread.join(180)
        assert not thread.is_alive()
        rep = box["rep"]
        assert isinstance(rep, dict), rep
        results = rep["runs"]
        assert victim not in client.run(os.getpid).values()  # it did die mid-series
    finally:
        dc.close()
    assert len(results) == 3
    assert all(r["error"] is None for r in results), [r["error"] for r in results]
    assert all(Path(str(r["log"])).is_file() for r in results)


def test_pool_and_cluster_give_the_same_report(tmp_path: Path, cluster: str) -> None:
    """The station with --eval-cluster: the Evaluate tab's class job runs on the cluster's
    workers with the students' code and the suite's checks.py sent by content (nothing by
    path), its progress in health; its report is the local pool's for the same seeds (the
    grade table, every run, each log byte for byte), its page self-contained; a failed run's
    log (back from the worker as bytes) opens in the player."""
    from fastapi.testclient import TestClient

    from backend.api import create_app
    from backend.config import Settings
    from backend.station import Station
    from evaluate.jobs import run_class
    from launcher.supervisor import free_tcp_port

    here = Path(__file__).parent
    suite = load_suite(str(here / "class_suite"))
    pool_rep = run_class(here / "class", suite, tmp_path / "pool", LocalPool(2))
    _two_workers(cluster)
    settings = Settings(relay_pub=f"tcp://127.0.0.1:{free_tcp_port()}",
                        relay_sub=f"tcp://127.0.0.1:{free_tcp_port()}", static_dir=tmp_path,
                        state_dir=None, record_dir=tmp_path / "rec",
                        reports_dir=tmp_path / "reports", suite_dirs=[here],
                        class_dir=here / "class", allowed_hosts=["testserver"],
                        eval_cluster=cluster)
    st = Station(settings)
    with TestClient(create_app(settings, st), headers={"X-Touchline": "1"}) as c:
        view = c.get("/api/evaluate").json()
        assert view["cluster"] == cluster and view["students"] == ["crash", "good", "spin"]
        r = c.post("/api/evaluate", json={"action": "start", "kind": "class",
                                          "suite": "class_suite"})
        assert r.status_code == 200, r.text
        job = wait_until(lambda: (j := c.get("/api/health").json()["evaluation"])["state"]
                         != "running" and j, 180, 0.1, "the job's end in health")
        assert job["state"] == "done", job
        assert (job["done"], job["total"], job["passed"], job["failed"]) == (3, 3, 1, 2)
        rep = c.get(f"/api/evaluate/reports/{job['report']}").json()
        grades = {g["student"]: g for g in rep["grades"]}
        assert {k: g["cells"]["drive"]["passed"]
                for k, g in grades.items()} == {"crash": False, "good": True, "spin": False}
        assert grades["crash"]["cells"]["drive"]["note"].startswith(
            "exception at drive_to_point.py:7: ZeroDivisionError")
        runs = {x["id"]: x for x in rep["runs"]}
        assert runs["crash.drive"]["team_error"].startswith(
            "exception at drive_to_point.py:7: ZeroDivisionError")
        assert runs["good.drive"]["team_error"] == ""
        run = grades["spin"]["cells"]["drive"]["run"]
        assert run == "spin.drive"
        r = c.post("/api/evaluate/replay", json={"report": job["report"], "run": run})
        assert r.status_code == 200, r.text
        p = wait_until(lambda: (q := c.get("/api/player").json())["source"] == "log" and q,
                       60, 0.1, "the log in the player")
        assert p["file"].endswith("spin/drive.log")
    saved = json.loads((tmp_path / "reports" / job["report"] / "report.json").read_text())
    assert saved["backend"]["kind"] == "dask" and saved["backend"]["address"] == cluster

    def same(rep: dict[str, Any]) -> dict[str, Any]:
        s = strip_volatile(rep)
        for r in s["runs"]:
            r["log"] = Path(r["log"]).relative_to(Path(r["log"]).parents[2]).as_posix()
            # where the CPU limit caught the endless loop (line 8 or 9) is the machine's
            r["team_error"] = re.sub(r"py:\d+", "py:N", str(r["team_error"]))
        for g in s["grades"]:
            for cell in g["cells"].values():
                cell["note"] = re.sub(r"py:\d+", "py:N", cell["note"])
                cell["replay"] = Path(cell["replay"]).name
        return s

    a, b = same(pool_rep), same(saved)
    assert [c["name"] for c in b["runs"][1]["checks"]] == ["reach", "stopped"]
    assert a == b
    # the logs too (not the spinning student's: its commands stop when the CPU limit, in
    # real time, catches it)
    for ra, rb in zip(pool_rep["runs"], saved["runs"], strict=True):
        assert Path(rb["log"]).is_relative_to(tmp_path / "reports")
        if ra["student"] != "spin":
            assert Path(ra["log"]).read_bytes() == Path(rb["log"]).read_bytes(), ra["student"]
    page = (tmp_path / "reports" / job["report"] / "report.html").read_text()
    assert "<svg" in page and "<script" not in page and "href=" not in page


def test_a_shipped_task_carries_its_code(tmp_path: Path) -> None:
    """What a cluster worker on another machine gets: the student's play and the suite's
    checks.py by content. Shipped, then both folders removed here, the run still finds
    them (run_shipped writes them to a folder of its own) and passes both checks."""
    import shutil

    from evaluate.pool import run_shipped, ship
    from evaluate.runner import ScenarioTask

    here = Path(__file__).parent
    student = tmp_path / "good"
    shutil.copytree(here / "class" / "good", student)
    shutil.copytree(here / "class_suite", tmp_path / "suite")
    suite = load_suite(str(tmp_path / "suite"))
    task = ScenarioTask(suite.scenarios[0], 0, Entrant(None, {}, str(student)),
                        str(tmp_path / "runs" / "drive.log"), suite.checks_file)
    shipped = ship(task)
    assert [name for name, _ in shipped.folders[0][1]] == ["drive_to_point.py"]
    shutil.rmtree(student)
    shutil.rmtree(tmp_path / "suite")
    res = run_shipped(shipped)
    assert res["error"] is None and res["passed"], res
    assert [c["name"] for c in res["checks"]] == ["reach", "stopped"]
    assert res["log"] == task.log_path and res["log_bytes"][:12] == b"SSL_LOG_FILE"
