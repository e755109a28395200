"""How much the strategy's worker thread delays the station thread (figures, not a test).

Both share one interpreter and its GIL. A stand-in for the station thread waits for UDP
datagrams that another *process* sends at the vision rate (600 a second: 8 cameras x 75 Hz),
each carrying its send time (CLOCK_MONOTONIC, the same clock in both processes), does a
station pass's worth of Python work, and records how long after the send the pass ended.
Meanwhile a worker thread runs the strategy over a recording (bench/strategy_replay.py) at
20 Hz, as the StrategyProcessor does. Rows: no strategy (the floor), then the strategy with
Python's default switch interval (5 ms) and with the station's (0.5 ms,
backend/station_loop.py), with and without path reuse, and with the pause between two
robots that the StrategyProcessor gives the strategy (sleep(0): the GIL released).

Wall-clock figures: on a shared machine read the rows against each other, not alone.

    PYTHONPATH=. .venv/bin/python bench/strategy_gil.py [--in F] [--seconds 15]
"""

from __future__ import annotations

import argparse
import socket
import struct
import subprocess
import sys
import threading
import time
from pathlib import Path
from typing import Any

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from backend.processors.strategy import _let_station_run
from backend.strategy.core import StrategyCore
from bench.strategy_replay import DEFAULT, load

SENDER = """
import socket, struct, sys, time
s = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
port, hz, seconds = int(sys.argv[1]), float(sys.argv[2]), float(sys.argv[3])
period, t0 = 1.0 / hz, time.monotonic()
k = 0
while time.monotonic() - t0 < seconds:
    k += 1
    wait = t0 + k * period - time.monotonic()
    if wait > 0:
        time.sleep(wait)
    s.sendto(struct.pack("<d", time.monotonic()), ("127.0.0.1", port))
s.sendto(b"end", ("127.0.0.1", port))
"""


def station_pass(work: np.ndarray) -> float:
    """About a pass's worth of interpreter work (small numpy calls and Python arithmetic)."""
    acc = 0.0
    for row in work:
        acc += float(row.sum()) * 0.5
    return acc


def strategy(ticks: list[Any], reuse: bool, pause: bool, stop: threading.Event,
             done: list[float]) -> None:
    def fresh() -> StrategyCore:
        core = StrategyCore()
        core.reuse_paths = reuse
        core.pause = _let_station_run if pause else None
        return core

    core = fresh()
    k = 0
    c0 = time.thread_time()
    while not stop.is_set():
        t = time.monotonic()
        prep, keeper = ticks[k % len(ticks)]
        if k and k % len(ticks) == 0:
            core = fresh()  # the recording starts over: no stale plans
        core.decide(prep, keeper)
        k += 1
        rest = 0.05 - (time.monotonic() - t)
        if rest > 0:
            stop.wait(rest)
    done.append(time.thread_time() - c0)


def run(ticks: list[Any] | None, reuse: bool, pause: bool, interval: float, seconds: float,
        hz: float) -> tuple[np.ndarray, float]:
    sys.setswitchinterval(interval)
    sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    sock.bind(("127.0.0.1", 0))
    port = sock.getsockname()[1]
    stop = threading.Event()
    cpu: list[float] = []
    worker = None
    if ticks is not None:
        worker = threading.Thread(target=strategy, args=(ticks, reuse, pause, stop, cpu),
                                  daemon=True)
        worker.start()
    sender = subprocess.Popen([sys.executable, "-c", SENDER, str(port), str(hz), str(seconds)])
    work = np.random.default_rng(1).random((60, 8))
    delays: list[float] = []
    try:
        while True:
            data = sock.recv(64)
            if data == b"end":
                break
            (sent,) = struct.unpack("<d", data)
            station_pass(work)
            delays.append(time.monotonic() - sent)
    finally:
        stop.set()
        if worker is not None:
            worker.join(timeout=10)
        sender.wait(timeout=10)
        sock.close()
    return np.asarray(delays[int(hz):]) * 1000.0, (cpu[0] / seconds * 100 if cpu else 0.0)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--in", dest="inp", default=DEFAULT)
    ap.add_argument("--seconds", type=float, default=15.0)
    ap.add_argument("--hz", type=float, default=600.0)
    a = ap.parse_args()
    ticks = load(a.inp)
    rows = [("no strategy", None, True, False, 0.0005),
            ("reuse off, 5 ms", ticks, False, False, 0.005),
            ("reuse off, 0.5 ms", ticks, False, False, 0.0005),
            ("reuse on, 0.5 ms", ticks, True, False, 0.0005),
            ("reuse on, 0.5 ms, pause", ticks, True, True, 0.0005)]
    print(f"{'strategy, switch interval':>26} {'p50 ms':>7} {'p99 ms':>7} {'p99.9':>7} "
          f"{'max':>7} {'strategy CPU %':>15}")
    for name, tk, reuse, pause, interval in rows:
        d, cpu = run(tk, reuse, pause, interval, a.seconds, a.hz)
        print(f"{name:>26} {np.median(d):7.3f} {np.percentile(d, 99):7.3f} "
              f"{np.percentile(d, 99.9):7.3f} {d.max():7.2f} {cpu:15.1f}")


if __name__ == "__main__":
    main()
