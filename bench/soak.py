"""Soak of the whole station at full load (figures, not a test): issue 11's "zero datagrams
lost over 10 minutes" and "memory flat over 30 minutes".

Runs the launcher's station (8 cameras x 75 Hz, division A, 11 v 11, the "match" play) for
``--minutes`` (default 10) and reports, between minute 1 and the end:

- vision datagrams sent by fieldsim (from the frame numbers, which advance by one per frame
  sent: read by this script's own multicast listener, so it needs no counter of fieldsim's),
  received by the relay (its ``vision`` stream), decoded by the backend, overwritten on the
  backend's bus before it decoded them ("backend behind"), refused by the world model;
- command sets into the relay and command datagrams out of it;
- RSS of every process sampled every ``--sample`` seconds (10), and its growth from minute 1
  to the end; CPU of each over the window; the relay's arrival -> command p50 / p99.

The counts are exact: at both ends of the window fieldsim is paused (SIGSTOP) for a moment,
so no datagram is in flight while the counters are read, then resumed (SIGCONT).

    PYTHONPATH=. .venv/bin/python bench/soak.py [--minutes 10] [--json out.json]
"""

from __future__ import annotations

import argparse
import json
import os
import signal
import socket
import statistics
import sys
import threading
import time
from pathlib import Path
from typing import Any

import httpx

from bench.station_run import full_scale_args, start_station
from sslnet.multicast import open_multicast_receiver
from sslnet.proc import process_cpu_s as cpu_s
from sslpb import ssl_vision_wrapper_pb2 as wrapper_pb

ROOT = Path(__file__).resolve().parent.parent
PY = sys.executable



def rss_mb(pid: int) -> float:
    for line in Path(f"/proc/{pid}/status").read_text().splitlines():
        if line.startswith("VmRSS:"):
            return int(line.split()[1]) / 1024
    return -1.0


class Listener(threading.Thread):
    """The vision multicast, as a fourth party: the newest frame number of every camera."""

    def __init__(self, group: str, port: int) -> None:
        super().__init__(daemon=True)
        self.sock = open_multicast_receiver(group, port, "127.0.0.1")
        self.sock.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 8 << 20)
        self.sock.settimeout(0.5)
        self.last: dict[int, int] = {}
        self.received = 0
        self.geometry = 0  # geometry packets (they carry no number: counted as heard)
        self.lock = threading.Lock()
        self.stop = threading.Event()

    def run(self) -> None:
        while not self.stop.is_set():
            try:
                data = self.sock.recv(65536)
            except TimeoutError:
                continue
            p = wrapper_pb.SSL_WrapperPacket.FromString(data)
            with self.lock:
                if p.HasField("detection"):
                    self.last[p.detection.camera_id] = p.detection.frame_number
                    self.received += 1
                if p.HasField("geometry"):
                    self.geometry += 1

    def snapshot(self) -> tuple[dict[int, int], int, int]:
        """(newest frame number per camera, detections heard, geometry packets heard)."""
        with self.lock:
            return dict(self.last), self.received, self.geometry


def counters(h: dict[str, Any]) -> dict[str, float]:
    s = h["streams"]
    vis = s["vision"]
    rejected = h["world"]["rejected"]
    return {
        "relay_vision": s["relay.vision"]["packets"],
        "backend_decoded": vis["packets"],
        "backend_behind": vis["errors_by_reason"].get("backend behind", 0),
        "backend_errors": vis["errors"],
        "world_rejected": sum(rejected.values()) if isinstance(rejected, dict) else 0,
        "commands_in": s["relay.commands"]["packets"],
        "commands_out": s["relay.output"]["packets"],
        "relay_output_errors": s["relay.output"]["errors"],
    }


#: the relay's latency figures cover its last second: samples this soon after fieldsim's
#: pause are left out of the latency summary (kept for memory)
PAUSE_SETTLE_S = 2.5


def paused_snapshot(sim_pid: int, url: str, listener: Listener, client: httpx.Client
                    ) -> tuple[tuple[dict[int, int], int, int], dict[str, float]]:
    """Counters with fieldsim paused and the pipeline drained: the relay's figures come from
    its stats (once a second), so they count only once stats made after the pause arrived
    and two reads agree (bounded: 10 s)."""
    os.kill(sim_pid, signal.SIGSTOP)
    paused_ns = time.time_ns()
    try:
        before: dict[str, float] | None = None
        deadline = time.monotonic() + 10.0
        while time.monotonic() < deadline:
            time.sleep(0.2)
            h = client.get(url + "/api/health").json()
            if (h.get("relay") or {}).get("time_ns", 0) < paused_ns + 200_000_000:
                continue
            now = counters(h)
            if now == before:
                break
            before = now
        assert before is not None, "no relay stats after the pause"
        return listener.snapshot(), before
    finally:
        os.kill(sim_pid, signal.SIGCONT)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--minutes", type=float, default=10.0)
    ap.add_argument("--sample", type=float, default=10.0, help="seconds between samples")
    ap.add_argument("--cameras", type=int, default=8)
    ap.add_argument("--hz", type=float, default=75.0)
    ap.add_argument("--json", default=None, help="also write every sample here")
    a = ap.parse_args()
    err = open("/tmp/soak-station.log", "w")  # noqa: SIM115 - the station's whole life
    station = start_station(full_scale_args(a.cameras, a.hz), stderr=err)
    proc, pids, ports, url = station.proc, station.pids, station.ports, station.url
    pids["launcher"] = proc.pid
    listener = Listener(ports["vision_group"], ports["vision"])
    listener.start()
    client = httpx.Client(timeout=10)
    samples: list[dict[str, Any]] = []
    try:
        t_start = time.monotonic()
        time.sleep(max(0.0, 60.0 - (time.monotonic() - t_start)))  # minute 1: warm
        (frames0, heard0, geo0), c0 = paused_snapshot(pids["fieldsim"], url, listener, client)
        cpu0 = {k: cpu_s(p) for k, p in pids.items()}
        t0 = time.monotonic()
        end = t_start + a.minutes * 60.0
        while True:
            relay = client.get(url + "/api/health").json().get("relay") or {}
            samples.append({
                "t_s": round(time.monotonic() - t_start, 1),
                "rss_mb": {k: round(rss_mb(p), 1) for k, p in pids.items()},
                "p50_ms": relay.get("command_latency_p50_ms", -1),
                "p99_ms": relay.get("command_latency_p99_ms", -1),
                # fieldsim was paused for the counters just before t0: commands sent then
                # still carry the last frame's arrival (up to vision_stale_s old), so the
                # relay's figures of the first seconds measure the pause, not the station
                "after_pause": time.monotonic() - t0 < PAUSE_SETTLE_S,
            })
            left = end - time.monotonic()
            if left <= 0:
                break
            time.sleep(min(a.sample, left))
        (frames1, heard1, geo1), c1 = paused_snapshot(pids["fieldsim"], url, listener, client)
        dt = time.monotonic() - t0
        cpu = {k: (cpu_s(p) - cpu0[k]) / dt * 100 for k, p in pids.items()}
    finally:
        listener.stop.set()
        proc.terminate()
        proc.wait(timeout=30)
        err.close()
    detections = sum(frames1[k] - frames0.get(k, frames1[k]) for k in frames1)
    sent = detections + geo1 - geo0
    d = {k: c1[k] - c0[k] for k in c0}
    print(f"soak: {a.cameras} cameras x {a.hz:g} Hz, division A, 11 v 11, match play, "
          f"{a.minutes:g} min (window: minute 1 to the end, {dt:.0f} s)")
    print(f"vision datagrams: fieldsim sent {sent} ({detections} detection frames by their "
          f"numbers, of which this script heard {heard1 - heard0}; {geo1 - geo0} geometry), "
          f"relay received {d['relay_vision']:.0f} (lost {sent - d['relay_vision']:.0f}), "
          f"backend received {d['backend_decoded']:.0f}, of which overwritten before decoding "
          f"(backend behind) {d['backend_behind']:.0f}, other backend errors "
          f"{d['backend_errors'] - d['backend_behind']:.0f}, world rejected "
          f"{d['world_rejected']:.0f}")
    print(f"commands: {d['commands_in']:.0f} command sets into the relay, "
          f"{d['commands_out']:.0f} datagrams out ({d['commands_out'] / dt:.0f}/s), "
          f"send errors {d['relay_output_errors']:.0f}")
    print("| process | CPU % | RSS minute 1 MB | RSS end MB | max MB | growth |")
    print("|---|---|---|---|---|---|")
    for k in pids:
        series = [s["rss_mb"][k] for s in samples]
        growth = (series[-1] - series[0]) / series[0] * 100 if series and series[0] > 0 else 0
        print(f"| {k} | {cpu[k]:.1f} | {series[0]:.1f} | {series[-1]:.1f} | {max(series):.1f} | "
              f"{growth:+.1f} % |")
    p50 = [s["p50_ms"] for s in samples if s["p50_ms"] >= 0 and not s["after_pause"]]
    p99 = [s["p99_ms"] for s in samples if s["p99_ms"] >= 0 and not s["after_pause"]]
    if p50:
        print(f"relay arrival -> command: median of the samples' p50 {statistics.median(p50):.2f}"
              f" ms, of their p99 {statistics.median(p99):.2f} ms, worst p99 {max(p99):.2f} ms")
    if a.json:
        Path(a.json).write_text(json.dumps({"counters": d, "sent": sent, "cpu": cpu,
                                            "samples": samples}, indent=1))


if __name__ == "__main__":
    main()
