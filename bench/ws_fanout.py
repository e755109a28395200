"""Benchmark: websocket fan-out to 20 clients at 60 Hz and its effect on the control loop.

Starts the real station (launcher --isolated), measures the control processor's rate and the
vision-to-command latency with 0 clients, with 20 reading clients, and with 20 clients of
which 2 stop reading. Prints numbers; not a test."""

from __future__ import annotations

import asyncio
import json
import subprocess
import sys
import time
from pathlib import Path
from typing import Any

import httpx
from websockets.asyncio.client import connect

ROOT = Path(__file__).resolve().parent.parent


def start_station() -> tuple[subprocess.Popen[str], str]:
    proc = subprocess.Popen([sys.executable, "-m", "launcher", "--isolated"], cwd=ROOT,
                            stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True)
    assert proc.stdout is not None
    deadline = time.monotonic() + 60
    for line in proc.stdout:
        if line.startswith("TOUCHLINE_READY "):
            return proc, line.split()[1]
        if time.monotonic() > deadline:
            break
    proc.kill()
    raise RuntimeError("station did not start")


def health(url: str) -> dict[str, Any]:
    h: dict[str, Any] = httpx.get(url + "/api/health", timeout=5).json()
    return h


def control_numbers(url: str) -> str:
    h = health(url)
    ctrl = next(p for p in h["processors"] if p["name"] == "control")
    lat = h["latency"]
    return (f"control {ctrl['measured_hz']:.0f} Hz (tick mean {ctrl['tick_mean_ms']:.2f} ms), "
            f"vision->command p50 {lat['p50_ms']:.2f} ms p99 {lat['p99_ms']:.2f} ms, "
            f"clients {h['websocket_clients']}")


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


async def phase(url: str, n: int, stalled: int, seconds: float) -> None:
    counts = [0] * n
    stop = asyncio.Event()
    tasks = [asyncio.create_task(reader(url, counts, i, stop, i < stalled)) for i in range(n)]
    await asyncio.sleep(2.0)  # let buffers of stalled clients fill
    base = list(counts)
    await asyncio.sleep(seconds)
    rates = [(c - b) / seconds for c, b in zip(counts, base, strict=True)][stalled:]
    numbers = await asyncio.to_thread(control_numbers, url)
    stop.set()
    for t in tasks:
        t.cancel()
    await asyncio.gather(*tasks, return_exceptions=True)
    print(f"{n} clients ({stalled} stalled): world msgs/s per reading client "
          f"min {min(rates):.1f} mean {sum(rates) / len(rates):.1f}; {numbers}")


def main() -> None:
    proc, url = start_station()
    try:
        time.sleep(3)
        print("0 clients:", control_numbers(url))
        asyncio.run(phase(url, 20, 0, 5.0))
        asyncio.run(phase(url, 20, 2, 5.0))
    finally:
        proc.terminate()
        proc.wait(timeout=15)


if __name__ == "__main__":
    main()
