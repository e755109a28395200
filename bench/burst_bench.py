"""How often camera frames arrive in bursts (figures, not a test; issue 29).

Runs fieldsim as the loop benches do (8 cameras x 75 Hz, division A, 11 v 11) once per
camera timing (``--camera-phases``: spread, each camera its own phase; together, every camera
captures at once and the frames go out back to back, as grSim sends its four cameras in one
burst per step, ``sendVisionBuffer``) and listens to its vision multicast on loopback like the
relay does, with the kernel's receive time of every datagram (SO_TIMESTAMPNS: this script's
own scheduling does not count). A frame is *in a burst* when it arrived within ``--window-ms``
(0.3) of the frame before it: the relay reads such frames in one wake-up and the backend can
take them in one pass. Prints, per timing: detection frames a second, the share of frames in
a burst, the bursts' sizes (frames that came together), and the span of a whole burst (first
to last arrival), with the load average.

The backend's side of it (camera frames a pass) is ``bench/loop_bench.py``'s
``frames a pass``.

    PYTHONPATH=. .venv/bin/python bench/burst_bench.py [--seconds 10]
        [--camera-phases spread|together|both] [--window-ms 0.3]
"""

from __future__ import annotations

import argparse
import itertools
import random
import statistics
import subprocess
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from sslpb.ssl_vision_wrapper_pb2 import SSL_WrapperPacket
from tests.integration.standins import Arrivals

ROOT = Path(__file__).resolve().parents[1]
GROUP = "224.5.23.2"


def run(phases: str, seconds: float, window_s: float, cameras: int, hz: float) -> str:
    port = random.SystemRandom().randint(20000, 40000)
    frames = Arrivals(GROUP, port, rcvbuf=4 << 20, keep_data=True)
    sim = subprocess.Popen(
        [sys.executable, "-m", "fieldsim", "--division", "A", "--blue", "11", "--yellow", "11",
         "--cameras", str(cameras), "--camera-hz", str(hz), "--camera-phases", phases,
         "--vision-group", GROUP, "--vision-port", str(port), "--interface", "127.0.0.1",
         "--control-port", "0", "--blue-port", "0", "--yellow-port", "0", "--grsim-port", "0",
         "--grsim-status-blue-port", "0", "--grsim-status-yellow-port", "0",
         "--log-level", "WARNING"], cwd=ROOT)
    try:
        time.sleep(3.0)  # fieldsim's start-up (imports, the first frames)
        t0 = time.time()
        time.sleep(seconds)
        t1 = time.time()
    finally:
        sim.terminate()
        sim.wait(timeout=10)
        frames.close()
    assert frames.datagrams is not None
    # the detection frames of the measured window (not the geometry packets)
    times = [t for t, data in frames.datagrams
             if t0 <= t <= t1 and SSL_WrapperPacket.FromString(data).HasField("detection")]
    if len(times) < 2:
        return f"{phases}: no frames heard"
    gaps = [b - a for a, b in itertools.pairwise(times)]
    together = [g <= window_s for g in gaps]
    bursts: list[list[float]] = [[times[0]]]
    for t, joined in zip(times[1:], together, strict=True):
        if joined:
            bursts[-1].append(t)
        else:
            bursts.append([t])
    sizes = sorted(len(b) for b in bursts)
    multi = [b for b in bursts if len(b) > 1]
    spans = sorted((b[-1] - b[0]) * 1e3 for b in multi)
    rate = len(times) / (times[-1] - times[0])

    def pct(v: list[float], q: float) -> float:
        return v[min(len(v) - 1, int(q * len(v)))] if v else 0.0

    return (f"{phases}: {rate:.0f} frames/s, {100 * sum(together) / len(gaps):.1f} % within "
            f"{window_s * 1e3:g} ms of the frame before; {len(bursts) / (times[-1] - times[0]):.0f}"
            f" arrivals a second (a burst counted once), frames a burst mean "
            f"{statistics.fmean(sizes):.2f}, max {sizes[-1]}; a burst of 2+ spans p50 "
            f"{pct(spans, 0.5):.3f} ms, p99 {pct(spans, 0.99):.3f} ms")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--seconds", type=float, default=10.0)
    ap.add_argument("--camera-phases", choices=["spread", "together", "both"], default="both")
    ap.add_argument("--window-ms", type=float, default=0.3)
    ap.add_argument("--cameras", type=int, default=8)
    ap.add_argument("--hz", type=float, default=75.0)
    a = ap.parse_args()
    with open("/proc/loadavg") as f:
        print(f"load average at the start: {' '.join(f.read().split()[:3])}")
    for phases in (["spread", "together"] if a.camera_phases == "both" else [a.camera_phases]):
        print(run(phases, a.seconds, a.window_ms / 1e3, a.cameras, a.hz), flush=True)


if __name__ == "__main__":
    main()
