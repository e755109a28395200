"""The strategy's cost on the inputs of a real game (figures, not a test).

``record``: starts the launcher's station at full scale (built-in simulator, 8 cameras x
75 Hz, division A, 11 v 11, the "match" play) with ``TOUCHLINE_STRATEGY_RECORD`` set, so the
strategy processor pickles every tick's input (backend/processors/strategy.py), for
``--seconds``. ``python -m match`` records the same way with the variable set by hand
(``{team}`` in the file name keeps the two backends apart).

``replay``: runs a fresh ``StrategyCore.decide`` over the recorded ticks in order (the plan
cache sees the same sequence as in the game), prints the median, p99 and max per tick and
the CPU time per second of game; ``--profile`` prints the cProfile top too; ``--compare``
also runs with path reuse off and reports how far the targets and paths differ.

    PYTHONPATH=. .venv/bin/python bench/strategy_replay.py record [--seconds 30] [--out F]
    PYTHONPATH=. .venv/bin/python bench/strategy_replay.py replay [--in F] [--profile]
"""

from __future__ import annotations

import argparse
import cProfile
import gc
import math
import pickle
import pstats
import statistics
import sys
import time
from pathlib import Path
from typing import Any

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from backend.processors.strategy import RECORD_ENV
from backend.strategy.core import StrategyCore
from bench.station_run import full_scale_args, start_station

DEFAULT = "/tmp/touchline-strategy.pkl"


def record(a: argparse.Namespace) -> None:
    station = start_station(full_scale_args(), env={RECORD_ENV: a.out})
    try:
        time.sleep(a.seconds)  # the game plays meanwhile: a recording of that long
    finally:
        station.stop(30)
    print(f"recorded {len(load(a.out))} ticks to {a.out}")


def load(path: str) -> list[Any]:
    out = []
    with open(path, "rb") as f:
        while True:
            try:
                out.append(pickle.load(f))
            except EOFError:
                return out
            except pickle.UnpicklingError:  # the last one cut short by the stop
                return out


def run(ticks: list[Any], reuse: bool, prof: cProfile.Profile | None = None,
        ) -> tuple[list[float], float, list[dict[int, Any]], list[float]]:
    """Wall time per tick (ms), CPU s in all, the moves, CPU time per tick (ms)."""
    core = StrategyCore()
    core.reuse_paths = reuse
    times: list[float] = []
    cpus: list[float] = []
    moves: list[dict[int, Any]] = []
    c0 = time.thread_time()
    for prep, keeper in ticks:
        t0 = time.perf_counter()
        u0 = time.thread_time()
        if prof is not None:
            m = prof.runcall(core.decide, prep, keeper)
        else:
            m = core.decide(prep, keeper)
        cpus.append((time.thread_time() - u0) * 1000.0)
        times.append((time.perf_counter() - t0) * 1000.0)
        moves.append(m)
    return times, time.thread_time() - c0, moves, cpus


def _stats(v: list[float]) -> tuple[float, float, float, int]:
    """Median, p99, max and the tick of the max."""
    s = sorted(v)
    worst = max(range(len(v)), key=v.__getitem__)
    return statistics.median(s), s[min(len(s) - 1, int(0.99 * len(s)))], s[-1], worst


def summary(name: str, times: list[float], cpu_s: float, game_s: float,
            cpus: list[float]) -> None:
    med, p99, top, worst = _stats(times)
    cmed, cp99, ctop, cworst = _stats(cpus)
    print(f"{name:>10}: {len(times)} ticks, median {med:.2f} ms, p99 {p99:.2f} ms, max "
          f"{top:.2f} ms (tick {worst}); {cpu_s / game_s * 100:.2f} % of a core over "
          f"{game_s:.1f} s of game\n{'':>10}  CPU time per tick (load-independent): median "
          f"{cmed:.2f} ms, p99 {cp99:.2f} ms, max {ctop:.2f} ms (tick {cworst})")


def _dist(a: tuple[float, float], b: tuple[float, float]) -> float:
    return math.hypot(a[0] - b[0], a[1] - b[1])


def compare(fresh: list[dict[int, Any]], reused: list[dict[int, Any]]) -> None:
    """How far reuse moves the outputs: target, first waypoint, path length."""
    tgt: list[float] = []
    first: list[float] = []
    n_diff = n = 0
    for f, r in zip(fresh, reused, strict=True):
        for rid, mf in f.items():
            mr = r.get(rid)
            if mr is None:
                continue
            n += 1
            tgt.append(_dist((mf.x, mf.y), (mr.x, mr.y)))
            first.append(_dist(mf.path[0], mr.path[0]))
            n_diff += mf.path != mr.path
    tgt.sort()
    first.sort()
    print(f"moves {n}, paths not identical {n_diff}; target gap max {tgt[-1]:.1f} mm; first "
          f"waypoint gap median {statistics.median(first):.1f} p99 "
          f"{first[int(0.99 * len(first))]:.1f} max {first[-1]:.1f} mm")


def replay(a: argparse.Namespace) -> None:
    ticks = load(a.inp)
    if not ticks:
        raise SystemExit(f"no ticks in {a.inp}")
    # the recording is ~90k objects: a full collection that a tick's allocations trigger
    # would walk them all (a 50-80 ms "tick" that is the benchmark's own heap, not the
    # strategy's work), so they are moved out of the collector's sight first
    gc.collect()
    gc.freeze()
    game_s = ticks[-1][0].inp.t - ticks[0][0].inp.t
    prof = cProfile.Profile() if a.profile else None
    times, cpu, moves, cpus = run(ticks, True, prof)
    summary("reuse", times, cpu, game_s, cpus)
    if a.compare:
        t2, c2, m2, u2 = run(ticks, False)
        summary("no reuse", t2, c2, game_s, u2)
        compare(m2, moves)
    if prof is not None:
        st = pstats.Stats(prof)
        st.sort_stats("tottime").print_stats(a.top)
        st.sort_stats("cumulative").print_stats(a.top)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = ap.add_subparsers(dest="cmd", required=True)
    r = sub.add_parser("record")
    r.add_argument("--seconds", type=float, default=30.0)
    r.add_argument("--out", default=DEFAULT)
    p = sub.add_parser("replay")
    p.add_argument("--in", dest="inp", default=DEFAULT)
    p.add_argument("--profile", action="store_true")
    p.add_argument("--compare", action="store_true")
    p.add_argument("--top", type=int, default=25)
    a = ap.parse_args()
    record(a) if a.cmd == "record" else replay(a)


if __name__ == "__main__":
    main()
