"""Benchmark: websocket fan-out to N clients (default 25) at 60 Hz and its effect on the control
loop (issue 11: 25 clients add <= 10 % of a core and never move the loop's numbers).

Starts the real station (launcher --isolated) at full load (8 cameras x 75 Hz, division A,
11 v 11, the "match" play) and measures, in phases of ``--seconds`` each: 0 clients, N reading
clients, N clients of which ``--stalled`` stop reading. Per phase: CPU of every process (% of
one core, /proc), world messages/s per reading client, the control processor's rate, the
backend's vision -> command latency and the relay's arrival -> command p50 / p99. Prints
numbers; not a test.

    PYTHONPATH=. .venv/bin/python bench/ws_fanout.py [--clients 25] [--stalled 2] [--seconds 10]
"""

from __future__ import annotations

import argparse
import asyncio
import json
import statistics
import time
from pathlib import Path
from typing import Any

import httpx
from websockets.asyncio.client import connect

from bench.station_run import full_scale_args, start_station
from sslnet.proc import process_cpu_s as cpu_s

ROOT = Path(__file__).resolve().parent.parent


def health(url: str) -> dict[str, Any]:
    h: dict[str, Any] = httpx.get(url + "/api/health", timeout=5).json()
    return h


class Sampler:
    """CPU per process over a phase, and the loop's latency figures sampled once a second."""

    def __init__(self, url: str, pids: dict[str, int]) -> None:
        self.url, self.pids = url, pids
        self.rows: list[dict[str, float]] = []

    def start(self) -> None:
        self.c0 = {k: cpu_s(p) for k, p in self.pids.items()}
        self.t0 = time.monotonic()
        self.rows = []

    def sample(self) -> None:
        h = health(self.url)
        ctrl = next(p for p in h["processors"] if p["name"] == "control")
        relay = h["relay"] or {}
        self.rows.append({
            "control_hz": ctrl["measured_hz"], "backend_p50": h["latency"]["p50_ms"],
            "backend_p99": h["latency"]["p99_ms"],
            "relay_p50": relay.get("command_latency_p50_ms", -1),
            "relay_p99": relay.get("command_latency_p99_ms", -1),
            "clients": h["websocket_clients"],
        })

    def result(self) -> dict[str, float]:
        dt = time.monotonic() - self.t0
        out = {f"cpu_{k}": (cpu_s(p) - self.c0[k]) / dt * 100 for k, p in self.pids.items()}
        for k in ("control_hz", "backend_p50", "backend_p99", "relay_p50", "relay_p99",
                  "clients"):
            vals = [r[k] for r in self.rows if r[k] >= 0]
            out[k] = statistics.median(vals) if vals else -1.0
        return out


async def reader(url: str, counts: list[int], i: int, stop: asyncio.Event,
                 stall: bool) -> None:
    async with connect(url.replace("http", "ws") + "/api/ws", max_size=None,
                       compression=None) as ws:
        while not stop.is_set():
            if stall:
                await stop.wait()  # connected, never reads again
                break
            msg = json.loads(await ws.recv())
            if msg["type"] == "world":
                counts[i] += 1


async def phase(s: Sampler, n: int, stalled: int, seconds: float) -> dict[str, float]:
    counts = [0] * n
    stop = asyncio.Event()
    tasks = [asyncio.create_task(reader(s.url, counts, i, stop, i < stalled)) for i in range(n)]
    await asyncio.sleep(2.0)  # let buffers of stalled clients fill
    base = list(counts)
    s.start()
    t_end = time.monotonic() + seconds
    while time.monotonic() < t_end:
        await asyncio.sleep(1.0)
        await asyncio.to_thread(s.sample)
    r = s.result()
    rates = [(c - b) / seconds for c, b in zip(counts, base, strict=True)][stalled:]
    stop.set()
    for t in tasks:
        t.cancel()
    await asyncio.gather(*tasks, return_exceptions=True)
    r["msgs_min"] = min(rates) if rates else 0.0
    r["msgs_mean"] = sum(rates) / len(rates) if rates else 0.0
    return r


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--clients", type=int, default=25)
    ap.add_argument("--stalled", type=int, default=2)
    ap.add_argument("--seconds", type=float, default=10.0)
    ap.add_argument("--cameras", type=int, default=8)
    ap.add_argument("--hz", type=float, default=75.0)
    a = ap.parse_args()
    station = start_station(full_scale_args(a.cameras, a.hz))
    proc, url, pids = station.proc, station.url, station.pids
    try:
        time.sleep(5)
        s = Sampler(url, pids)
        phases = [("0 clients", 0, 0), (f"{a.clients} reading", a.clients, 0),
                  (f"{a.clients} ({a.stalled} stalled)", a.clients, a.stalled)]
        results = [(name, asyncio.run(phase(s, n, st, a.seconds))) for name, n, st in phases]
    finally:
        proc.terminate()
        proc.wait(timeout=15)
    print(f"websocket fan-out, {a.cameras} cameras x {a.hz:g} Hz, 11 v 11, match play, "
          f"{a.seconds:g} s per phase (CPU in % of one core; latencies: medians of 1 s figures)")
    print("| phase | world msgs/s per reader (min / mean) | backend CPU | relay CPU | "
          "control Hz | backend vision->command p50 / p99 | relay arrival->command p50 / p99 |")
    print("|---|---|---|---|---|---|---|")
    for name, r in results:
        print(f"| {name} | {r['msgs_min']:.1f} / {r['msgs_mean']:.1f} | "
              f"{r['cpu_backend']:.1f} | {r['cpu_relay']:.1f} | {r['control_hz']:.0f} | "
              f"{r['backend_p50']:.2f} / {r['backend_p99']:.2f} ms | "
              f"{r['relay_p50']:.2f} / {r['relay_p99']:.2f} ms |")
    base = results[0][1]
    for name, r in results[1:]:
        added = r["cpu_backend"] + r["cpu_relay"] - base["cpu_backend"] - base["cpu_relay"]
        print(f"{name}: adds {added:+.1f} % of a core to relay + backend")


if __name__ == "__main__":
    main()
