"""Compute-engine call overhead (not a test): median and p99 of a trivial call, awaited one
after another, for the NumpyEngine and (when installed) the OctaveEngine.

Usage: .venv/bin/python bench/engine_bench.py [--calls 2000]
"""

from __future__ import annotations

import argparse
import asyncio
import statistics
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from backend.engine import NumpyEngine, OctaveEngine, find_octave

ROOT = Path(__file__).resolve().parents[1]


async def measure(engine: Any, calls: int, name: str, *args: Any) -> tuple[float, float]:
    for _ in range(min(50, calls)):
        await engine.call(name, *args)
    lat = []
    for _ in range(calls):
        t0 = time.perf_counter()
        await engine.call(name, *args)
        lat.append((time.perf_counter() - t0) * 1000.0)
    lat.sort()
    return statistics.median(lat), lat[min(len(lat) - 1, int(0.99 * len(lat)))]


def row(label: str, med: float, p99: float) -> None:
    print(f"{label:<48} median {med:7.3f} ms   p99 {p99:7.3f} ms")


async def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--calls", type=int, default=2000)
    n = ap.parse_args().calls
    a = np.zeros(2)
    b = np.ones(2)
    pts = np.random.default_rng(0).normal(size=(1000, 2))
    async with NumpyEngine(workers=1) as eng:
        row("numpy: geometry.distance, 1 point", *await measure(eng, n, "geometry.distance", a, b))
        row("numpy: geometry.distance, 1000 points",
            *await measure(eng, n, "geometry.distance", pts, pts[::-1]))
    if find_octave() is None:
        print("octave: not installed, skipped")
        return
    async with OctaveEngine(ROOT / "engine_scripts", workers=1) as oct_eng:
        row("octave: plus(1, 2)", *await measure(oct_eng, n, "plus", 1.0, 2.0))
        row("octave: geometry_src.distance, 1 point",
            *await measure(oct_eng, n, "geometry_src.distance", a, b))
        row("octave: geometry_src.distance, 1000 points",
            *await measure(oct_eng, n, "geometry_src.distance", pts, pts[::-1]))
        row("octave: goalkeeper, 1 ball",
            *await measure(oct_eng, n, "goalkeeper", a, np.array([-1000.0, 50.0]), -4500.0,
                           1000.0))
        t0 = time.perf_counter()
        await oct_eng.restart_workers()
        await oct_eng.call("plus", 1.0, 1.0, timeout_s=30.0)
        ms = 1000 * (time.perf_counter() - t0)
        print(f"{'octave: worker restart to first result':<48} {ms:7.1f} ms")


if __name__ == "__main__":
    asyncio.run(main())
