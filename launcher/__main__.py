"""`python -m launcher`: start the station (simulator, relay, backend) and supervise it.

With ``--sim builtin`` (default) it runs fieldsim; with ``--sim none`` it expects an external
simulator or real SSL-Vision on the same ports. ``--isolated`` picks free non-standard ports
for everything (used by the end-to-end tests so they never disturb a running station).
"""

from __future__ import annotations

import argparse
import json
import logging
import os
import random
import shutil
import signal
import socket
import subprocess
import sys
import tempfile
import time
import urllib.request
from dataclasses import asdict, dataclass, field
from pathlib import Path

from sslnet import defaults
from sslnet.multicast import loopback_multicast_ok

ROOT = Path(__file__).resolve().parent.parent
log = logging.getLogger("touchline.launcher")


def free_tcp_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port: int = s.getsockname()[1]
        return port


def free_udp_port() -> int:
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as s:
        s.bind(("127.0.0.1", 0))
        port: int = s.getsockname()[1]
        return port


@dataclass
class Ports:
    http: int = defaults.BACKEND_PORT
    vision_group: str = defaults.VISION_GROUP
    vision: int = defaults.VISION_PORT_SIM
    referee_group: str = defaults.REFEREE_GROUP
    referee: int = defaults.REFEREE_PORT
    sim_control: int = defaults.SIM_CONTROL_PORT
    sim_blue: int = defaults.SIM_BLUE_PORT
    sim_yellow: int = defaults.SIM_YELLOW_PORT
    grsim: int = defaults.GRSIM_COMMAND_PORT
    relay_pub: str = defaults.RELAY_PUB
    relay_sub: str = defaults.RELAY_SUB

    @staticmethod
    def isolated(http: int | None) -> Ports:
        rnd = random.Random(os.getpid() ^ time.time_ns())
        return Ports(
            http=http or free_tcp_port(),
            vision=rnd.randrange(30000, 40000),
            referee=rnd.randrange(40000, 50000),
            sim_control=free_udp_port(),
            sim_blue=free_udp_port(),
            sim_yellow=free_udp_port(),
            grsim=free_udp_port(),
            relay_pub=f"tcp://127.0.0.1:{free_tcp_port()}",
            relay_sub=f"tcp://127.0.0.1:{free_tcp_port()}",
        )


@dataclass
class Child:
    name: str
    argv: list[str]
    proc: subprocess.Popen[bytes] | None = None
    restarts: int = 0
    started: float = 0.0
    history: list[float] = field(default_factory=list)


def build_children(a: argparse.Namespace, ports: Ports) -> list[Child]:
    py = sys.executable
    children: list[Child] = []
    if a.sim == "builtin":
        children.append(Child("fieldsim", [
            py, "-m", "fieldsim",
            "--seed", str(a.seed),
            "--vision-group", ports.vision_group, "--vision-port", str(ports.vision),
            "--interface", a.interface,
            "--control-port", str(ports.sim_control), "--blue-port", str(ports.sim_blue),
            "--yellow-port", str(ports.sim_yellow), "--grsim-port", str(ports.grsim),
            *a.sim_args,
        ]))
    children.append(Child("relay", [
        py, "-m", "larcmacs_relay",
        "--vision", f"{ports.vision_group}:{ports.vision}",
        "--referee", f"{ports.referee_group}:{ports.referee}",
        "--interface", a.interface,
        "--output", a.output, "--sim-host", a.sim_host,
        "--sim-control-port", str(ports.sim_control), "--sim-blue-port", str(ports.sim_blue),
        "--sim-yellow-port", str(ports.sim_yellow), "--grsim-port", str(ports.grsim),
        "--pub", ports.relay_pub, "--sub", ports.relay_sub,
        *a.relay_args,
    ]))
    children.append(Child("backend", [
        py, "-m", "backend", "--host", a.host, "--port", str(ports.http),
        "--relay-pub", ports.relay_pub, "--relay-sub", ports.relay_sub,
        *(["--our-team", a.our_team] if a.our_team else []),
        *(["--state-dir", a.state_dir] if a.state_dir else []),
        *a.backend_args,
    ]))
    return children


def start(child: Child) -> None:
    log.info("starting %s: %s", child.name, " ".join(child.argv[1:]))
    child.proc = subprocess.Popen(child.argv, cwd=ROOT)
    child.started = time.monotonic()


def wait_http(url: str, timeout_s: float) -> bool:
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        try:
            with urllib.request.urlopen(url, timeout=1.0) as r:
                if r.status == 200:
                    return True
        except OSError:
            pass
        time.sleep(0.2)
    return False


def main() -> int:
    p = argparse.ArgumentParser(prog="python -m launcher", description=__doc__)
    p.add_argument("--sim", choices=["builtin", "none"], default="builtin")
    p.add_argument("--host", default="127.0.0.1")
    p.add_argument("--port", type=int, default=None, help="HTTP port (default 8000)")
    p.add_argument("--interface", default="127.0.0.1",
                   help="interface address for multicast (vision, referee)")
    p.add_argument("--output", choices=["sim", "grsim", "robot-box"], default="sim")
    p.add_argument("--sim-host", default="127.0.0.1", help="simulator address for commands")
    p.add_argument("--our-team", choices=["blue", "yellow"], default=None,
                   help="override the stored team parameter")
    p.add_argument("--state-dir", default=None,
                   help="parameters and presets folder (default var/; --isolated: a temp dir)")
    p.add_argument("--seed", type=int, default=1)
    p.add_argument("--isolated", action="store_true",
                   help="free non-standard ports for everything (tests)")
    p.add_argument("--vision-port", type=int, default=None,
                   help="vision multicast port (default 10020, real SSL-Vision uses 10006)")
    p.add_argument("--sim-arg", dest="sim_args", action="append", default=[],
                   help="extra flag for fieldsim (repeatable), e.g. --sim-arg=--false-prob=0.2")
    p.add_argument("--relay-arg", dest="relay_args", action="append", default=[])
    p.add_argument("--backend-arg", dest="backend_args", action="append", default=[])
    a = p.parse_args()
    logging.basicConfig(level=logging.INFO,
                        format="%(asctime)s %(levelname)s launcher: %(message)s")

    if not loopback_multicast_ok() and a.interface == "127.0.0.1":
        log.error("multicast on loopback does not work on this machine. As root run:\n"
                  "  ip link set lo multicast on\n"
                  "  ip route replace 224.0.0.0/4 dev lo src 127.0.0.1\n"
                  "(make run does this for you when run as root)")
        return 2

    ports = Ports.isolated(a.port) if a.isolated else Ports(http=a.port or defaults.BACKEND_PORT)
    own_state_dir: str | None = None  # a temporary state folder of ours: removed at exit
    if a.isolated and a.state_dir is None:
        a.state_dir = own_state_dir = tempfile.mkdtemp(prefix="touchline-state-")
    if a.vision_port:
        ports.vision = a.vision_port
    children = build_children(a, ports)
    stopping = False

    def on_signal(signum: int, _frame: object) -> None:
        nonlocal stopping
        stopping = True

    signal.signal(signal.SIGINT, on_signal)
    signal.signal(signal.SIGTERM, on_signal)

    for c in children:
        start(c)
    url = f"http://{a.host}:{ports.http}"
    if wait_http(url + "/api/health", 30.0):
        print(f"\n  Touchline is running: {url}\n", flush=True)  # noqa: T201
        # machine-readable lines for tests and scripts
        print(f"TOUCHLINE_PORTS {json.dumps(asdict(ports))}", flush=True)  # noqa: T201
        if own_state_dir is not None:
            print(f"TOUCHLINE_STATE_DIR {own_state_dir}", flush=True)  # noqa: T201
        print(f"TOUCHLINE_READY {url}", flush=True)  # noqa: T201
    else:
        log.error("backend did not answer on %s within 30 s", url)

    try:
        while not stopping:
            for c in children:
                assert c.proc is not None
                code = c.proc.poll()
                if code is None or stopping:
                    continue
                now = time.monotonic()
                c.history = [t for t in c.history if now - t < 60] + [now]
                if len(c.history) > 5:
                    log.error("%s exited %s and keeps crashing; giving up", c.name, code)
                    stopping = True
                    break
                log.warning("%s exited with %s; restarting", c.name, code)
                c.restarts += 1
                time.sleep(min(2.0, 0.2 * c.restarts))
                start(c)
            time.sleep(0.2)
    finally:
        # stop in mirror order: backend first (it sends a last stop), simulator last
        for c in reversed(children):
            if c.proc and c.proc.poll() is None:
                c.proc.send_signal(signal.SIGTERM)
                try:
                    c.proc.wait(timeout=5)
                except subprocess.TimeoutExpired:
                    c.proc.kill()
                    c.proc.wait()
        if own_state_dir is not None:
            shutil.rmtree(own_state_dir, ignore_errors=True)
        log.info("stopped")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
