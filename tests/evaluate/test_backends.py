"""The local pool and a real two-worker Dask cluster (a scheduler and two workers started
here, on loopback) give the same report for the same seeds, logs and all."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from collections.abc import Iterator
from pathlib import Path

import pytest

from evaluate.jobs import run_suite
from evaluate.pool import DaskCluster, LocalPool
from evaluate.runner import Entrant
from evaluate.scenario import load_suite
from evaluate.series import strip_volatile

ROOT = Path(__file__).resolve().parents[2]
DATA = Path(__file__).parent / "quick"
pytestmark = pytest.mark.timeout(240)


@pytest.fixture
def cluster(tmp_path: Path) -> Iterator[str]:
    """``dask scheduler`` and two ``dask worker`` processes on 127.0.0.1."""
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
        for p in reversed(procs):
            p.terminate()
        for p in procs:
            try:
                p.wait(timeout=20)
            except subprocess.TimeoutExpired:
                p.kill()
        for log in logs:
            log.close()


def test_pool_and_cluster_give_the_same_report(tmp_path: Path, cluster: str) -> None:
    suite = load_suite(str(DATA))
    entrant = Entrant()
    pool = LocalPool(2)
    a = run_suite(suite, entrant, tmp_path / "pool", pool)
    dc = DaskCluster(cluster)
    try:
        assert dc.backend.workers == 2
        b = run_suite(suite, entrant, tmp_path / "dask", dc)
    finally:
        dc.close()
    assert a["backend"]["kind"] == "pool" and b["backend"]["kind"] == "dask"
    sa, sb = strip_volatile(a), strip_volatile(b)
    for s, where in ((sa, "pool"), (sb, "dask")):
        for r in s["runs"]:
            assert r["error"] is None, r["error"]
            assert Path(r["log"]).is_relative_to(tmp_path / where)
            r["log"] = Path(r["log"]).name
    assert sa == sb
    assert a["summary"]["totals"]["runs"] == len(suite.scenarios) + 1  # quick_keeper: 2 runs
    # each run's log, from the worker as bytes on the cluster, is the same file
    for ra, rb in zip(a["runs"], b["runs"], strict=True):
        assert Path(ra["log"]).read_bytes() == Path(rb["log"]).read_bytes()
    saved = json.loads((tmp_path / "dask" / "report.json").read_text())
    assert saved["backend"] == {"kind": "dask", "workers": 2, "address": cluster}
    page = (tmp_path / "dask" / "report.html").read_text()
    assert "<svg" in page and "<script" not in page and "href=" not in page
