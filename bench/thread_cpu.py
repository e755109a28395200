"""CPU per thread of a full-scale station (figures, not a test).

Starts the launcher's station (built-in simulator, 8 cameras x 75 Hz, division A, 11 v 11,
the "match" play) and samples /proc/PID/task/*/stat (utime + stime) of the backend and the
relay over ``--seconds`` after ``--warmup``: each thread's share of one core, busiest first.
Python does not name its threads for the OS, so the threads are told apart by their load
(in the backend: the station thread first; the strategy's worker thread is the one that
``--play idle`` leaves idle). CPU time holds on a shared machine; wall-clock latency does not.

    PYTHONPATH=. .venv/bin/python bench/thread_cpu.py [--seconds 10] [--play match]
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
TICKS = os.sysconf("SC_CLK_TCK")


def thread_cpu(pid: int) -> dict[int, tuple[str, float]]:
    """Each thread's (name, CPU seconds so far)."""
    out: dict[int, tuple[str, float]] = {}
    for task in Path(f"/proc/{pid}/task").iterdir():
        try:
            stat = (task / "stat").read_text()
        except OSError:
            continue  # the thread ended meanwhile
        name = stat[stat.index("(") + 1:stat.rindex(")")]
        fields = stat[stat.rindex(")") + 2:].split()
        out[int(task.name)] = (name, (int(fields[11]) + int(fields[12])) / TICKS)
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--seconds", type=float, default=10.0)
    ap.add_argument("--warmup", type=float, default=10.0)
    ap.add_argument("--play", default="match")
    ap.add_argument("--top", type=int, default=5)
    a = ap.parse_args()
    sim = ["--division", "A", "--blue", "11", "--yellow", "11", "--cameras", "8",
           "--camera-hz", "75"]
    args = [sys.executable, "-m", "launcher", "--isolated", *(f"--sim-arg={x}" for x in sim),
            "--backend-arg=--set", f"--backend-arg=strategy.play={a.play}"]
    proc = subprocess.Popen(args, cwd=ROOT, stdout=subprocess.PIPE, stderr=subprocess.DEVNULL,
                            text=True)
    assert proc.stdout is not None
    pids: dict[str, int] = {}
    try:
        for line in proc.stdout:
            if line.startswith("TOUCHLINE_PIDS "):
                pids = json.loads(line.split(" ", 1)[1])
            if line.startswith("TOUCHLINE_READY "):
                break
        else:
            raise SystemExit("station did not start")
        time.sleep(a.warmup)
        keep = {k: v for k, v in pids.items() if k in ("backend", "relay")}
        c0 = {k: thread_cpu(v) for k, v in keep.items()}
        t0 = time.monotonic()
        time.sleep(a.seconds)
        c1 = {k: thread_cpu(v) for k, v in keep.items()}
        dt = time.monotonic() - t0
    finally:
        proc.terminate()
        proc.wait(timeout=30)
    for k in keep:
        rows = sorted(((c1[k][t][1] - c0[k].get(t, ("", 0.0))[1]) / dt * 100, t, c1[k][t][0])
                      for t in c1[k])[::-1]
        total = sum(r[0] for r in rows)
        print(f"{k}: {total:.1f} % of a core in {len(rows)} threads; busiest: "
              + ", ".join(f"{pct:.1f} % ({name} {tid})" for pct, tid, name in rows[:a.top]))


if __name__ == "__main__":
    main()
