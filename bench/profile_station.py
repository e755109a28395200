"""Profiles of the station at full scale (figures, not a test): issue 11 wants a profile before
and after every change to the hot path.

Starts the launcher's station (built-in simulator at 8 cameras x 75 Hz, division A, 11 v 11,
the "match" play) and profiles one part under cProfile for ``--seconds``:

- ``--part backend`` (default): the station thread, through ``TOUCHLINE_PROFILE`` (from 5 s
  after the start; the backend writes the file itself, backend/station_loop.py);
- ``--part relay``: the relay, through its ``--profile`` (written on its normal stop).

Prints the top by own time and by cumulative time. cProfile slows the part down: read the
shares, and take CPU figures from bench/loop_bench.py.

    PYTHONPATH=. .venv/bin/python bench/profile_station.py [--part backend|relay]
        [--seconds 20] [--out FILE] [--clock wall|cpu] [--camera-phases spread|together]
"""

from __future__ import annotations

import argparse
import pstats
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from bench.station_run import full_scale_args, start_station  # noqa: E402


def wait_for_file(path: Path, timeout_s: float) -> None:
    deadline = time.monotonic() + timeout_s
    while not (path.exists() and path.stat().st_size > 0) and time.monotonic() < deadline:
        time.sleep(0.1)  # polled: the process writes it in one go
    time.sleep(0.5)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--part", choices=["backend", "relay"], default="backend")
    ap.add_argument("--seconds", type=float, default=20.0)
    ap.add_argument("--cameras", type=int, default=8)
    ap.add_argument("--hz", type=float, default=75.0)
    ap.add_argument("--robots", type=int, default=11, help="robots a team")
    ap.add_argument("--camera-phases", choices=["spread", "together"], default="spread",
                    help="fieldsim's cameras: each its own phase, or all at once (a burst)")
    ap.add_argument("--out", default=None, help="default /tmp/touchline-<part>.prof")
    ap.add_argument("--top", type=int, default=30)
    ap.add_argument("--clock", choices=["wall", "cpu"], default="wall",
                    help="cpu counts the profiled thread's CPU time, not the wall "
                    "clock (epoll waits and preemption after a send then cost nothing)")
    a = ap.parse_args()
    out = Path(a.out or f"/tmp/touchline-{a.part}.prof")
    out.unlink(missing_ok=True)
    args = full_scale_args(a.cameras, a.hz, robots=a.robots, camera_phases=a.camera_phases)
    env = {"TOUCHLINE_PROFILE_CLOCK": a.clock}
    if a.part == "backend":
        env.update(TOUCHLINE_PROFILE=str(out), TOUCHLINE_PROFILE_AFTER="5",
                   TOUCHLINE_PROFILE_FOR=str(a.seconds))
    else:
        args.append(f"--relay-arg=--profile={out}")
    station = start_station(args, env=env)
    if a.part == "backend":  # the backend writes it 5 + N s after its start, still running
        wait_for_file(out, a.seconds + 30)
    else:
        time.sleep(a.seconds)
    station.stop(30)
    if a.part == "relay":  # the relay writes it as it stops
        wait_for_file(out, 10)
    st = pstats.Stats(str(out))
    st.sort_stats("tottime").print_stats(a.top)
    st.sort_stats("cumulative").print_stats(a.top)


if __name__ == "__main__":
    main()
