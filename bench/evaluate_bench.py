"""Evaluation speed (issue 28): a headless 6 v 6 match against real time on one core (4 and
2 cameras), the exercise suite's runs per second and per minute on the local pool and on a
Dask LocalCluster at 1 and 2 workers, and the whole 30-scenario exercise suite's wall time
on 2 cores (figures, not a test).

    PYTHONPATH=. .venv/bin/python bench/evaluate_bench.py [--half-s 45] [--quick] [--match-only]

The machine is shared: the load average (1, 5, 15 min) is printed before and after every
number; a figure whose 1-minute load moved much is not comparable with the next row's.
"""

from __future__ import annotations

import argparse
import resource
import tempfile
import time
from pathlib import Path

from evaluate.jobs import run_suite
from evaluate.pool import DaskCluster, LocalPool
from evaluate.runner import Entrant, MatchTask, run_match_task
from evaluate.scenario import load_suite

SOLUTIONS = Path(__file__).resolve().parent.parent / "evaluate" / "solutions"


def load() -> str:
    with open("/proc/loadavg") as f:
        return " ".join(f.read().split()[:3])


def match_speed(half_s: float, cameras: int = 4) -> None:
    with tempfile.TemporaryDirectory() as tmp:
        log = Path(tmp) / "match.log"
        task = MatchTask("bench", Entrant("match"), Entrant("simple"), 1, half_s,
                         cameras=cameras, log_path=str(log))
        before = load()
        t0, c0 = time.perf_counter(), time.process_time()
        res = run_match_task(task)
        wall, cpu = time.perf_counter() - t0, time.process_time() - c0
        size = log.stat().st_size if log.exists() else 0
    sim = float(res.get("sim_s") or 0.0)
    print(f"match 6 v 6 (match v simple, {half_s:g} s halves, interludes, {cameras} cameras): "
          f"{sim:.1f} s of game "
          f"in {wall:.1f} s wall / {cpu:.1f} s CPU: {sim / wall:.1f}x real time (wall), "
          f"{sim / cpu:.1f}x (CPU); score {res.get('score')}; log {size / 1e6:.1f} MB; "
          f"this process {resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024:.0f} MB "
          f"at most; load {before} -> {load()}")


def suite_speed(backend: LocalPool | DaskCluster, label: str, out: Path, play: str | None,
                team_dir: str | None) -> None:
    suite = load_suite("exercises")
    before = load()
    r0 = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    rep = run_suite(suite, Entrant(play, {}, team_dir), out, backend, keep_logs=True)
    wall = time.perf_counter() - t0
    r1 = resource.getrusage(resource.RUSAGE_CHILDREN)
    t = rep["timing"]
    logs = [p.stat().st_size for p in (out / "runs").glob("*.log")]
    who = f"play {play}" if play else f"each scenario's play from {Path(team_dir or '.').name}"
    print(f"exercises ({len(suite.scenarios)} scenarios, {t['runs']} runs, {who}) on "
          f"{label}: {wall:.1f} s wall, {t['runs'] / wall:.2f} runs/s "
          f"({t['runs_per_minute']} runs/min), {t['runs_per_minute_per_worker']} runs/min "
          f"per worker-busy minute, {t['speed_vs_real_time']}x real time a run, "
          f"{rep['summary']['totals']['passed']}/{t['runs']} passed; "
          f"load {before} -> {load()}")
    if isinstance(backend, LocalPool):
        # the pool's workers (and the team plays' processes they ran) have ended and been
        # waited for: their CPU is this process's children's
        cpu = (r1.ru_utime + r1.ru_stime) - (r0.ru_utime + r0.ru_stime)
        print(f"  CPU {cpu:.1f} s: {cpu / t['runs']:.2f} s a run; largest process "
              f"{r1.ru_maxrss / 1024:.0f} MB; logs {sum(logs) / 1e6:.1f} MB "
              f"({max(logs) / 1e6:.2f} MB the largest)")


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--half-s", type=float, default=45.0)
    ap.add_argument("--play", default=None,
                    help="one play for every exercise (default: each scenario's own, from "
                         "--team-dir)")
    ap.add_argument("--team-dir", default=str(SOLUTIONS),
                    help="the team folder of the exercises' plays (default: the reference "
                         "solutions, evaluate/solutions: team plays in worker processes, as "
                         "a class's)")
    ap.add_argument("--quick", action="store_true", help="the pool at 2 workers only")
    ap.add_argument("--match-only", action="store_true")
    ap.add_argument("--suites-only", action="store_true")
    args = ap.parse_args()
    if not args.suites_only:
        match_speed(args.half_s)
        match_speed(args.half_s, cameras=2)
    if args.match_only:
        return
    with tempfile.TemporaryDirectory() as tmp:
        root = Path(tmp)
        configs: list[tuple[str, object]] = [("pool, 2 workers", lambda: LocalPool(2))]
        if not args.quick:
            configs = [("pool, 1 worker", lambda: LocalPool(1)),
                       ("pool, 2 workers", lambda: LocalPool(2)),
                       ("dask LocalCluster, 1 worker", lambda: DaskCluster("local:1")),
                       ("dask LocalCluster, 2 workers", lambda: DaskCluster("local:2"))]
        for i, (label, make) in enumerate(configs):
            backend = make()  # type: ignore[operator]
            try:
                suite_speed(backend, label, root / f"r{i}", args.play, args.team_dir)
            finally:
                backend.close()


if __name__ == "__main__":
    main()
