"""The longest silence of Touchline's tracked vision, heard like the game controller hears it
(figures, not a test; issue 30 item 4).

The game controller drops its tracker source after 300 ms without a frame, so a backend pass
that stalls that long makes it judge the game with no tracker. This runs the launcher's station
(``--full``: 8 cameras x 75 Hz, division A, 11 v 11, the "match" play; else the default
simulator with ``--play``) for ``--minutes`` (2) and listens to the relay's tracked-vision multicast
on loopback as a third party, with the kernel's receive time of every datagram (SO_TIMESTAMPNS:
this script's own scheduling does not count). Beside it, as options:

- ``--browser``: a headless Chromium with the page open (bench/open_page.mjs);
- ``--index-mb N``: a generated log of N MB (``--gz``: gzipped) opened through the API again
  and again (its mtime touched each time, so the log-cache is built anew), every
  ``--index-every`` s; once it is open the bench asks for live again (a replay publishes no
  tracked frames on purpose: the silence that contains a moment the player said "log" is not
  counted; what came before the last "still live" answer of it is);
- ``--plays S``: the strategy's play changed every S s (through all plays);
- ``--params S``: a parameter patch every S s (filters, strategy, the compute engine numpy/off);
- ``--listing S``: the log list asked for every S s.

It prints the gaps between tracked frames (max, the 10 longest with what was going on and the
vision multicast's own longest silence around each: fieldsim's stalls are not the backend's),
counts over 100 and 300 ms (and the same for the gaps the vision multicast did not share: on a
busy machine every process stops now and then, the simulator too), the relay's stale stops,
the launcher's restarts (a restarted backend is a long silence of its own), and the load
average at the start and the end.

    PYTHONPATH=. .venv/bin/python bench/tracker_gaps.py --minutes 10 --full --browser \\
        --index-mb 500 [--json out.json] [--pyspy FILE]
"""

from __future__ import annotations

import argparse
import bisect
import contextlib
import itertools
import json
import os
import select
import shutil
import signal
import socket
import struct
import subprocess
import sys
import tempfile
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import httpx

from bench.station_run import ROOT, full_scale_args, start_station
from sslnet.multicast import open_multicast_receiver

PLAYS = ("match", "defend", "attack-drill", "formation", "simple", "idle")
FIXTURE = ROOT / "tests" / "data" / "fieldsim-2s.log.gz"
SO_TIMESTAMPNS = getattr(socket, "SO_TIMESTAMPNS", 35)


class Arrivals(threading.Thread):
    """Every datagram on a multicast group and port with the kernel's receive time (wall
    clock, s)."""

    def __init__(self, group: str, port: int) -> None:
        super().__init__(daemon=True)
        self.sock = open_multicast_receiver(group, port, "127.0.0.1", rcvbuf=8 << 20)
        self.sock.setsockopt(socket.SOL_SOCKET, SO_TIMESTAMPNS, 1)
        self.times: list[float] = []
        self.halt = threading.Event()

    def run(self) -> None:
        while not self.halt.is_set():
            ready, _, _ = select.select([self.sock], [], [], 0.2)
            if not ready:
                continue
            while True:
                try:
                    _, anc, _, _ = self.sock.recvmsg(65536, 64)
                except BlockingIOError:
                    break
                t = time.time()
                for level, kind, data in anc:
                    if level == socket.SOL_SOCKET and kind == SO_TIMESTAMPNS:
                        sec, nsec = struct.unpack("qq", data[:16])
                        t = sec + nsec / 1e9
                self.times.append(t)


@dataclass
class Activity:
    """What the bench did, for the gap report: (start, end, label), wall clock."""

    spans: list[tuple[float, float, str]] = field(default_factory=list)
    #: moments a poll of the player said "log" (a replay: no tracked frames on purpose), each
    #: with the time of the poll before it that still said live
    replay_seen: list[tuple[float, float]] = field(default_factory=list)
    lock: threading.Lock = field(default_factory=threading.Lock)

    def add(self, t0: float, t1: float, label: str) -> None:
        with self.lock:
            self.spans.append((t0, t1, label))

    def during(self, t0: float, t1: float) -> list[str]:
        with self.lock:
            return sorted({lab for a, b, lab in self.spans if a <= t1 and b >= t0})


def make_log(path: Path, megabytes: float, gz: bool) -> None:
    """A log of about ``megabytes`` MB: the records of tests/data/fieldsim-2s.log.gz again and
    again, their times shifted on (what indexing reads: headers, camera ids, referee)."""
    from ssllog.logfile import LogFile
    from ssllog.writer import LogWriter

    with tempfile.TemporaryDirectory() as cache:
        src = LogFile.open(str(FIXTURE), cache)
        recs = [(r.time_ns, r.type, r.payload) for r in src.records(include_unknown=True)]
        src.close()
    span = recs[-1][0] - recs[0][0] + 20_000_000
    plain = path.with_suffix("") if gz else path
    if plain.exists():
        plain.unlink()
    w = LogWriter(str(plain))
    size, shift = 16, 0
    while size < megabytes * 1e6:
        for t, k, payload in recs:
            w.write(t + shift, k, payload)
            size += 16 + len(payload)
        shift += span
    w.finish()
    if gz:
        subprocess.run(["gzip", "-1", "-f", str(plain)], check=True)
        os.replace(str(plain) + ".gz", path)


def every(stop: threading.Event, period: float, fn: Callable[[int], None]) -> None:
    i = 0
    while not stop.wait(period):
        try:
            fn(i)
        except Exception as exc:  # a bench keeps going; said at the end
            print(f"  {fn.__name__}: {exc!r}", file=sys.stderr)
        i += 1


def indexer(url: str, log: Path, cache: Path, act: Activity, stop: threading.Event,
            period: float, cycles: list[float]) -> None:
    """Opens ``log`` through the API every ``period`` s (its mtime touched: a new cache key,
    the index built again), waits until it is open, asks for live again."""
    c = httpx.Client(base_url=url, timeout=30.0)
    while not stop.wait(period):
        for old in cache.glob("*"):
            with contextlib.suppress(OSError):
                old.unlink()
        now = time.time()
        os.utime(log, (now, now))
        t0 = time.time()
        r = c.post("/api/player", json={"action": "open", "path": str(log)})
        if r.status_code != 200:
            print(f"  open refused: {r.status_code} {r.text[:200]}", file=sys.stderr)
            continue
        last_live = time.time()
        while not stop.is_set():
            p = c.get("/api/player").json()
            t = time.time()
            if p["source"] == "log":
                act.replay_seen.append((last_live, t))
                break
            if p["error"]:
                print(f"  open failed: {p['error']}", file=sys.stderr)
                break
            last_live = t
            time.sleep(0.05)
        t1 = time.time()
        act.add(t0, t1, "indexing")
        cycles.append(t1 - t0)
        c.post("/api/player", json={"action": "live"})
        act.add(t1, time.time(), "back to live")


def gaps(times: list[float], act: Activity) -> list[tuple[float, float, float]]:
    """(length s, start, end) of every silence between two frames, a replay's own silence
    cut to what came before the player last said live."""
    ts = sorted(times)
    out = []
    seen = sorted(act.replay_seen, key=lambda x: x[1])
    for a, b in itertools.pairwise(ts):
        end = b
        for live, log_t in seen:
            if a < log_t < b:  # the player is replaying: up to its last "live" counts
                end = min(end, max(a, live))
        out.append((end - a, a, end))
    return out


def vision_silence(vision: list[float], t0: float, t1: float) -> float:
    """The longest silence of the vision multicast overlapping [t0, t1]."""
    i = max(0, bisect.bisect_left(vision, t0) - 1)
    j = min(len(vision), bisect.bisect_right(vision, t1) + 1)
    seg = vision[i:j]
    return max((b - a for a, b in itertools.pairwise(seg)), default=float("nan"))


def stale_stops(c: httpx.Client) -> int:
    """The relay's count of robots stopped because their commands went stale (it stops a
    robot whose commands are older than its timeout, 0.1 s: a stalled backend)."""
    relay = c.get("/api/health").json().get("relay") or {}
    return int(relay.get("stale_stops", 0))


def loadavg() -> str:
    return " ".join(Path("/proc/loadavg").read_text().split()[:3])


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--minutes", type=float, default=2.0)
    ap.add_argument("--full", action="store_true", help="8 x 75 Hz, division A, 11 v 11, match")
    ap.add_argument("--play", default="match", help="the play without --full")
    ap.add_argument("--browser", action="store_true")
    ap.add_argument("--index-mb", type=float, default=0.0)
    ap.add_argument("--gz", action="store_true", help="the log gzipped (a copy is made first)")
    ap.add_argument("--index-every", type=float, default=20.0)
    ap.add_argument("--plays", type=float, default=0.0, help="change the play every S s")
    ap.add_argument("--params", type=float, default=0.0, help="a parameter patch every S s")
    ap.add_argument("--listing", type=float, default=0.0, help="GET /api/logs every S s")
    ap.add_argument("--backend-arg", action="append", default=[])
    ap.add_argument("--env", action="append", default=[], help="NAME=VALUE for the station")
    ap.add_argument("--pyspy", help="py-spy record of the backend (threads, only the GIL holder, "
                    "not pausing it) into this file")
    ap.add_argument("--pyspy-format", default="chrometrace",
                    help="chrometrace: a timeline (its ts from the start printed below)")
    ap.add_argument("--json")
    a = ap.parse_args()

    work = Path(tempfile.mkdtemp(prefix="tracker-gaps-"))
    logs, rec = work / "logs", work / "rec" / "logs"
    logs.mkdir()
    rec.mkdir(parents=True)
    big = logs / ("big.log.gz" if a.gz else "big.log")
    if a.index_mb:
        t = time.monotonic()
        make_log(big, a.index_mb, a.gz)
        print(f"generated {big.name}: {big.stat().st_size / 1e6:.0f} MB in "
              f"{time.monotonic() - t:.1f} s")
    args = full_scale_args() if a.full else ["--backend-arg=--play", f"--backend-arg={a.play}"]
    args += ["--record-dir", str(rec), "--log-dir", str(logs)]
    args += [f"--backend-arg={x}" for x in a.backend_arg]
    env_before = dict(os.environ)
    for item in a.env:
        k, _, v = item.partition("=")
        os.environ[k] = v
    load0 = loadavg()
    launcher_log = work / "launcher.log"
    st = start_station(args, stderr=launcher_log.open("w"))
    os.environ.clear()
    os.environ.update(env_before)
    ports, url = st.ports, st.url
    tracker = Arrivals(ports["tracker_group"], ports["tracker"])
    vision = Arrivals(ports["vision_group"], ports["vision"])
    tracker.start()
    vision.start()
    act = Activity()
    stop = threading.Event()
    threads: list[threading.Thread] = []
    extra: list[subprocess.Popen[Any]] = []
    cycles: list[float] = []
    seconds = a.minutes * 60
    c = httpx.Client(base_url=url, timeout=30.0)
    try:
        # wait for tracked frames, then a few seconds of settling
        deadline = time.monotonic() + 60
        while len(tracker.times) < 100 and time.monotonic() < deadline:
            time.sleep(0.2)
        if a.browser:
            page = subprocess.Popen(["node", "bench/open_page.mjs", url, str(seconds + 60)],
                                    cwd=ROOT, stdout=subprocess.PIPE, text=True)
            extra.append(page)
            assert page.stdout is not None
            line = page.stdout.readline()
            if "PAGE_OPEN" not in line:
                raise RuntimeError(f"the page did not open: {line!r}")
        if a.pyspy:
            spy = shutil.which("py-spy") or "/tmp/pyspy/bin/py-spy"
            print(f"py-spy started at unix {time.time():.3f}")
            extra.append(subprocess.Popen(
                [spy, "record", "--pid", str(st.pids["backend"]), "--threads", "--gil",
                 "--nonblocking", "--format", a.pyspy_format, "-r", "500", "-o", a.pyspy,
                 "-d", str(int(seconds) + 5)],
                env=dict(os.environ, PYTHONPATH=str(Path(spy).parent.parent)),
                stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL))
        t_start = time.time()
        n0 = len(tracker.times)
        stale0 = stale_stops(c)
        if a.index_mb:
            threads.append(threading.Thread(target=indexer, daemon=True, args=(
                url, big, work / "rec" / "log-cache", act, stop, a.index_every, cycles)))

        def play(i: int) -> None:
            t = time.time()
            c.patch("/api/params", json={"strategy": {"play": PLAYS[i % len(PLAYS)]}})
            act.add(t, time.time(), f"play {PLAYS[i % len(PLAYS)]}")

        patches: list[dict[str, Any]] = [
            {"filters": {"ball": "kalman"}}, {"filters": {"ball": "adaptive"}},
            {"strategy": {"kick_speed_mps": 5.0}}, {"strategy": {"kick_speed_mps": 5.5}},
            {"strategy": {"engine": "numpy"}}, {"strategy": {"engine": "off"}},
        ]

        def params(i: int) -> None:
            t = time.time()
            body = patches[i % len(patches)]
            r = c.patch("/api/params", json=body)
            if r.status_code != 200:
                raise RuntimeError(f"{body}: {r.status_code} {r.text[:200]}")
            act.add(t, time.time(), f"params {json.dumps(body)}")

        def listing(i: int) -> None:
            t = time.time()
            c.get("/api/logs")
            act.add(t, time.time(), "log list")

        if a.plays:
            threads.append(threading.Thread(target=every, args=(stop, a.plays, play),
                                            daemon=True))
        if a.params:
            threads.append(threading.Thread(target=every, args=(stop, a.params, params),
                                            daemon=True))
        if a.listing:
            threads.append(threading.Thread(target=every, args=(stop, a.listing, listing),
                                            daemon=True))
        for th in threads:
            th.start()
        stop.wait(seconds)
        stop.set()
        for th in threads:
            th.join(60)
        t_end = time.time()
        load1 = loadavg()
        stale1 = stale_stops(c)
    finally:
        for p in extra:
            with contextlib.suppress(OSError):
                p.send_signal(signal.SIGINT)
        for p in extra:
            try:
                p.wait(20)
            except subprocess.TimeoutExpired:
                p.kill()
        st.proc.send_signal(signal.SIGINT)
        try:
            st.proc.wait(30)
        except subprocess.TimeoutExpired:
            st.proc.kill()
        tracker.halt.set()
        vision.halt.set()
        restarts = [line.strip() for line in launcher_log.read_text(errors="replace")
                    .splitlines() if "restarting" in line]
        shutil.rmtree(work, ignore_errors=True)

    times = [t for t in tracker.times if t_start <= t <= t_end]
    vis = sorted(vision.times)
    g = sorted(gaps(times, act), reverse=True)
    lengths = [x[0] for x in g]
    over = {ms: sum(1 for x in lengths if x > ms / 1000) for ms in (50, 100, 300)}
    print(f"tracked frames: {len(tracker.times) - n0} in {t_end - t_start:.0f} s "
          f"({len(times) / max(1e-9, t_end - t_start):.1f} Hz); load average {load0} -> "
          f"{load1}")
    if cycles:
        print(f"log opened {len(cycles)} times: {min(cycles):.1f}-{max(cycles):.1f} s each "
              f"(open to replaying)")
    print(f"max gap {lengths[0] * 1000:.1f} ms; gaps > 50 ms: {over[50]}, > 100 ms: "
          f"{over[100]}, > 300 ms: {over[300]}")
    # the gaps the simulator's vision did not share (its own longest silence in them under
    # 50 ms): what the relay and the backend added, not the machine stopping everyone
    own = [x for x in g if vision_silence(vis, x[1], x[2]) < 0.05]
    own_over = {ms: sum(1 for x in own if x[0] > ms / 1000) for ms in (100, 300)}
    print(f"  of them while vision kept coming: max {own[0][0] * 1000 if own else 0:.1f} ms; "
          f"> 100 ms: {own_over[100]}, > 300 ms: {own_over[300]}")
    print(f"relay stale stops (commands older than its timeout): {stale1 - stale0}; "
          f"processes restarted by the launcher: {len(restarts)}")
    for line in restarts:
        print(f"  {line}")
    print("longest gaps (ms, at s (unix), vision's own longest silence then, what was going on):")
    for length, t0, t1 in g[:10]:
        print(f"  {length * 1000:7.1f} at {t0 - t_start:7.1f} s ({t0:.3f})  vision "
              f"{1000 * vision_silence(vis, t0, t1):6.1f}  {', '.join(act.during(t0, t1)) or '-'}")
    if a.json:
        Path(a.json).write_text(json.dumps({
            "args": vars(a), "load_start": load0, "load_end": load1,
            "frames": len(times), "seconds": t_end - t_start,
            "max_gap_ms": lengths[0] * 1000, "over": over, "open_s": cycles,
            "stale_stops": stale1 - stale0, "restarts": restarts,
            "own_max_gap_ms": own[0][0] * 1000 if own else 0.0, "own_over": own_over,
            "tracker_times": [round(t, 6) for t in times],
            "vision_times": [round(t, 6) for t in vis if t_start <= t <= t_end],
            "replay_seen": act.replay_seen,
            "longest": [(x[0] * 1000, x[1] - t_start, act.during(x[1], x[2])) for x in g[:50]],
        }, indent=1))


if __name__ == "__main__":
    main()
