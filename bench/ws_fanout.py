"""Benchmark: websocket fan-out to N clients (default 25) at 60 Hz and its effect on the control
loop (issue 11: 25 clients add <= 10 % of a core and never move the loop's numbers), and its
fairness (issue 30: every reader gets the stream's rate within 10 % whoever else is connected,
a client that never reads is dropped within 2 s).

Starts the real station (launcher --isolated) at full load (8 cameras x 75 Hz, division A,
11 v 11, the "match" play) and measures, in phases of ``--seconds`` each, ``--rounds`` times
interleaved: 0 clients, N reading clients (A, B, A, B...); then N reading clients beside
``--stalled`` clients that complete the handshake and never read a byte (raw sockets: no
client library reading ahead). A stalled client that is dropped is replaced at once, so the
readers share the server with ``--stalled`` stalled clients the whole phase; each one's drop
time is reported: from its upgrade request to its connection reset (polled every 20 ms), or
where the server leaves it open, to the backend's ``websocket_dropped`` count moving in the
health messages (about every 0.25 s). Per phase: world messages/s of every
reader (min / median / max, over the phase's measured time) and kB/s, the views processor's
publication rate, CPU of every process (% of one core, /proc), the backend's CPU per thread
(the web thread, the main one serving uvicorn, is where the fan-out is paid: the station
thread's CPU moves with the game by several %, which would swamp a process-wide
difference), the control processor's rate, the backend's vision -> command latency and the
relay's arrival -> command p50 / p99 (medians of the 1 s figures the health shows, and the
worst 1 s p99). The clients run in this process and only look at each message's type (the
first reader parses the health messages), so their own CPU disturbs the machine little.
Prints numbers; not a test.

    PYTHONPATH=. .venv/bin/python bench/ws_fanout.py [--clients 25] [--stalled 3]
        [--seconds 10] [--rounds 2] [--busy N] [--pyspy FILE]

``--busy N``: N processes spinning at full CPU the whole run (a shared, loaded machine: where
a fan-out that loses the race with its readers shows).

``--pyspy FILE``: a py-spy profile (raw, --threads) of the backend during the first
N-client phase (py-spy at /tmp/pyspy or on PATH); its own sampling disturbs that phase.
"""

from __future__ import annotations

import argparse
import asyncio
import base64
import contextlib
import fcntl
import json
import os
import shutil
import socket
import statistics
import subprocess
import sys
import termios
import time
from pathlib import Path
from typing import Any

import httpx
from websockets.asyncio.client import connect

from bench.station_run import full_scale_args, start_station
from sslnet.proc import process_cpu_s as cpu_s
from sslnet.proc import thread_cpu_s

ROOT = Path(__file__).resolve().parent.parent
LATENCIES = ("backend_p50", "backend_p99", "relay_p50", "relay_p99")


def health(url: str) -> dict[str, Any]:
    h: dict[str, Any] = httpx.get(url + "/api/health", timeout=5).json()
    return h


def backend_threads(pid: int) -> dict[str, float]:
    """CPU seconds of the backend's threads: the main thread (uvicorn's event loop: the web
    side) as "web", the others by name (threads of one name summed)."""
    out: dict[str, float] = {}
    for (name, tid), sec in thread_cpu_s(pid).items():
        key = "web" if tid == pid else name
        out[key] = out.get(key, 0.0) + sec
    return out


class Sampler:
    """CPU per process and per backend thread over a phase, and the loop's latency figures
    sampled once a second."""

    def __init__(self, url: str, pids: dict[str, int]) -> None:
        self.url, self.pids = url, pids
        self.rows: list[dict[str, float]] = []

    def start(self) -> None:
        self.c0 = {k: cpu_s(p) for k, p in self.pids.items()}
        self.th0 = backend_threads(self.pids["backend"])
        self.own0 = time.process_time()
        self.t0 = time.monotonic()
        self.rows = []

    def sample(self) -> None:
        h = health(self.url)
        ctrl = next(p for p in h["processors"] if p["name"] == "control")
        views = next(p for p in h["processors"] if p["name"] == "views")
        relay = h["relay"] or {}
        self.rows.append({
            "control_hz": ctrl["measured_hz"], "views_tick_ms": views["tick_mean_ms"],
            "views_hz": views["measured_hz"],
            "backend_p50": h["latency"]["p50_ms"],
            "backend_p99": h["latency"]["p99_ms"],
            "relay_p50": relay.get("command_latency_p50_ms", -1),
            "relay_p99": relay.get("command_latency_p99_ms", -1),
            "clients": h["websocket_clients"],
        })

    def result(self) -> dict[str, float]:
        dt = time.monotonic() - self.t0
        out = {f"cpu_{k}": (cpu_s(p) - self.c0[k]) / dt * 100 for k, p in self.pids.items()}
        th1 = backend_threads(self.pids["backend"])
        for k, v in th1.items():
            out[f"thread_{k}"] = (v - self.th0.get(k, 0.0)) / dt * 100
        out["cpu_bench"] = (time.process_time() - self.own0) / dt * 100
        for k in ("control_hz", "views_hz", "views_tick_ms", *LATENCIES, "clients"):
            vals = [r[k] for r in self.rows if r[k] >= 0]
            out[k] = statistics.median(vals) if vals else -1.0
        for k in ("backend_p99", "relay_p99"):
            vals = [r[k] for r in self.rows if r[k] >= 0]
            out[k + "_max"] = max(vals) if vals else -1.0
        return out


def world_message(data: str | bytes) -> bool:
    """Whether a websocket message is a world update (its type only: nothing parsed)."""
    if isinstance(data, str):
        data = data[:24].encode()
    return data.startswith(b'{"type":"world"')


async def reader(url: str, counts: list[int], sizes: list[int], i: int,
                 stop: asyncio.Event, dropped: list[int]) -> None:
    """Counts the world messages and bytes it gets; the first reader also keeps the
    backend's ``websocket_dropped`` count from the health messages (about 4 a second) in
    ``dropped[0]``."""
    async with connect(url.replace("http", "ws") + "/api/ws", max_size=None,
                       compression=None) as ws:
        while not stop.is_set():
            data = await ws.recv(decode=False)
            sizes[i] += len(data)
            if world_message(data):
                counts[i] += 1
            elif i == 0 and data.startswith(b'{"type":"health"'):
                dropped[0] = json.loads(data)["health"]["websocket_dropped"]


def stalled_client(url: str) -> socket.socket:
    """A websocket client that sends its upgrade request and never reads a byte."""
    host, port = url.split("//", 1)[1].rsplit(":", 1)
    s = socket.create_connection((host, int(port)))
    key = base64.b64encode(os.urandom(16)).decode()
    s.sendall((f"GET /api/ws HTTP/1.1\r\nHost: {host}:{port}\r\nUpgrade: websocket\r\n"
               f"Connection: Upgrade\r\nSec-WebSocket-Key: {key}\r\n"
               "Sec-WebSocket-Version: 13\r\n\r\n").encode())
    return s


def reset(s: socket.socket) -> bool:
    """Whether the server ended the connection (its TCP state left ESTABLISHED: a reset)."""
    state = s.getsockopt(socket.IPPROTO_TCP, socket.TCP_INFO, 1)[0]
    return state != 1  # TCP_ESTABLISHED


def received(s: socket.socket) -> bool:
    """Whether bytes from the server wait unread in ``s`` (its handshake answer, the snapshot)."""
    n = bytearray(4)
    fcntl.ioctl(s.fileno(), termios.FIONREAD, n)
    return int.from_bytes(n, sys.byteorder) > 0


class StalledClient:
    def __init__(self, url: str) -> None:
        self.t_request = time.monotonic()
        self.t_served: float | None = None  # when its first bytes from the server were seen
        self.sock = stalled_client(url)


async def keep_stalled(url: str, n: int, stop: asyncio.Event, dropped: list[int],
                       drops: list[tuple[float, float]]) -> None:
    """Keeps ``n`` stalled clients connected: one the backend drops is replaced at once, and
    ``drops`` gets its drop's time after its upgrade request and after the server's first
    bytes reached it (its handshake answer and snapshot: it was served and never read). A
    drop is seen as the client's connection reset (polled every 20 ms), or else (a server
    that leaves it open) as the ``websocket_dropped`` count moving in the health messages
    (about every 0.25 s; the oldest client is taken as the one dropped: they are alike)."""
    clients: list[StalledClient] = []
    while dropped[0] < 0 and not stop.is_set():  # the first health message
        await asyncio.sleep(0.02)
    counted = dropped[0]  # the drops accounted for so far
    try:
        while not stop.is_set():
            while len(clients) < n:
                clients.append(StalledClient(url))
            with contextlib.suppress(TimeoutError):
                await asyncio.wait_for(stop.wait(), 0.02)
            t = time.monotonic()
            for c in clients:
                if c.t_served is None and received(c.sock):
                    c.t_served = t
            gone = [c for c in clients if reset(c.sock)]
            rest = [c for c in clients if c not in gone]
            gone += rest[:max(0, dropped[0] - counted - len(gone))]
            for c in gone:
                clients.remove(c)
                drops.append((t - c.t_request, t - (c.t_served or c.t_request)))
                c.sock.close()
            counted += len(gone)
    finally:
        for c in clients:
            c.sock.close()


def pyspy_cmd() -> list[str] | None:
    exe = Path("/tmp/pyspy/bin/py-spy")
    if exe.exists():
        return [str(exe)]
    found = shutil.which("py-spy")
    return [found] if found else None


async def phase(s: Sampler, n: int, stalled: int, seconds: float,
                pyspy_out: str | None = None) -> dict[str, Any]:
    counts, sizes = [0] * n, [0] * n
    stop = asyncio.Event()
    drops: list[tuple[float, float]] = []
    dropped = [-1]
    tasks = [asyncio.create_task(reader(s.url, counts, sizes, i, stop, dropped))
             for i in range(n)]
    if stalled:
        tasks.append(asyncio.create_task(keep_stalled(s.url, stalled, stop, dropped, drops)))
    await asyncio.sleep(2.0)  # connected; the buffers of stalled clients fill
    base, base_sizes = list(counts), list(sizes)
    t0 = time.monotonic()
    spy: subprocess.Popen[bytes] | None = None
    cmd = pyspy_cmd() if pyspy_out else None
    if pyspy_out and cmd:
        env = dict(os.environ, PYTHONPATH="/tmp/pyspy")
        spy = subprocess.Popen([*cmd, "record", "-p", str(s.pids["backend"]), "-d",
                                str(int(seconds)), "-r", "200", "-f", "raw", "-o", pyspy_out,
                                "--threads", "--nonblocking"], env=env,
                               stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    s.start()
    t_end = time.monotonic() + seconds
    while time.monotonic() < t_end:
        await asyncio.sleep(1.0)
        await asyncio.to_thread(s.sample)
    r: dict[str, Any] = dict(s.result())
    dt = time.monotonic() - t0  # the time measured (the samples take some)
    rates = sorted((c - b) / dt for c, b in zip(counts, base, strict=True))
    bytes_s = [(c - b) / dt for c, b in zip(sizes, base_sizes, strict=True)]
    stop.set()
    for t in tasks:
        t.cancel()
    await asyncio.gather(*tasks, return_exceptions=True)
    if spy is not None:
        spy.wait(timeout=seconds + 30)
    r["msgs_min"] = rates[0] if rates else 0.0
    r["msgs_median"] = statistics.median(rates) if rates else 0.0
    r["msgs_max"] = rates[-1] if rates else 0.0
    r["msgs_mean"] = sum(rates) / len(rates) if rates else 0.0
    r["kb_s"] = sum(bytes_s) / len(bytes_s) / 1000 if bytes_s else 0.0
    r["drops"] = drops
    return r


def busy_loops(n: int) -> list[subprocess.Popen[bytes]]:
    """``n`` processes spinning at full CPU (a loaded, shared machine)."""
    return [subprocess.Popen([sys.executable, "-c", "while True: pass"]) for _ in range(n)]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--clients", type=int, default=25, help="reading clients")
    ap.add_argument("--stalled", type=int, default=3,
                    help="clients that never read, beside the readers in the last phase")
    ap.add_argument("--seconds", type=float, default=10.0)
    ap.add_argument("--rounds", type=int, default=2,
                    help="interleaved pairs of phases (0 clients, N clients)")
    ap.add_argument("--cameras", type=int, default=8)
    ap.add_argument("--hz", type=float, default=75.0)
    ap.add_argument("--busy", type=int, default=0, help="processes spinning the whole run")
    ap.add_argument("--pyspy", default=None, metavar="FILE")
    a = ap.parse_args()
    station = start_station(full_scale_args(a.cameras, a.hz))
    proc, url, pids = station.proc, station.url, station.pids
    busy = busy_loops(a.busy)
    load0 = os.getloadavg()
    results: list[tuple[str, int, dict[str, Any]]] = []
    try:
        time.sleep(5)
        s = Sampler(url, pids)
        plan: list[tuple[str, int, int]] = []
        for _ in range(a.rounds):
            plan += [("0 clients", 0, 0), (f"{a.clients} reading", a.clients, 0)]
        if a.stalled:
            plan.append((f"{a.clients} reading + {a.stalled} stalled", a.clients, a.stalled))
        spied = False
        for name, n, st in plan:
            spy = a.pyspy if n and not st and not spied else None
            spied = spied or spy is not None
            results.append((name, n, asyncio.run(phase(s, n, st, a.seconds, spy))))
    finally:
        for b in busy:
            b.kill()
            b.wait()
        proc.terminate()
        proc.wait(timeout=15)
    load1 = os.getloadavg()
    print(f"websocket fan-out, {a.cameras} cameras x {a.hz:g} Hz, 11 v 11, match play, "
          f"{a.seconds:g} s per phase, {a.rounds} interleaved rounds, {a.busy} busy processes "
          f"(CPU in % of one core; latencies: medians of 1 s figures, worst 1 s p99 in "
          f"brackets); load {load0[0]:.2f} -> {load1[0]:.2f}")
    print("| phase | world msgs/s per reader (min / median / max) | views published /s | "
          "kB/s per reader | backend CPU (web thread / station thread) | relay CPU | control Hz "
          "| views tick (ms) | backend vision->command p50 / p99 | relay arrival->command p50 "
          "/ p99 | bench's clients CPU |")
    print("|---|---|---|---|---|---|---|---|---|---|---|")
    for name, _n, r in results:
        print(f"| {name} | {r['msgs_min']:.1f} / {r['msgs_median']:.1f} / {r['msgs_max']:.1f} "
              f"| {r['views_hz']:.1f} | {r['kb_s']:.0f} | "
              f"{r['cpu_backend']:.1f} ({r.get('thread_web', 0):.1f} / "
              f"{r.get('thread_station', 0):.1f}) | {r['cpu_relay']:.1f} | "
              f"{r['control_hz']:.0f} | {r['views_tick_ms']:.2f} | "
              f"{r['backend_p50']:.2f} / {r['backend_p99']:.2f} "
              f"({r['backend_p99_max']:.2f}) ms | {r['relay_p50']:.2f} / {r['relay_p99']:.2f} "
              f"({r['relay_p99_max']:.2f}) ms | {r['cpu_bench']:.1f} |")
    idle = [r for _, n, r in results if n == 0]
    reading = [r for name, n, r in results if n and "stalled" not in name]

    def mean(rows: list[dict[str, Any]], k: str) -> float:
        return float(sum(r.get(k, 0.0) for r in rows)) / len(rows)

    if idle and reading:
        web = [b.get("thread_web", 0) - i.get("thread_web", 0)
               for i, b in zip(idle, reading, strict=False)]
        both = [b["cpu_backend"] + b["cpu_relay"] - i["cpu_backend"] - i["cpu_relay"]
                for i, b in zip(idle, reading, strict=False)]
        per_msg = [w / 100 / max(b["msgs_mean"] * a.clients, 1e-9) * 1e6
                   for w, b in zip(web, reading, strict=False)]
        print(f"{a.clients} reading clients add to the web thread: "
              + " / ".join(f"{x:+.1f}" for x in web) + " % of a core (per round; "
              + " / ".join(f"{x:.0f}" for x in per_msg) + " us per world message and client); "
              "to relay + backend: " + " / ".join(f"{x:+.1f}" for x in both) + " %")
        print(f"relay arrival->command p99 without / with the clients (mean of the rounds' "
              f"medians): {mean(idle, 'relay_p99'):.2f} / {mean(reading, 'relay_p99'):.2f} ms;"
              f" p50 {mean(idle, 'relay_p50'):.2f} / {mean(reading, 'relay_p50'):.2f} ms")
    for name, _n, r in results:
        if "stalled" not in name:
            continue
        if idle:
            both = (r["cpu_backend"] + r["cpu_relay"] - mean(idle, "cpu_backend")
                    - mean(idle, "cpu_relay"))
            print(f"{name}: adds {r['thread_web'] - mean(idle, 'thread_web'):+.1f} % of a core "
                  f"to the web thread, {both:+.1f} % to relay + backend")
        if r["drops"]:
            req = sorted(d[0] for d in r["drops"])
            served = sorted(d[1] for d in r["drops"])
            print(f"{name}: {len(req)} stalled clients dropped, after (min / median / max) "
                  f"{req[0]:.2f} / {statistics.median(req):.2f} / {req[-1]:.2f} s from their "
                  f"upgrade request, {served[0]:.2f} / {statistics.median(served):.2f} / "
                  f"{served[-1]:.2f} s from the server's first bytes")
            print("  in the order they went (s from the server's first bytes): "
                  + " ".join(f"{d[1]:.2f}" for d in r["drops"]))
        else:
            print(f"{name}: no stalled client dropped")

if __name__ == "__main__":
    main()
