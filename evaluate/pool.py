"""Where the runs run: a local process pool (the default: one worker per core) or a Dask
distributed cluster (``--cluster tcp://host:8786``, or ``local:N`` for a LocalCluster of N
worker processes on this machine). Both take the same tasks (``ScenarioTask`` /
``MatchTask``, picklable) and give back the same plain results, in task order, whatever order
they finished in; ``on_result`` is called as each one comes back (progress).

The pool: ``concurrent.futures.ProcessPoolExecutor`` with spawned workers, each limited in
memory (RLIMIT_AS) and to one BLAS thread; a worker that dies (a crash in C code, the kernel's
OOM killer) breaks the pool: the runs it had are tried once more in a fresh pool, then failed.
Dask: ``client.submit(..., retries=2)`` (a run that raised in its worker is run again; a
worker that dies has its runs rescheduled on the others by the scheduler, up to its
``allowed-failures``), ``as_completed`` for progress. A worker may be another machine, so
nothing goes by path: the team folders' code files and the suite's ``checks.py`` travel with
the task (``Shipped``) and are written to a temporary folder there; a run's log comes back as
bytes and is written here.
"""

from __future__ import annotations

import concurrent.futures
import multiprocessing
import os
import resource
import shutil
import tempfile
from collections.abc import Callable, Sequence
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

from .runner import Entrant, MatchTask, ScenarioTask, run_match_task, run_scenario_task

Task = ScenarioTask | MatchTask
OnResult = Callable[[int, int, dict[str, Any]], None]  # done, total, result

#: a pool worker's address space by default (a run takes ~150-300 MB; team code more)
DEFAULT_MEMORY_MB = 3072
#: a team folder's code shipped with each of its tasks to a cluster at most this big
MAX_SHIPPED_BYTES = 8 << 20


def run_task(task: Task) -> dict[str, Any]:
    """One task, whichever kind (what a worker calls)."""
    if isinstance(task, MatchTask):
        return run_match_task(task)
    return run_scenario_task(task)


def _worker_init(memory_mb: int, nice: int = 0) -> None:
    # one thread per worker: the pool is the parallelism (numpy's BLAS would add its own)
    for var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
        os.environ[var] = "1"
    if memory_mb > 0:
        limit = memory_mb * 1024 * 1024
        resource.setrlimit(resource.RLIMIT_AS, (limit, limit))
    if nice > 0:  # (the station's own job: its live loop comes first)
        os.nice(nice)


def _write_log(res: dict[str, Any]) -> None:
    data = res.pop("log_bytes", None)
    path = res.get("log")
    if data is None or not path:
        return
    p = Path(path)
    p.parent.mkdir(parents=True, exist_ok=True)
    with open(p, "xb") as f:  # never overwrites (like the recorder)
        f.write(data)


@dataclass
class Backend:
    """What ran the series, for the report."""

    kind: str  # "pool" | "dask"
    workers: int
    address: str = ""

    def as_dict(self) -> dict[str, Any]:
        return {"kind": self.kind, "workers": self.workers, "address": self.address}


class LocalPool:
    def __init__(self, workers: int | None = None, memory_mb: int = DEFAULT_MEMORY_MB,
                 nice: int = 0) -> None:
        self.workers = max(1, workers or os.cpu_count() or 1)
        self.memory_mb = memory_mb
        self.nice = nice
        self.backend = Backend("pool", self.workers)
        self.retried = 0

    def _pool(self, n: int) -> concurrent.futures.ProcessPoolExecutor:
        return concurrent.futures.ProcessPoolExecutor(
            max_workers=min(self.workers, max(1, n)),
            mp_context=multiprocessing.get_context("spawn"),
            initializer=_worker_init, initargs=(self.memory_mb, self.nice))

    def run(self, tasks: Sequence[Task], on_result: OnResult | None = None,
            cancelled: Callable[[], bool] = lambda: False) -> list[dict[str, Any]]:
        results: list[dict[str, Any] | None] = [None] * len(tasks)
        todo = list(range(len(tasks)))
        tries = dict.fromkeys(todo, 0)
        done = 0
        while todo and not cancelled():
            broken: list[int] = []
            with self._pool(len(todo)) as pool:
                futs = {pool.submit(run_task, tasks[i]): i for i in todo}
                for fut in concurrent.futures.as_completed(futs):
                    i = futs[fut]
                    try:
                        res = fut.result()
                    except concurrent.futures.process.BrokenProcessPool:
                        broken.append(i)
                        continue
                    except Exception as exc:  # (run_task catches its own; this is the pool's)
                        res = _failed(tasks[i], f"{type(exc).__name__}: {exc}")
                    _write_log(res)
                    results[i] = res
                    done += 1
                    if on_result is not None:
                        on_result(done, len(tasks), res)
                    if cancelled():
                        for f in futs:
                            f.cancel()
                        break
            todo = []
            for i in broken:
                tries[i] += 1
                if tries[i] >= 2:
                    res = _failed(tasks[i], "its worker process died twice (a crash or out "
                                            "of memory)")
                    results[i] = res
                    done += 1
                    if on_result is not None:
                        on_result(done, len(tasks), res)
                else:
                    self.retried += 1
                    todo.append(i)
        return [r if r is not None else _failed(tasks[i], "cancelled")
                for i, r in enumerate(results)]

    def close(self) -> None:
        pass


def _failed(task: Task, why: str) -> dict[str, Any]:
    if isinstance(task, MatchTask):
        return {"kind": "match", "name": task.name, "seed": task.seed,
                "blue": task.blue.name(), "yellow": task.yellow.name(),
                "blue_on_positive": task.blue_on_positive, "log": None, "error": why}
    return {"kind": "scenario", "name": task.name, "scenario": task.scenario.name,
            "title": task.scenario.title, "run": task.run_index,
            "seed": task.scenario.seed + task.run_index, "entrant": task.entrant.name(),
            "play": task.entrant.play or task.scenario.play, "log": None, "error": why,
            "passed": False, "score": 0.0, "checks": []}


class DaskCluster:
    """A Dask distributed cluster: ``address`` "tcp://host:port" (a running scheduler), or
    "local:N" (a LocalCluster of N single-threaded worker processes, started here)."""

    def __init__(self, address: str, memory_mb: int = DEFAULT_MEMORY_MB) -> None:
        from dask.distributed import Client, LocalCluster

        self._cluster: Any = None
        if address.startswith("local:"):
            n = int(address.split(":", 1)[1] or "0") or (os.cpu_count() or 1)
            self._cluster = LocalCluster(n_workers=n, threads_per_worker=1, processes=True,
                                         host="127.0.0.1", dashboard_address=None,
                                         memory_limit=f"{memory_mb}MB" if memory_mb else None)
            self.client = Client(self._cluster)
        else:
            self.client = Client(address)
        workers = len(self.client.scheduler_info().get("workers", {}))
        self.backend = Backend("dask", workers, address)

    def run(self, tasks: Sequence[Task], on_result: OnResult | None = None,
            cancelled: Callable[[], bool] = lambda: False) -> list[dict[str, Any]]:
        from dask.distributed import as_completed

        results: list[dict[str, Any] | None] = [None] * len(tasks)
        cache: dict[str, Files] = {}
        index: dict[Any, int] = {}  # a future's key -> its task
        futs = []
        done = 0
        for i, t in enumerate(tasks):
            try:
                shipped = ship(t, cache)
            except (OSError, ValueError) as exc:  # (that run fails, the others go)
                results[i] = res = _failed(t, str(exc))
                done += 1
                if on_result is not None:
                    on_result(done, len(tasks), res)
                continue
            fut = self.client.submit(run_shipped, shipped, retries=2, pure=False)
            index[fut.key] = i
            futs.append(fut)
        for fut in as_completed(futs):
            done += 1
            i = index[fut.key]
            try:
                res = fut.result()
            except Exception as exc:  # its retries spent (the worker died each time)
                res = _failed(tasks[i], f"lost on the cluster: {type(exc).__name__}: {exc}")
            _write_log(res)
            results[i] = res
            if on_result is not None:
                on_result(done, len(tasks), res)
            if cancelled():
                for f in futs:
                    f.cancel()
                break
        return [r if r is not None else _failed(tasks[i], "cancelled")
                for i, r in enumerate(results)]

    def close(self) -> None:
        self.client.close()
        if self._cluster is not None:
            self._cluster.close()


Files = tuple[tuple[str, bytes], ...]


@dataclass(frozen=True)
class Shipped:
    """A task for a cluster worker, with the code it needs by content, not by path: each
    team folder's play files (``folders``: the folder as named in the task -> its files,
    relative names) and the suite's checks.py."""

    task: Task
    folders: tuple[tuple[str, Files], ...] = ()
    checks: bytes | None = None


def team_files(folder: str) -> Files:
    """What the team-code host reads of a team folder (backend/teamcode/discovery.py): the
    ``*.py`` and ``*.m`` files of its top level and of ``lib/``."""
    from backend.teamcode.discovery import NAME_RE

    root = Path(folder)
    out: list[tuple[str, bytes]] = []
    total = 0
    for p in sorted([*root.glob("*"), *root.glob("lib/*")]):
        rel = p.relative_to(root).as_posix()
        if not p.is_file() or not NAME_RE.match(rel):
            continue
        data = p.read_bytes()
        total += len(data)
        if total > MAX_SHIPPED_BYTES:
            raise ValueError(f"team folder {folder}: its code is over "
                             f"{MAX_SHIPPED_BYTES >> 20} MB, too big to send to a cluster")
        out.append((rel, data))
    return tuple(out)


def _entrants(task: Task) -> list[Entrant]:
    return [task.blue, task.yellow] if isinstance(task, MatchTask) else [task.entrant]


def ship(task: Task, cache: dict[str, Files] | None = None) -> Shipped:
    """The task with its log coming back as bytes and its code going by content (``cache``:
    folders already read, by path, as a series reuses them)."""
    cache = {} if cache is None else cache
    folders: dict[str, Files] = {}
    for e in _entrants(task):
        if e.team_dir and e.team_dir not in folders and Path(e.team_dir).is_dir():
            if e.team_dir not in cache:
                cache[e.team_dir] = team_files(e.team_dir)
            folders[e.team_dir] = cache[e.team_dir]
    checks = None
    if isinstance(task, ScenarioTask) and task.checks_py:
        checks = Path(task.checks_py).read_bytes()
    return Shipped(replace(task, ship_log=task.log_path is not None),
                   tuple(folders.items()), checks)


def run_shipped(shipped: Shipped) -> dict[str, Any]:
    """What a cluster worker calls: the shipped files written to a temporary folder, the task
    pointed at them, run, the folder removed."""
    if not shipped.folders and shipped.checks is None:
        return run_task(shipped.task)
    tmp = Path(tempfile.mkdtemp(prefix="evaluate-code-"))
    try:
        where: dict[str, str] = {}
        for i, (name, files) in enumerate(shipped.folders):
            # the folder's own name kept (a class report names students by it)
            d = tmp / str(i) / Path(name).name
            for rel, data in files:
                (d / rel).parent.mkdir(parents=True, exist_ok=True)
                (d / rel).write_bytes(data)
            d.mkdir(parents=True, exist_ok=True)
            where[name] = str(d)

        def moved(e: Entrant) -> Entrant:
            return replace(e, team_dir=where[e.team_dir]) if e.team_dir in where else e

        task = shipped.task
        if isinstance(task, MatchTask):
            task = replace(task, blue=moved(task.blue), yellow=moved(task.yellow))
        else:
            checks_py = task.checks_py
            if shipped.checks is not None:
                checks_py = str(tmp / "checks.py")
                Path(checks_py).write_bytes(shipped.checks)
            task = replace(task, entrant=moved(task.entrant), checks_py=checks_py)
        return run_task(task)
    finally:
        shutil.rmtree(tmp, ignore_errors=True)


def make_backend(cluster: str | None, workers: int | None,
                 memory_mb: int = DEFAULT_MEMORY_MB) -> LocalPool | DaskCluster:
    if cluster:
        return DaskCluster(cluster, memory_mb)
    return LocalPool(workers, memory_mb)
