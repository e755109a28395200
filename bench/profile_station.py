"""Profile of the station thread (the backend's control loop) at full scale (figures, not a test).

Starts the launcher like bench/loop_bench.py (built-in simulator at 8 cameras x 75 Hz, division
A, 11 v 11, the "match" play) with ``TOUCHLINE_PROFILE`` set, profiles ``--seconds`` after a
5 s warm-up, stops it and prints the top of the station thread's cProfile by own time and
by cumulative time.

    PYTHONPATH=. .venv/bin/python bench/profile_station.py [--seconds 20] [--out /tmp/st.prof]
"""

from __future__ import annotations

import argparse
import os
import pstats
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--seconds", type=float, default=20.0)
    ap.add_argument("--cameras", type=int, default=8)
    ap.add_argument("--hz", type=float, default=75.0)
    ap.add_argument("--out", default="/tmp/touchline-station.prof")
    ap.add_argument("--top", type=int, default=30)
    a = ap.parse_args()
    out = Path(a.out)
    out.unlink(missing_ok=True)
    sim = ["--division", "A", "--blue", "11", "--yellow", "11", "--cameras", str(a.cameras),
           "--camera-hz", str(a.hz)]
    env = {**os.environ, "TOUCHLINE_PROFILE": str(out), "TOUCHLINE_PROFILE_AFTER": "5",
           "TOUCHLINE_PROFILE_FOR": str(a.seconds)}
    proc = subprocess.Popen([sys.executable, "-m", "launcher", "--isolated",
                             *(f"--sim-arg={x}" for x in sim),
                             "--backend-arg=--set", "--backend-arg=strategy.play=match"],
                            cwd=ROOT, env=env, stdout=subprocess.PIPE,
                            stderr=subprocess.DEVNULL, text=True)
    assert proc.stdout is not None
    for line in proc.stdout:
        if line.startswith("TOUCHLINE_READY "):
            break
    for _ in range(int((a.seconds + 30) * 10)):  # bounded: the station writes it after 5+N s
        if out.exists() and out.stat().st_size > 0:
            break
        time.sleep(0.1)
    time.sleep(0.5)  # the file is written in one go; let the write finish
    proc.terminate()
    proc.wait(timeout=30)
    st = pstats.Stats(str(out))
    st.sort_stats("tottime").print_stats(a.top)
    st.sort_stats("cumulative").print_stats(a.top)


if __name__ == "__main__":
    main()
