"""The relay alone under the full camera load (figures, not a test).

fieldsim at 8 cameras x 75 Hz (division A, 11 v 11) -> ``python -m larcmacs_relay`` -> a
stand-in backend (a thread: every vision Envelope answered at once by a RobotCommandSet for 11
robots, like bench/floor's bridge) -> the relay -> fieldsim. Only the relay's code differs
between runs, so its CPU (% of one core, /proc) and its own arrival -> command latency (p50,
p99 from its RelayStats) compare variants on a busy machine better than the whole station
does. Variants are run alternately, ``--rounds`` times each.

    PYTHONPATH=. .venv/bin/python bench/relay_load.py [--seconds 15] [--rounds 2] \\
        [--variant NAME=ARGS ...]   e.g. --variant "uvloop=--event-loop=uvloop"
"""

from __future__ import annotations

import argparse
import os
import shlex
import signal
import statistics
import subprocess
import sys
import threading
import time
from pathlib import Path

import zmq

from launcher.supervisor import Ports
from sslnet.proc import process_cpu_s as cpu_s
from sslpb import touchline_pb2 as tl

ROOT = Path(__file__).resolve().parent.parent


def backend(pub_ep: str, sub_ep: str, stop: threading.Event, stats: list[tl.RelayStats]) -> None:
    """Answers every vision datagram with commands for blue 0..10; keeps the relay's stats."""
    ctx = zmq.Context()
    sub = ctx.socket(zmq.SUB)
    sub.setsockopt(zmq.SUBSCRIBE, b"vision")
    sub.setsockopt(zmq.SUBSCRIBE, b"stats")
    sub.connect(pub_ep)
    pub = ctx.socket(zmq.PUB)
    pub.connect(sub_ep)
    seq = 0
    try:
        while not stop.is_set():
            if not sub.poll(200):
                continue
            topic, body = sub.recv_multipart()
            if topic == b"stats":
                stats.append(tl.RelayStats.FromString(body))
                continue
            env = tl.Envelope.FromString(body)
            seq += 1
            cset = tl.RobotCommandSet(source_receive_time_ns=env.receive_time_ns, sequence=seq)
            for i in range(11):
                cset.commands.add(team=tl.TEAM_BLUE, id=i, forward_mps=0.1 * (seq % 10))
            pub.send_multipart([b"commands", cset.SerializeToString()])
    finally:
        ctx.destroy(linger=0)


def run(a: argparse.Namespace, extra: list[str], root: Path = ROOT) -> dict[str, float]:
    p = Ports.isolated(None)
    pub_ep, sub_ep = f"tcp://127.0.0.1:{p.http + 1}", f"tcp://127.0.0.1:{p.http + 2}"
    sim = subprocess.Popen(
        [sys.executable, "-m", "fieldsim", "--division", "A", "--blue", "11", "--yellow", "11",
         "--cameras", str(a.cameras), "--camera-hz", str(a.hz), "--vision-port", str(p.vision),
         "--control-port", str(p.sim_control), "--blue-port", str(p.sim_blue), "--yellow-port",
         str(p.sim_yellow), "--grsim-port", str(p.grsim), "--grsim-status-blue-port", "0",
         "--grsim-status-yellow-port", "0", "--log-level", "WARNING"],
        cwd=ROOT)
    relay = subprocess.Popen(
        [sys.executable, "-m", "larcmacs_relay", "--vision", f"{p.vision_group}:{p.vision}",
         "--referee", f"{p.referee_group}:{p.referee}", "--pub", pub_ep, "--sub", sub_ep,
         "--sim-control-port", str(p.sim_control), "--sim-blue-port", str(p.sim_blue),
         "--sim-yellow-port", str(p.sim_yellow), "--grsim-port", str(p.grsim),
         "--no-tracker-out", "--log-level", "WARNING", *extra],
        cwd=root, env=dict(os.environ, PYTHONPATH=str(ROOT)))
    stop = threading.Event()
    stats: list[tl.RelayStats] = []
    th = threading.Thread(target=backend, args=(pub_ep, sub_ep, stop, stats), daemon=True)
    th.start()
    try:
        time.sleep(a.warmup)
        n0 = len(stats)
        c0, s0, t0 = cpu_s(relay.pid), cpu_s(sim.pid), time.monotonic()
        time.sleep(a.seconds)
        dt = time.monotonic() - t0
        relay_cpu = (cpu_s(relay.pid) - c0) / dt * 100
        sim_cpu = (cpu_s(sim.pid) - s0) / dt * 100
        window = [s for s in stats[n0:] if s.command_latency_p50_ms >= 0]
        vision = [next(x for x in s.streams if x.name == "vision").rate_hz for s in stats[n0:]]
    finally:
        stop.set()
        relay.send_signal(signal.SIGTERM)
        sim.terminate()
        for proc in (relay, sim):
            try:
                proc.wait(timeout=10)
            except subprocess.TimeoutExpired:
                proc.kill()
        th.join(timeout=5)
    return {
        "relay": relay_cpu, "sim": sim_cpu,
        "vision_hz": statistics.median(vision) if vision else -1.0,
        "p50": statistics.median(s.command_latency_p50_ms for s in window) if window else -1,
        "p99": statistics.median(s.command_latency_p99_ms for s in window) if window else -1,
        "out_hz": statistics.median(s.output_rate_hz for s in window) if window else -1,
    }


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--seconds", type=float, default=15.0)
    ap.add_argument("--warmup", type=float, default=4.0)
    ap.add_argument("--rounds", type=int, default=2)
    ap.add_argument("--cameras", type=int, default=8)
    ap.add_argument("--hz", type=float, default=75.0)
    ap.add_argument("--variant", action="append", default=[], metavar="NAME=ARGS",
                    help="relay arguments of a variant (the default variant has none)")
    ap.add_argument("--before", type=Path, default=None, metavar="DIR",
                    help="a variant 'before': the larcmacs_relay package in DIR (e.g. from "
                         "git archive OLD larcmacs_relay | tar -x -C DIR), the rest from here")
    a = ap.parse_args()
    variants: list[tuple[str, list[str]]] = [("default", [])]
    variants += [(v.split("=", 1)[0], shlex.split(v.split("=", 1)[1])) for v in a.variant]
    if a.before is not None:
        variants.insert(0, ("before", []))
    results: dict[str, list[dict[str, float]]] = {name: [] for name, _ in variants}
    for _ in range(a.rounds):
        for name, extra in variants:
            root = a.before.resolve() if name == "before" and a.before is not None else ROOT
            results[name].append(run(a, extra, root))
    print(f"relay alone, {a.cameras} cameras x {a.hz:g} Hz, 11 v 11, a stand-in backend "
          f"answering every frame; {a.seconds:g} s x {a.rounds} rounds (medians)")
    print("| variant | relay CPU % | vision Hz | output cycles/s | arrival -> command p50 | "
          "p99 | simulator CPU % |")
    print("|---|---|---|---|---|---|---|")
    for name, rs in results.items():
        def med(k: str, rs: list[dict[str, float]] = rs) -> float:
            return statistics.median(r[k] for r in rs)
        each = ", ".join(f"{r['relay']:.1f}" for r in rs)
        print(f"| {name} | {med('relay'):.1f} ({each}) | "
              f"{med('vision_hz'):.0f} | {med('out_hz'):.0f} | {med('p50'):.2f} ms | "
              f"{med('p99'):.2f} ms | {med('sim'):.1f} |")


if __name__ == "__main__":
    main()
