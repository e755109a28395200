"""Restart benchmark (not a test): how soon is a restarted process back at work?

``--target relay`` (the default; issue 12: "a restarted relay is back in the backend's data
within 250 ms of starting"). This starts the station's three processes with the launcher's own
supervisor (fieldsim, the relay, the backend, isolated ports and a temporary state folder),
waits until the backend is healthy, then ``--kills`` times: SIGKILLs the relay and lets
``Supervisor.watch`` (the launcher's restart, with its backoff) start a new one, and measures
from the new relay's ``Popen`` (its process start):

* ``bound``: the relay's PUB port accepts a TCP connection (interpreter, imports, sockets);
* ``first frame``: the capture time of the first world the backend merged from a frame
  captured after that start (so it came through the new relay); a frame reaches the backend
  about a millisecond after its capture, so this is when the data was back, whatever the
  polling below;
* ``seen``: when this program's poll of ``GET /api/world`` (every ``--poll-ms``) first saw it
  (an upper bound).

``--target backend`` (issue 30: "commands flow again <= 1 s after the kill"). This runs the
real launcher (``python -m launcher --isolated``: its supervisor restarts the backend as in
``make run``, from its warm spare unless ``--no-standby``) and stands between the relay and
the simulator: the relay's simulator ports are this program's
(``--relay-arg=--sim-blue-port=...``), which forwards every datagram to the simulator and its
answers back, and notes when each arrived and what it commanded. ``--kills`` times it
SIGKILLs the backend while the robots drive and measures from the kill:

* ``restarted``: the new backend's process start, or its spare's word to start (the
  supervisor's ``supervisor.json``);
* ``first command``: the first command the relay sent that came from the new backend, as it
  arrived here (on the simulator's side, not polled). The relay repeats each robot's last
  command for 100 ms, then zeros: a robot's command that moves it and differs from every
  command the relay sent that robot up to 50 ms after the kill (the old backend's last
  sets, still on their way then) can only be the new backend's. (A new backend whose first
  commands are zeros, or repeat the old one's bit for bit, is seen at its next: the robots
  are killed while driving, in the formation play with a new formation every second, so
  they keep driving.)
* ``web``: the new backend's ``GET /api/health`` answers (polled every 20 ms: an upper
  bound).

``--sim builtin`` runs fieldsim under the launcher; ``--sim external`` runs the launcher with
``--sim none`` (the relay then requires arming) and a fieldsim started by this program as the
external simulator, arms the station once through ``POST /api/arm`` and never again: a kill
whose new backend sends no command within ``--timeout`` s counts as "never", and one whose
new backend came up disarmed is counted (it is armed again to go on). Kills are 13 s apart
at least: the launcher gives up on a child that exits more than 5 times in a minute. The new
backend's own start timeline (``GET /api/health`` ``startup``, when it has one) is printed
per kill.

Usage: .venv/bin/python bench/restart_bench.py [--target relay|backend] [--sim builtin|external]
       [--kills 10] [--poll-ms 5] [--no-standby] [--backend-arg=--set=strategy.engine=octave]
"""

from __future__ import annotations

import argparse
import json
import os
import selectors
import signal
import socket
import statistics
import subprocess
import sys
import tempfile
import threading
import time
import urllib.error
import urllib.request
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from bench.station_run import Station, start_station  # noqa: E402
from launcher.supervisor import (  # noqa: E402
    Ports,
    StationConfig,
    Supervisor,
    command_lines,
    free_udp_port,
)
from sslpb.ssl_simulation_robot_control_pb2 import RobotControl  # noqa: E402

#: commands the relay sends up to this long after the kill may still be the old backend's
#: (its last command sets on their way, a busy relay): they are the baseline
OLD_GRACE_S = 0.05
#: at least this long between two kills: the launcher gives up on a child that exits more
#: than 5 times in a minute
KILL_SPACING_S = 13.0


def get(url: str, timeout_s: float = 2.0) -> Any:
    with urllib.request.urlopen(url, timeout=timeout_s) as r:
        return json.loads(r.read())


def wait(cond: Any, timeout_s: float, what: str, interval_s: float = 0.005) -> Any:
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        try:
            got = cond()
        except (OSError, ValueError):
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
    if not values_s:
        return f"{name:<40} (none)"
    v = sorted(x * 1000 for x in values_s)
    return (f"{name:<40} min {v[0]:7.1f}  median {statistics.median(v):7.1f}  "
            f"max {v[-1]:7.1f} ms  (n={len(v)})")


# ---- the relay ----------------------------------------------------------------------------

def relay_mode(args: argparse.Namespace) -> int:
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


# ---- the backend --------------------------------------------------------------------------

class SimTap:
    """Stands between the relay and the simulator on one team's port: forwards each command
    datagram to the simulator and each answer back to the relay, and notes for every command
    datagram its arrival (monotonic) and each robot's command (its bytes, and whether it
    moves the robot)."""

    def __init__(self) -> None:
        self.front = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)  # the relay sends here
        self.front.bind(("127.0.0.1", 0))
        self.port: int = self.front.getsockname()[1]
        self.back = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)  # to the simulator
        self.back.bind(("127.0.0.1", 0))
        self.sim: tuple[str, int] | None = None  # set once the simulator's port is known
        self.relay: tuple[str, int] | None = None
        self.lock = threading.Lock()
        self.log: list[tuple[float, list[tuple[int, bytes, bool]]]] = []

    def since(self, t: float) -> list[tuple[float, list[tuple[int, bytes, bool]]]]:
        with self.lock:
            return [e for e in self.log if e[0] >= t]


def run_taps(taps: list[SimTap], stop: threading.Event) -> None:
    sel = selectors.DefaultSelector()
    for tap in taps:
        sel.register(tap.front, selectors.EVENT_READ, (tap, True))
        sel.register(tap.back, selectors.EVENT_READ, (tap, False))
    while not stop.is_set():
        for key, _ in sel.select(0.1):
            tap, front = key.data
            sock: socket.socket = key.fileobj  # type: ignore[assignment]
            try:
                data, addr = sock.recvfrom(65536)
            except OSError:
                continue
            now = time.monotonic()
            if front:
                robots: list[tuple[int, bytes, bool]] = []
                try:
                    for c in RobotControl.FromString(data).robot_commands:
                        lv = c.move_command.local_velocity
                        moving = abs(lv.forward) + abs(lv.left) + abs(lv.angular) > 1e-6
                        robots.append((c.id, c.SerializeToString(), moving))
                except Exception:  # not ours to judge: forwarded as it is
                    pass
                with tap.lock:
                    tap.log.append((now, robots))
                    tap.relay = addr
                if tap.sim is not None:
                    tap.back.sendto(data, tap.sim)
            elif tap.relay is not None:
                tap.front.sendto(data, tap.relay)


def first_new_command(taps: list[SimTap], t_kill: float) -> float | None:
    """The arrival (s from the kill) of the first robot command that moves a robot and that
    the relay had not sent that robot up to ``OLD_GRACE_S`` after the kill; None if none
    came yet."""
    found: list[float] = []
    for tap in taps:
        old: dict[int, set[bytes]] = {}
        for t, robots in tap.since(t_kill - 1.0):
            if t <= t_kill + OLD_GRACE_S:
                for rid, raw, _ in robots:
                    old.setdefault(rid, set()).add(raw)
                continue
            if any(moving and raw not in old.get(rid, ()) for rid, raw, moving in robots):
                found.append(t - t_kill)
                break
    return min(found) if found else None


def supervisor_child(state_dir: Path, name: str) -> dict[str, Any] | None:
    try:
        status = json.loads((state_dir / "supervisor.json").read_text())
    except (OSError, ValueError):
        return None
    child: dict[str, Any] | None = next(
        (c for c in status["children"] if c["name"] == name), None)
    return child


def arm(base: str, timeout_s: float = 20.0) -> None:
    def accepted() -> bool:
        req = urllib.request.Request(base + "/api/arm", data=b'{"armed": true}', method="POST",
                                     headers={"Content-Type": "application/json"})
        try:
            with urllib.request.urlopen(req, timeout=5.0) as r:
                return bool(json.loads(r.read())["armed"])
        except urllib.error.HTTPError as e:
            if e.code == 409:  # no vision yet
                return False
            raise
    wait(accepted, timeout_s, "the station armed", 0.2)


def backend_mode(args: argparse.Namespace) -> int:
    external = args.sim == "external"
    taps = [SimTap(), SimTap()]  # blue, yellow
    stop = threading.Event()
    threading.Thread(target=run_taps, args=(taps, stop), daemon=True).start()
    restarted_s: list[float] = []
    first_s: list[float] = []
    first_by: dict[str, list[float]] = {}
    web_s: list[float] = []
    never = 0
    disarmed = 0
    kills: list[float] = []
    with tempfile.TemporaryDirectory(prefix="touchline-restart-") as tmp:
        argv = [f"--relay-arg=--sim-blue-port={taps[0].port}",
                f"--relay-arg=--sim-yellow-port={taps[1].port}",
                # a new formation every second: the robots keep driving, so the new
                # backend's first commands move them (they are told by that)
                "--backend-arg=--set=strategy.formation_period_s=1",
                *(["--no-standby"] if args.no_standby else []),
                *(f"--backend-arg={a}" for a in args.backend_args)]
        sim: Supervisor | None = None
        if external:
            # the external simulator's own ports, known before the launcher starts
            sim_ports = Ports.isolated(None)
            sim_ports.sim_blue, sim_ports.sim_yellow = free_udp_port(), free_udp_port()
            argv += ["--sim", "none", "--vision-port", str(sim_ports.vision)]
            fieldsim = command_lines(StationConfig(sim="builtin"), sim_ports)[0]
            sim = Supervisor([fieldsim], log_dir=Path(tmp) / "sim")
            sim.start()
            taps[0].sim = ("127.0.0.1", sim_ports.sim_blue)
            taps[1].sim = ("127.0.0.1", sim_ports.sim_yellow)
        log = (Path(tmp) / "launcher.log").open("w")
        station: Station | None = None
        try:
            station = start_station(argv, stderr=subprocess.STDOUT, timeout_s=120,
                                    env={"PYTHONUNBUFFERED": "1"}, log=log)
            ports, base = station.ports, station.url
            assert station.state_dir is not None  # --isolated: its own
            state_dir = station.state_dir
            if not external:
                taps[0].sim = ("127.0.0.1", ports["sim_blue"])
                taps[1].sim = ("127.0.0.1", ports["sim_yellow"])
            wait(lambda: get(base + "/api/health")["ok"], 90, "a healthy station", 0.2)
            if external:
                arm(base)
            for i in range(args.kills):
                def driving() -> bool:
                    # the robots driven now (a moving command in the last 50 ms)
                    t = time.monotonic() - 0.05
                    return any(m for tap in taps for _, robots in tap.since(t)
                               for _, _, m in robots)
                time.sleep(1.0)  # a second of play (and the relay's statistics)
                # the launcher gives up on a child that crashes more than 5 times a minute;
                # and its warm spare comes 5 s after a start
                if kills:
                    time.sleep(max(0.0, kills[-1] + KILL_SPACING_S - time.monotonic()))
                wait(driving, 30, "the robots driving at the kill", 0.002)
                before = supervisor_child(state_dir, "backend")
                assert before is not None
                pid = before["pid"]
                spare = before.get("spare_pid")
                # a spare still importing at the kill starts later (its log line says ready)
                how = ("cold" if spare is None else "spare ready"
                       if f"standby (pid {spare}): imported" in station.text() else
                       "spare importing")
                t_kill = time.monotonic()
                t_kill_unix = time.time()
                kills.append(t_kill)
                os.kill(pid, signal.SIGKILL)

                def new_child(old: int = pid) -> dict[str, Any] | None:
                    c = supervisor_child(state_dir, "backend")
                    return c if c is not None and c["pid"] != old else None
                child = wait(new_child, 30, "the supervisor's restart", 0.005)
                restarted = child["started_unix"] - t_kill_unix
                web: float | None = None
                first: float | None = None
                deadline = t_kill + args.timeout
                while time.monotonic() < deadline and (web is None or first is None):
                    if web is None:
                        try:
                            get(base + "/api/health", 0.5)
                            web = time.monotonic() - t_kill
                        except (OSError, ValueError):
                            pass
                    if first is None:
                        first = first_new_command(taps, t_kill)
                    time.sleep(0.02)
                restarted_s.append(restarted)
                if web is not None:
                    web_s.append(web)
                startup = startup_line(base)
                if external and web is not None and not get(base + "/api/arm")["armed"]:
                    # the new backend came up disarmed (and disarmed the relay): nothing
                    # after its first moments reaches the robots; armed again to go on
                    disarmed += 1
                    startup += "\n    the new backend came up DISARMED (armed again to go on)"
                    arm(base)
                if first is None:
                    never += 1
                    print(f"kill {i + 1}: restarted ({how}) {restarted * 1000:6.1f} ms, NO "
                          f"command from the new backend within {args.timeout:g} s; web "
                          f"{_ms(web)}{startup}", flush=True)
                    continue
                first_s.append(first)
                first_by.setdefault(how, []).append(first)
                print(f"kill {i + 1}: restarted ({how}) {restarted * 1000:6.1f} ms, first "
                      f"command {first * 1000:6.1f} ms, web {_ms(web)} after the kill"
                      f"{startup}", flush=True)
        finally:
            if station is not None:
                station.stop()
            log.close()
            if sim is not None:
                sim.stop()
            stop.set()
    print()
    what = "external simulator, armed" if external else "built-in simulator"
    print(f"backend restarts ({what}), times from the SIGKILL; load {_loadavg()}")
    print(ms_summary("kill -> restarted (supervisor)", restarted_s))
    print(ms_summary("kill -> first command from it", first_s))
    if len(first_by) > 1:
        for how, values in sorted(first_by.items()):
            print(ms_summary(f"  of which {how}", values))
    print(ms_summary("kill -> web answers (poll 20 ms)", web_s))
    if never:
        print(f"{never} of {args.kills} kills: no command from the new backend within "
              f"{args.timeout:g} s")
    if external:
        print(f"{disarmed} of {args.kills} kills: the new backend came up disarmed")
    return 0


def startup_line(base: str) -> str:
    try:
        startup = get(base + "/api/health").get("startup")
    except (OSError, ValueError):
        return ""
    if not startup:
        return ""
    steps = ", ".join(f"{k} {v * 1000:.0f}" for k, v in startup.get("steps_s", {}).items())
    frm = "the spare's word to start" if startup.get("standby") else "its process start"
    return f"\n    new backend from {frm} (ms): {steps}"


def _ms(v: float | None) -> str:
    return "-" if v is None else f"{v * 1000:6.1f} ms"


def _loadavg() -> str:
    try:
        return " ".join(Path("/proc/loadavg").read_text().split()[:3])
    except OSError:
        return "?"


def main() -> int:
    ap = argparse.ArgumentParser(description=(__doc__ or "").splitlines()[0])
    ap.add_argument("--target", choices=["relay", "backend"], default="relay")
    ap.add_argument("--sim", choices=["builtin", "external"], default="builtin",
                    help="--target backend: the launcher's fieldsim, or one started here "
                         "with the launcher on --sim none (arming required)")
    ap.add_argument("--kills", type=int, default=None,
                    help="default 5 (relay), 10 (backend)")
    ap.add_argument("--poll-ms", type=float, default=5.0)
    ap.add_argument("--timeout", type=float, default=15.0,
                    help="--target backend: a kill with no command within this many s counts "
                         "as never")
    ap.add_argument("--no-standby", action="store_true",
                    help="--target backend: the launcher keeps no warm spare (a cold restart)")
    ap.add_argument("--backend-arg", dest="backend_args", action="append", default=[],
                    help="--target backend: passed to the launcher's --backend-arg")
    ap.add_argument("--logs", type=Path, default=None,
                    help="keep the children's logs in this folder (default: a temporary one)")
    args = ap.parse_args()
    # a SIGTERM (timeout, kill) stops the station too, like Ctrl-C
    signal.signal(signal.SIGTERM, lambda *_: sys.exit(143))
    if args.target == "relay":
        args.kills = args.kills or 5
        return relay_mode(args)
    args.kills = args.kills or 10
    return backend_mode(args)



if __name__ == "__main__":
    raise SystemExit(main())
