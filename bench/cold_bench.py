"""What a frame costs hot and what it costs with the live gap between frames (figures, not a
test): issue 29 measures Touchline against a floor that does almost nothing a frame, on a
machine where the same work costs more the longer the CPU idled before it.

The same synthetic camera frames as ``pipeline_bench.py`` (8 cameras x 75 Hz, division A,
11 v 11) go, one frame a pass, through
- **floor**: the floor bridge's work a frame (bench/floor/floor.py: parse, a trivial command
  per blue robot, encode),
- **floor + algorithms**: the same with the paper's filters and speed control in plain Python
  (floor.py's ``--algorithms``),
- **Touchline**: the station's hot path (vision decoding, world model with the default
  filter, control, command and tracked-vision publishers; pipeline_bench's ``run``),
with a sleep of ``gap`` after each frame (0: a hot loop; 1.67 ms: 600 frames a second, the
live arrival; 5 ms). Each figure is the process's CPU a frame, less what the sleep alone costs
(a loop of sleeps, measured the same way). The ZeroMQ hops, the relay and the event loop are
in none of them: this is the work itself, hot and cold.

    PYTHONPATH=. .venv/bin/python bench/cold_bench.py [--frames 3000] [--gaps 0,1.67,5]
"""

from __future__ import annotations

import argparse
import asyncio
import importlib.util
import sys
import time
from collections.abc import Callable
from pathlib import Path
from types import ModuleType

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from bench.pipeline_bench import datagrams, run  # noqa: E402
from sslpb import touchline_pb2 as tl  # noqa: E402
from sslpb.ssl_vision_wrapper_pb2 import SSL_WrapperPacket  # noqa: E402

WARMUP = 600


def _floor_module() -> ModuleType:
    """bench/floor/floor.py, imported by path (it is a script, not a package)."""
    spec = importlib.util.spec_from_file_location("floor_bridge", ROOT / "bench/floor/floor.py")
    assert spec is not None and spec.loader is not None
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def floor_frame(algorithms: bool) -> Callable[[int, bytes], bytes]:
    """The floor bridge's loop body (after its ``recv``), as a function of one frame."""
    fl = _floor_module()
    tracks: dict[tuple[int, int], object] = {}
    seq = 0

    def one(recv_ns: int, raw: bytes) -> bytes:
        nonlocal seq
        pkt = SSL_WrapperPacket.FromString(raw)
        seq += 1
        cset = tl.RobotCommandSet(created_time_ns=time.time_ns(), source_receive_time_ns=recv_ns,
                                  sequence=seq)
        if algorithms:
            fl._algorithms(pkt, tracks, cset)
        else:
            for r in pkt.detection.robots_blue:
                cset.commands.add(team=tl.TEAM_BLUE, id=r.robot_id)
        return bytes(cset.SerializeToString())

    return one


def floor_us(frames: list[tuple[int, bytes]], algorithms: bool, gap_s: float) -> float:
    one = floor_frame(algorithms)
    cpu0 = 0.0
    for i, (recv_ns, raw) in enumerate(frames):
        if i == WARMUP:
            cpu0 = time.process_time()
        one(recv_ns, raw)
        if gap_s > 0:
            time.sleep(gap_s)
    return (time.process_time() - cpu0) / (len(frames) - WARMUP) * 1e6


def sleep_us(n: int, gap_s: float) -> float:
    """What a sleep of ``gap_s`` alone costs the process (its system calls), a sleep."""
    if gap_s <= 0:
        return 0.0
    cpu0 = time.process_time()
    for _ in range(n):
        time.sleep(gap_s)
    return (time.process_time() - cpu0) / n * 1e6


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--frames", type=int, default=3000)
    ap.add_argument("--gaps", default="0,1.67,5", help="ms after each frame, comma-separated")
    ap.add_argument("--reps", type=int, default=2, help="best of this many runs a cell")
    a = ap.parse_args()
    gaps = [float(g) / 1000.0 for g in a.gaps.split(",")]
    frames = datagrams(a.frames + WARMUP, time.time())
    rows: dict[str, list[float]] = {"floor": [], "floor + algorithms": [], "Touchline": []}
    for gap in gaps:
        base = min(sleep_us(min(a.frames, 1000), gap) for _ in range(a.reps))
        rows["floor"].append(min(floor_us(frames, False, gap) for _ in range(a.reps)) - base)
        rows["floor + algorithms"].append(
            min(floor_us(frames, True, gap) for _ in range(a.reps)) - base)
        touch = min(sum(asyncio.run(run(frames, 1, WARMUP, gap)).values())
                    for _ in range(a.reps))
        rows["Touchline"].append(touch - base)
    load = " ".join(Path("/proc/loadavg").read_text().split()[:3])
    head = " | ".join(f"{g * 1000:g} ms gap" for g in gaps)
    print(f"CPU a frame in us, one frame a pass, the sleep's own cost taken off "
          f"({a.frames} frames; load {load})")
    print(f"| | {head} | cold / hot |")
    print("|---|" + "---|" * (len(gaps) + 1))
    for name, us in rows.items():
        cells = " | ".join(f"{u:.1f}" for u in us)
        print(f"| {name} | {cells} | {us[-1] / us[0]:.1f}x |")
    ours, bare = rows["Touchline"], rows["floor"]
    print("| Touchline / floor | " + " | ".join(f"{x / y:.1f}x"
                                              for x, y in zip(ours, bare, strict=True))
          + " | |")


if __name__ == "__main__":
    main()
