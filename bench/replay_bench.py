"""Benchmark of record and replay through the real station (figures, not a test).

1. Replay speed: a 4-camera log (the recorded fieldsim session of tests/data, repeated with
   its times shifted to make a longer match) played "as fast as possible" through the whole
   pipeline (ingest, world model, strategy, control; nothing sent): log seconds per wall second.
2. A match-sized log (``--mb``, default 700): the station opens it (index built once), then
   random seeks are timed from the request to the world at the new position (0.3 s of log
   pre-rolled through the pipeline each time); the backend's memory (peak RSS) is read.
3. Recording cost: the backend's CPU with the built-in simulator (4 cameras x 60 Hz) with
   and without recording (--no-record), in the same run.

Run: ``PYTHONPATH=. .venv/bin/python bench/replay_bench.py [--mb 700] [--seconds 60]``."""

from __future__ import annotations

import argparse
import random
import statistics
import tempfile
import time
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

import httpx

from bench.station_run import start_station
from ssllog.format import (
    RECORD_HEADER,
    TYPE_REFEREE_2013,
    TYPE_TRACKER_2020,
    TYPE_VISION_2014,
    file_header,
)
from ssllog.reader import LogReader
from sslnet.proc import process_cpu_s as cpu_s
from sslpb.ssl_gc_referee_message_pb2 import Referee
from sslpb.ssl_vision_wrapper_pb2 import SSL_WrapperPacket
from sslpb.ssl_vision_wrapper_tracked_pb2 import TrackerWrapperPacket

ROOT = Path(__file__).resolve().parent.parent
FIXTURE = ROOT / "tests" / "data" / "fieldsim-2s.log.gz"
JSON = {"content-type": "application/json"}
#: one client for every request (a new httpx client per request costs tens of ms: it makes
#: an SSL context), so the figures are the station's, not the client's
HTTP = httpx.Client(timeout=30)


def _shifted(rtype: int, payload: bytes, shift_s: float) -> bytes:
    """The record with every time inside it moved by ``shift_s`` (so the camera clock check
    sees one continuous match, not the same 2.5 s again and again)."""
    if rtype == TYPE_VISION_2014:
        w = SSL_WrapperPacket()
        w.ParseFromString(payload)
        if w.HasField("detection"):
            d = w.detection
            d.t_capture += shift_s
            d.t_sent += shift_s
            if d.HasField("t_capture_camera"):
                d.t_capture_camera += shift_s
        return w.SerializeToString()
    if rtype == TYPE_REFEREE_2013:
        r = Referee()
        r.ParseFromString(payload)
        r.packet_timestamp += int(shift_s * 1e6)
        r.command_timestamp += int(shift_s * 1e6)
        return r.SerializeToString()
    if rtype == TYPE_TRACKER_2020:
        t = TrackerWrapperPacket()
        t.ParseFromString(payload)
        t.tracked_frame.timestamp += shift_s
        return t.SerializeToString()
    return payload


def make_log(dest: Path, target_bytes: int) -> float:
    """Writes a log of about ``target_bytes`` (no index record: like a recorder that was
    killed, so the station builds its own index); returns its duration in s."""
    recs = list(LogReader(str(FIXTURE)))
    t0 = recs[0].time_ns
    span = recs[-1].time_ns - t0 + 16_666_667
    written, k = 0, 0
    with open(dest, "wb") as f:
        f.write(file_header())
        while written < target_bytes:
            shift_ns = k * span
            for r in recs:
                body = _shifted(r.type, r.payload, shift_ns / 1e9)
                f.write(RECORD_HEADER.pack(r.time_ns + shift_ns, r.type, len(body)))
                f.write(body)
                written += 16 + len(body)
            k += 1
    return k * span / 1e9


@contextmanager
def station(*args: str) -> Iterator[tuple[str, int]]:
    st = start_station(list(args))
    try:
        yield st.url, st.pids["backend"]
    finally:
        st.stop()


def rss_mb(pid: int, key: str = "VmHWM") -> float:
    for line in Path(f"/proc/{pid}/status").read_text().splitlines():
        if line.startswith(key + ":"):
            return int(line.split()[1]) / 1024
    return float("nan")


def get(url: str, path: str) -> Any:
    return HTTP.get(url + path).json()


def player(url: str, body: dict[str, Any]) -> Any:
    r = HTTP.post(url + "/api/player", json=body, headers=JSON)
    r.raise_for_status()
    return r.json()


def wait_open(url: str, timeout_s: float) -> dict[str, Any]:
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        p: dict[str, Any] = get(url, "/api/player")
        if p["source"] == "log":
            return p
        if p["error"]:
            raise RuntimeError(p["error"])
        time.sleep(0.05)
    raise RuntimeError("the log did not open")


def bench_speed(tmp: Path, seconds: float) -> None:
    path = tmp / "speed.log"
    dur = make_log(path, int(seconds / 2.56 * 600_000))
    with station("--log", str(path)) as (url, pid):
        p = wait_open(url, 60)
        cpu0, t0 = cpu_s(pid), time.monotonic()
        player(url, {"action": "play", "speed": 0})
        while get(url, "/api/player")["playing"]:
            time.sleep(0.05)
        wall = time.monotonic() - t0
        cpu = cpu_s(pid) - cpu0
        h = get(url, "/api/health")
        procs = {x["name"]: x for x in h["processors"]}
    print(f"replay as fast as possible: {dur:.1f} s of 4-camera log in {wall:.2f} s = "
          f"{p['duration_s'] / wall:.1f}x real time (backend CPU {cpu / wall * 100:.0f} % of "
          f"a core; world model {procs['world-model']['measured_hz']:.0f} ticks/s at the end)")


def bench_big(tmp: Path, mb: int, seeks: int) -> None:
    path = tmp / "match.log"
    t = time.monotonic()
    dur = make_log(path, mb << 20)
    size = path.stat().st_size / 2**20
    print(f"made a {size:.0f} MB log of {dur / 60:.1f} min in {time.monotonic() - t:.0f} s")
    with station("--log", str(path)) as (url, pid):
        t = time.monotonic()
        p = wait_open(url, 300)
        print(f"open with index build: {time.monotonic() - t:.1f} s "
              f"({p['duration_s'] / 60:.1f} min, {len(p['events'])} events)")
        rng = random.Random(1)
        times: list[float] = []
        for _ in range(seeks):
            pos = round(rng.uniform(1, p["duration_s"] - 1), 3)
            t = time.monotonic()
            player(url, {"action": "seek", "position_s": pos})
            while True:
                w = get(url, "/api/world")
                if w["replay"] and abs(w["replay"]["position_s"] - pos) < 1e-3 and w["robots"]:
                    break
            times.append((time.monotonic() - t) * 1000)
        times.sort()
        print(f"seek to a random time until the world is there ({seeks}x, 0.3 s pre-roll "
              f"through the pipeline each): p50 {statistics.median(times):.0f} ms, "
              f"max {times[-1]:.0f} ms")
        print(f"backend memory while replaying it: peak RSS {rss_mb(pid):.0f} MB, "
              f"now {rss_mb(pid, 'VmRSS'):.0f} MB")


def bench_recording(window_s: float) -> None:
    out: dict[str, float] = {}
    for label, args in (("without recording", ("--no-record",)), ("recording", ())):
        with station(*args) as (url, pid):
            time.sleep(3.0)  # let the simulator and the loop settle
            c0, t0 = cpu_s(pid), time.monotonic()
            time.sleep(window_s)
            out[label] = (cpu_s(pid) - c0) / (time.monotonic() - t0) * 100
            rec = get(url, "/api/health")["recording"]
        print(f"backend CPU {label}: {out[label]:.1f} % of a core"
              + (f" (file {rec['size_bytes'] / 2**20:.1f} MB, {rec['records']} records, "
                 f"{rec['dropped']} dropped)" if rec["recording"] else ""))
    print(f"recording costs {out['recording'] - out['without recording']:.1f} % of a core "
          "(4 cameras x 60 Hz, 6 v 6; one run each, the machine's noise is about 1-2 %)")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--mb", type=int, default=700)
    ap.add_argument("--seconds", type=float, default=60.0)
    ap.add_argument("--seeks", type=int, default=20)
    ap.add_argument("--window", type=float, default=20.0)
    a = ap.parse_args()
    with tempfile.TemporaryDirectory(prefix="touchline-replay-bench-") as d:
        bench_speed(Path(d), a.seconds)
        bench_big(Path(d), a.mb, a.seeks)
    bench_recording(a.window)


if __name__ == "__main__":
    main()
