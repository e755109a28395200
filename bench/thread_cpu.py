"""Per-thread CPU of the relay and the backend at full scale (figures, not a test).

Starts the launcher's station like bench/loop_bench.py (built-in simulator at 8 cameras x
75 Hz, division A, 11 v 11, the "match" play), waits ``--warmup`` s, then reads
/proc/PID/task/*/stat (utime + stime) of the relay and the backend over ``--seconds`` and
prints each thread's CPU in % of one core, with the feedback rates the station saw (the
relay's answers from the simulator, the envelopes the backend got). CPU time holds on a
shared machine where wall-clock latency does not.

    PYTHONPATH=. .venv/bin/python bench/thread_cpu.py [--seconds 10] [--warmup 5]
        [--relay-arg=--feedback-interval=0]
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import httpx

from bench.station_run import full_scale_args, start_station
from sslnet.proc import thread_cpu_s

ROOT = Path(__file__).resolve().parent.parent


def threads(pid: int) -> dict[str, float]:
    """CPU seconds per thread of ``pid``, keyed "name/tid" (a thread that ended is left out)."""
    return {f"{name}/{tid}": sec for (name, tid), sec in thread_cpu_s(pid).items()}


def counts(client: httpx.Client, url: str) -> tuple[int, int]:
    """(answers the relay got from the simulator, feedback envelopes the backend got)."""
    streams = client.get(url + "/api/health").json().get("streams", {})
    relay = streams.get("relay.sim_responses", {})
    backend = streams.get("feedback", {})
    return int(relay.get("packets", 0)), int(backend.get("packets", 0))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--seconds", type=float, default=10.0)
    ap.add_argument("--warmup", type=float, default=5.0)
    ap.add_argument("--relay-arg", action="append", default=[])
    a = ap.parse_args()
    station = start_station(full_scale_args(relay_args=a.relay_arg))
    proc, pids, url = station.proc, station.pids, station.url
    try:
        time.sleep(a.warmup)
        client = httpx.Client(timeout=5)
        n0 = counts(client, url)
        c0 = {k: threads(pids[k]) for k in ("relay", "backend")}
        t0 = time.monotonic()
        time.sleep(a.seconds)
        dt = time.monotonic() - t0
        c1 = {k: threads(pids[k]) for k in ("relay", "backend")}
        n1 = counts(client, url)
    finally:
        proc.terminate()
        proc.wait(timeout=30)
    for k in ("relay", "backend"):
        rows = [(name, (c1[k][name] - c0[k].get(name, 0.0)) / dt * 100) for name in c1[k]]
        total = sum(v for _, v in rows)
        print(f"{k}: {total:.1f} % of a core")
        for name, v in sorted(rows, key=lambda r: -r[1]):
            if v >= 0.5:
                print(f"  {name:28s} {v:5.1f} %")
    print(f"feedback: {(n1[0] - n0[0]) / dt:.0f} answers/s at the relay, "
          f"{(n1[1] - n0[1]) / dt:.0f} envelopes/s at the backend")


if __name__ == "__main__":
    main()
