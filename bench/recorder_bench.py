"""Session recorder CPU cost (not a test): a live session's record rate in real time.

4 cameras x 60 Hz of ~1 KB vision datagrams, referee at 40 Hz, command sets at 240 Hz
(520 records a second), for ``--seconds``, into a temporary folder. The process CPU time
(time.process_time: this thread and the recorder's writer thread) over the wall time, as %
of one core, with the recorder and without it (the same schedule calling nothing): the
difference is the recorder's cost. Goal: <= 2 % of one core.

Usage: .venv/bin/python bench/recorder_bench.py [--seconds 10]
"""

from __future__ import annotations

import argparse
import os
import tempfile
import time
from collections.abc import Callable
from pathlib import Path

from backend.recorder import SessionRecorder
from ssllog.format import TYPE_REFEREE_2013, TYPE_TL_COMMANDS, TYPE_VISION_2014
from ssllog.reader import LogReader

Event = tuple[float, int, bytes]


def schedule(seconds: float) -> list[Event]:
    """Every record of the session: (offset s, type, payload), in time order."""
    events: list[Event] = []
    vision = [os.urandom(1000 + 10 * c) for c in range(4)]
    for c in range(4):
        events += [(i / 60 + c / 240, TYPE_VISION_2014, vision[c])
                   for i in range(int(seconds * 60))]
    events += [(i / 40, TYPE_REFEREE_2013, os.urandom(180)) for i in range(int(seconds * 40))]
    events += [(i / 240, TYPE_TL_COMMANDS, os.urandom(120)) for i in range(int(seconds * 240))]
    events.sort(key=lambda e: e[0])
    return events


def run(events: list[Event], sink: Callable[[int, int, bytes], None]) -> tuple[float, float]:
    """Plays the events in real time into ``sink``; (cpu s, wall s)."""
    cpu0, wall0 = time.process_time(), time.monotonic()
    for offset, rtype, payload in events:
        delay = wall0 + offset - time.monotonic()
        if delay > 0.0005:
            time.sleep(delay)
        sink(time.time_ns(), rtype, payload)
    return time.process_time() - cpu0, time.monotonic() - wall0


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--seconds", type=float, default=10.0)
    args = ap.parse_args()
    events = schedule(args.seconds)

    def nothing(_t: int, _r: int, _p: bytes) -> None:
        pass

    base_cpu, base_wall = run(events, nothing)
    with tempfile.TemporaryDirectory() as tmp:
        rec = SessionRecorder(Path(tmp))
        cpu0 = time.process_time()
        cpu, wall = run(events, rec.record)
        rec.close()
        cpu_close = time.process_time() - cpu0 - cpu
        [path] = list(Path(tmp).glob("*.log"))
        size = path.stat().st_size
        n = sum(1 for _ in LogReader(str(path)))
    base = 100 * base_cpu / base_wall
    total = 100 * cpu / wall
    print(f"{len(events)} records in {wall:.1f} s ({len(events) / wall:.0f}/s), "
          f"file {size / 1e6:.1f} MB, {n} records read back, dropped {rec.dropped}")
    print(f"CPU with the recorder {total:.2f} % of one core, schedule alone {base:.2f} %: "
          f"recorder {total - base:.2f} % (goal <= 2 %); close() {cpu_close * 1000:.1f} ms CPU")


if __name__ == "__main__":
    main()
