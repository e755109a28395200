"""The relay's profile in the full station (figures, not a test): issue 11 wants a profile
before and after every change to the relay's hot path.

Starts the launcher's station (8 cameras x 75 Hz, division A, 11 v 11, the "match" play) with
the relay under cProfile (``--relay-arg=--profile=FILE``), lets it run ``--seconds``, stops the
station (the relay writes its profile on its normal shutdown) and prints the top of it by
internal time and by cumulative time. cProfile slows the relay down: read the shares, and
take CPU figures from bench/loop_bench.py.

    PYTHONPATH=. .venv/bin/python bench/relay_profile.py [--seconds 30] [--out /tmp/relay.prof]
"""

from __future__ import annotations

import argparse
import pstats
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--seconds", type=float, default=30.0)
    ap.add_argument("--cameras", type=int, default=8)
    ap.add_argument("--hz", type=float, default=75.0)
    ap.add_argument("--out", default="/tmp/relay.prof")
    ap.add_argument("--top", type=int, default=25)
    a = ap.parse_args()
    out = Path(a.out)
    out.unlink(missing_ok=True)
    sim = ["--division", "A", "--blue", "11", "--yellow", "11", "--cameras", str(a.cameras),
           "--camera-hz", str(a.hz)]
    proc = subprocess.Popen(
        [sys.executable, "-m", "launcher", "--isolated", *(f"--sim-arg={x}" for x in sim),
         "--backend-arg=--set", "--backend-arg=strategy.play=match",
         f"--relay-arg=--profile={out}"],
        cwd=ROOT, stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True)
    assert proc.stdout is not None
    for line in proc.stdout:
        if line.startswith("TOUCHLINE_READY "):
            break
    else:
        raise SystemExit("station did not start")
    time.sleep(a.seconds)
    proc.terminate()
    proc.wait(timeout=30)
    deadline = time.monotonic() + 10
    while not out.exists() and time.monotonic() < deadline:
        time.sleep(0.1)  # polled: the relay writes it while it exits
    st = pstats.Stats(str(out))
    st.strip_dirs().sort_stats("tottime").print_stats(a.top)
    st.sort_stats("cumulative").print_stats(a.top)


if __name__ == "__main__":
    main()
