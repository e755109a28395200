"""Restart benchmark (not a test): how soon is a restarted relay back in the backend's data?

Issue 12 asks: "a restarted relay is back in the backend's data within 250 ms of starting".
This starts the station's three processes with the launcher's own supervisor (fieldsim, the
relay, the backend, isolated ports and a temporary state folder), waits until the backend is
healthy, then ``--kills`` times: SIGKILLs the relay and lets ``Supervisor.watch`` (the
launcher's restart, with its backoff) start a new one, and measures from the new relay's
``Popen`` (its process start):

* ``bound``: the relay's PUB port accepts a TCP connection (interpreter, imports, sockets);
* ``first frame``: the capture time of the first world the backend merged from a frame
  captured after that start (so it came through the new relay); a frame reaches the backend
  about a millisecond after its capture, so this is when the data was back, whatever the
  polling below;
* ``seen``: when this program's poll of ``GET /api/world`` (every ``--poll-ms``) first saw it
  (an upper bound).

Usage: .venv/bin/python bench/restart_bench.py [--kills 5] [--poll-ms 5]
"""

from __future__ import annotations

import argparse
import json
import os
import signal
import socket
import statistics
import sys
import tempfile
import time
import urllib.request
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from launcher.supervisor import Ports, StationConfig, Supervisor, command_lines  # noqa: E402


def get(url: str) -> Any:
    with urllib.request.urlopen(url, timeout=2.0) as r:
        return json.loads(r.read())


def wait(cond: Any, timeout_s: float, what: str, interval_s: float = 0.005) -> Any:
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        try:
            got = cond()
        except OSError:
            got = None
        if got:
            return got
        time.sleep(interval_s)
    raise SystemExit(f"timed out after {timeout_s} s waiting for {what}")


def port_open(endpoint: str) -> bool:
    host, port = endpoint.removeprefix("tcp://").rsplit(":", 1)
    with socket.socket() as s:
        s.settimeout(0.05)
        return s.connect_ex((host, int(port))) == 0


def ms_summary(name: str, values_s: list[float]) -> str:
    v = sorted(x * 1000 for x in values_s)
    return (f"{name:<34} min {v[0]:7.1f}  median {statistics.median(v):7.1f}  "
            f"max {v[-1]:7.1f} ms  (n={len(v)})")


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--kills", type=int, default=5)
    ap.add_argument("--poll-ms", type=float, default=5.0)
    ap.add_argument("--logs", type=Path, default=None,
                    help="keep the children's logs in this folder (default: a temporary one)")
    args = ap.parse_args()
    poll_s = args.poll_ms / 1000

    with tempfile.TemporaryDirectory(prefix="touchline-restart-") as tmp:
        ports = Ports.isolated(None)
        cfg = StationConfig(state_dir=str(Path(tmp) / "state"),
                            backend_args=["--no-record"])
        sup = Supervisor(command_lines(cfg, ports), log_dir=args.logs or Path(tmp) / "logs",
                         restart=True,
                         max_restarts=args.kills + 1)
        base = f"http://127.0.0.1:{ports.http}"
        sup.start()
        bound_s: list[float] = []
        first_s: list[float] = []
        seen_s: list[float] = []
        try:
            wait(lambda: get(base + "/api/health")["ok"], 90, "a healthy station", 0.2)
            relay = sup.child("relay")
            for i in range(args.kills):
                time.sleep(1.0)  # the station settles (and the relay's stats are published)
                assert relay.proc is not None
                os.kill(relay.proc.pid, signal.SIGKILL)
                relay.proc.wait()
                wait(lambda: sup.watch() is None and relay.proc is not None
                     and relay.proc.poll() is None, 10, "the restart")
                started_mono = relay.started
                started_unix = time.time() - (time.monotonic() - started_mono)
                wait(lambda: port_open(ports.relay_pub), 30, "the new relay bound", 0.001)
                bound_s.append(time.monotonic() - started_mono)

                def fresh(after: float = started_unix) -> float | None:
                    t: float = get(base + "/api/world")["t_capture"]
                    return t if t > after else None
                t_capture = wait(fresh, 30, "a world from the new relay", poll_s)
                seen_s.append(time.monotonic() - started_mono)
                first_s.append(t_capture - started_unix)
                print(f"restart {i + 1}: bound {bound_s[-1] * 1000:6.1f} ms, first frame "
                      f"{first_s[-1] * 1000:6.1f} ms, seen {seen_s[-1] * 1000:6.1f} ms "
                      "after the new relay's start", flush=True)
        finally:
            sup.stop()
    print()
    print(ms_summary("start -> relay bound", bound_s))
    print(ms_summary("start -> first frame in the backend", first_s))
    print(ms_summary("bound -> first frame in the backend",
                     [f - b for f, b in zip(first_s, bound_s, strict=True)]))
    print(ms_summary(f"start -> seen (poll {args.poll_ms:g} ms)", seen_s))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
