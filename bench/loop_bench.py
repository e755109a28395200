"""The control loop at full scale beside its floor (figures, not a test).

Both runs take the same input: the built-in simulator at 8 cameras x 75 Hz (600 vision
datagrams a second), division A, 11 v 11.
- **floor** (bench/floor/floor.py): the bare minimum of the same path from the same libraries,
  in two processes like the relay and the backend: UDP receive, ZeroMQ hop, protobuf parse, a
  trivial command per robot, ZeroMQ hop, RobotControl encode, UDP send.
- **floor + the paper's algorithms** (``floor.py bridge --algorithms``): the same with the
  paper's per-frame filters and speed control in the bridge, as plain and tight as Python
  allows: what any CPython station pays for them at this load.
- **Touchline**: the launcher's relay and backend (recording on, tracked vision out), the
  "match" play.
It prints each side's CPU (% of one core, from /proc over ``--seconds``) and the latency from a
vision datagram's arrival at the relay to the first command datagram it caused (Touchline: the
relay's own p50/p99 of each second, the median of them; floor: every frame), and the ratios;
and what a robot experiences, the age of the newest frame that saw it when its command is sent
(Touchline: the backend's p50/p99 of the last 2000 robot commands, each second, the median of
them; measured at the backend's send to the relay, one ZeroMQ hop before the relay's own send,
against the relay's receive stamps on this machine's wall clock; floor: each command set is
computed from one frame for the robots in it, so a robot's frame age is its set's latency).
Machines are noisy: the ratios of one run are the figures that count.

    PYTHONPATH=. .venv/bin/python bench/loop_bench.py [--seconds 20] [--cameras 8] [--hz 75]
        [--browser] [--camera-phases spread|together]
"""

from __future__ import annotations

import argparse
import json
import signal
import statistics
import subprocess
import sys
import time
from pathlib import Path
from typing import Any

import httpx

from backend.processors.publisher import FRAME_AGE_STAGE
from bench.station_run import full_scale_args, start_station
from launcher.supervisor import Ports
from sslnet.proc import process_cpu_s as cpu_s
from sslnet.proc import thread_cpu_s

ROOT = Path(__file__).resolve().parent.parent
PY = sys.executable


def sim_args(a: argparse.Namespace) -> list[str]:
    return ["--division", "A", "--blue", str(a.robots), "--yellow", str(a.robots), "--cameras",
            str(a.cameras), "--camera-hz", str(a.hz), "--camera-phases", a.camera_phases]


def measure(pids: dict[str, int], seconds: float) -> dict[str, float]:
    c0 = {k: cpu_s(p) for k, p in pids.items()}
    t0 = time.monotonic()
    time.sleep(seconds)
    dt = time.monotonic() - t0
    return {k: (cpu_s(p) - c0[k]) / dt * 100 for k, p in pids.items()}


def floor(a: argparse.Namespace, algorithms: bool = False) -> dict[str, Any]:
    p = Ports.isolated(None)
    pub, sub = f"tcp://127.0.0.1:{p.http + 1}", f"tcp://127.0.0.1:{p.http + 2}"
    procs = {
        "sim": subprocess.Popen([PY, "-m", "fieldsim", *sim_args(a), "--vision-port",
                                 str(p.vision), "--control-port", str(p.sim_control),
                                 "--blue-port", str(p.sim_blue), "--yellow-port",
                                 str(p.sim_yellow), "--grsim-port", str(p.grsim)],
                                cwd=ROOT, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL),
        "relay": subprocess.Popen([PY, "bench/floor/floor.py", "relay", "--vision",
                                   f"{p.vision_group}:{p.vision}", "--pub", pub, "--sub", sub,
                                   "--out", f"127.0.0.1:{p.sim_blue}"], cwd=ROOT,
                                  stdout=subprocess.PIPE, text=True),
        "backend": subprocess.Popen([PY, "bench/floor/floor.py", "bridge", "--pub", sub, "--sub",
                                     pub, *(["--algorithms"] if algorithms else [])], cwd=ROOT),
    }
    try:
        time.sleep(a.warmup)
        cpu = measure({k: v.pid for k, v in procs.items()}, a.seconds)
    finally:
        procs["relay"].send_signal(signal.SIGTERM)
        out, _ = procs["relay"].communicate(timeout=10)
        for k in ("backend", "sim"):
            procs[k].terminate()
            procs[k].wait(timeout=10)
    lat = json.loads(out.strip().splitlines()[-1])
    # each of the floor's command sets is computed from the one frame that caused it, for
    # the robots in that frame: every robot's frame age is its set's latency
    return {**cpu, "p50_ms": lat["p50_ms"], "p99_ms": lat["p99_ms"],
            "age_p50_ms": lat["p50_ms"], "age_p99_ms": lat["p99_ms"]}


def thread_cpu_by_name(pid: int) -> dict[str, float]:
    """CPU seconds of each thread of ``pid`` by thread name (threads of one name summed)."""
    out: dict[str, float] = {}
    for (name, _tid), seconds in thread_cpu_s(pid).items():
        out[name] = out.get(name, 0.0) + seconds
    return out


def frames_and_passes(health: dict[str, Any]) -> tuple[int, int]:
    """The vision frames the backend took so far and its world model's runs (one a pass
    that brought frames)."""
    runs = {p["name"]: p["runs"] for p in health["processors"]}
    return health["streams"]["vision"]["packets"], runs["world-model"]


def touchline(a: argparse.Namespace, browser: bool = False) -> dict[str, Any]:
    """Touchline's row; ``browser``: with headless Chromium showing the page meanwhile (its
    own CPU apart: only the relay's and the backend's count)."""
    station = start_station(full_scale_args(a.cameras, a.hz, a.relay_arg, a.robots,
                                            a.camera_phases))
    proc, pids, url = station.proc, station.pids, station.url
    page: subprocess.Popen[str] | None = None
    try:
        if browser:
            page = subprocess.Popen(
                ["node", "bench/open_page.mjs", url, str(a.warmup + a.seconds + 30)], cwd=ROOT,
                stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True)
            assert page.stdout is not None
            for line in page.stdout:  # the page shows the field (bounded: the script's own
                if line.startswith("PAGE_OPEN"):  # 30 s timeout ends it otherwise)
                    break
        time.sleep(a.warmup)
        client = httpx.Client(timeout=5)
        p50s: list[float] = []
        p99s: list[float] = []
        age50s: list[float] = []
        age99s: list[float] = []
        passes0 = frames_and_passes(client.get(url + "/api/health").json())
        c0 = {k: cpu_s(v) for k, v in pids.items()}
        th0 = thread_cpu_by_name(pids["backend"])
        t0 = time.monotonic()
        while time.monotonic() - t0 < a.seconds:
            time.sleep(1.0)
            h = client.get(url + "/api/health").json()
            r = h["relay"] or {}
            if r.get("command_latency_p50_ms", -1) >= 0:
                p50s.append(r["command_latency_p50_ms"])
                p99s.append(r["command_latency_p99_ms"])
            age = next((s for s in h["latency_stages"] if s["stage"] == FRAME_AGE_STAGE), None)
            if age is not None and age["n"]:
                age50s.append(age["p50_ms"])
                age99s.append(age["p99_ms"])
        dt = time.monotonic() - t0
        passes1 = frames_and_passes(h)
        th1 = thread_cpu_by_name(pids["backend"])
        threads = {k: (v - th0.get(k, 0.0)) / dt * 100 for k, v in th1.items()}
        cpu = {("sim" if k == "fieldsim" else k): (cpu_s(v) - c0[k]) / dt * 100
               for k, v in pids.items()}
    finally:
        if page is not None:
            page.terminate()
            page.wait(timeout=20)
        proc.terminate()
        proc.wait(timeout=20)
    return {**cpu, "p50_ms": statistics.median(p50s) if p50s else -1,
            "p99_ms": statistics.median(p99s) if p99s else -1,
            "p99_worst_ms": max(p99s) if p99s else -1, "threads": threads,
            "age_p50_ms": statistics.median(age50s) if age50s else -1,
            "age_p99_ms": statistics.median(age99s) if age99s else -1,
            "frames_a_pass": (passes1[0] - passes0[0]) / max(1, passes1[1] - passes0[1])}


def loadavg() -> str:
    with open("/proc/loadavg") as f:
        return " ".join(f.read().split()[:3])


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--seconds", type=float, default=20.0)
    ap.add_argument("--warmup", type=float, default=5.0)
    ap.add_argument("--cameras", type=int, default=8)
    ap.add_argument("--hz", type=float, default=75.0)
    ap.add_argument("--camera-phases", choices=["spread", "together"], default="spread",
                    help="fieldsim's cameras: each its own phase (spread), or all captured at "
                         "once and sent back to back (together, as grSim does)")
    ap.add_argument("--robots", type=int, default=11,
                    help="robots a team (11: the goal's load; 1: the same frames with almost no "
                         "robot in them, the framework's own cost)")
    ap.add_argument("--relay-arg", action="append", default=[],
                    help="an argument for Touchline's relay (repeat it), e.g. --min-gap=0")
    ap.add_argument("--no-floor", action="store_true", help="Touchline's row only")
    ap.add_argument("--browser", action="store_true",
                    help="also a row with headless Chromium rendering the page (node, "
                         "/usr/bin/chromium)")
    a = ap.parse_args()
    load0 = loadavg()
    t = touchline(a)
    if a.no_floor:
        print(f"Touchline: relay {t['relay']:.1f} % backend {t['backend']:.1f} % "
              f"simulator {t['sim']:.1f} %, arrival -> command p50 {t['p50_ms']:.2f} ms "
              f"p99 {t['p99_ms']:.2f} ms (worst 1 s p99 {t['p99_worst_ms']:.2f} ms), "
              f"robot's frame age p50 {t['age_p50_ms']:.2f} ms p99 {t['age_p99_ms']:.2f} ms, "
              f"{t['frames_a_pass']:.2f} frames a pass, cameras {a.camera_phases}, load average "
              f"{load0} -> {loadavg()}")
        print("backend threads (% of one core): " + ", ".join(
            f"{k} {v:.1f}" for k, v in sorted(t["threads"].items(), key=lambda kv: -kv[1])
            if v >= 0.05))
        return
    f = floor(a)
    rows = [("floor", f), ("floor + the paper's algorithms in plain Python", floor(a, True)),
            ("Touchline", t)]
    if a.browser:
        rows.append(("Touchline, a Chromium page open", touchline(a, browser=True)))
    print(f"control loop, {a.cameras} cameras x {a.hz:g} Hz ({a.camera_phases}), division A, "
          f"{a.robots} v {a.robots}, "
          f"{a.seconds:g} s (CPU in % of one core)")
    print("| | relay | backend | relay + backend | arrival -> command p50 | p99 | "
          "robot's frame age p50 | p99 | simulator |")
    print("|---|---|---|---|---|---|---|---|---|")
    for name, r in rows:
        print(f"| {name} | {r['relay']:.1f} | {r['backend']:.1f} | "
              f"{r['relay'] + r['backend']:.1f} | {r['p50_ms']:.2f} ms | {r['p99_ms']:.2f} ms | "
              f"{r['age_p50_ms']:.2f} ms | {r['age_p99_ms']:.2f} ms | {r['sim']:.1f} |")

    def x(k: str) -> str:
        return f"{t[k] / max(1e-9, f[k]):.1f}x"

    ratio = (t["relay"] + t["backend"]) / max(1e-9, f["relay"] + f["backend"])
    print(f"| Touchline / floor | {x('relay')} | {x('backend')} | {ratio:.1f}x | "
          f"{x('p50_ms')} | {x('p99_ms')} | {x('age_p50_ms')} | {x('age_p99_ms')} | |")
    print(f"(Touchline's worst one-second p99: {t['p99_worst_ms']:.2f} ms; "
          f"{t['frames_a_pass']:.2f} camera frames a pass; cameras {a.camera_phases}; "
          f"load average {load0} at the start, {loadavg()} at the end)")


if __name__ == "__main__":
    main()
