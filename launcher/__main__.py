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
import shutil
import signal
import socket
import sys
import tempfile
import time
import urllib.error
import urllib.request
from collections.abc import Callable
from dataclasses import asdict
from pathlib import Path
from typing import TextIO

from backend.access import is_loopback
from backend.config import Settings
from sslnet import defaults
from sslnet.multicast import interface_multicast_flag, loopback_multicast_ok

from .started import PIDS, PORTS, READY, STATE_DIR
from .supervisor import ROOT, Ports, StationConfig, Supervisor, command_lines

ROOT_VAR = ROOT / "var"  # the backend's default state folder

log = logging.getLogger("touchline.launcher")


LO_FLAG_WARNING = (
    "lo has no MULTICAST flag: the station works without it, but the league's tools "
    "(ssl-vision-client, ssl-game-controller) skip interfaces without it: on a machine "
    "whose only interface is lo they hear nothing of this station. As root run:\n"
    "  ip link set lo multicast on\n(make run does this for you when run as root)")


def lo_flag_warning(
    interface: str, flag: Callable[[str], bool | None] = interface_multicast_flag
) -> str | None:
    """The warning for a station on loopback whose lo lacks the MULTICAST flag, else None."""
    if is_loopback(interface) and flag("lo") is False:
        return LO_FLAG_WARNING
    return None


def wait_http(url: str, timeout_s: float) -> bool:
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        try:
            with urllib.request.urlopen(url, timeout=1.0) as r:
                if r.status == 200:
                    return True
        except urllib.error.HTTPError as e:
            if e.code == 401:  # up, and asking for a token (--view-token)
                return True
        except OSError:
            pass
        time.sleep(0.2)
    return False



def announce(line: str, out: TextIO | None = None) -> None:
    """Writes a machine-readable line (for tests and scripts) as one write of the line and its
    newline. ``print`` writes the two apart when standard output is unbuffered
    (PYTHONUNBUFFERED, as the tests run it), and the children share the pipe: a child's log
    line written between them ended up inside "TOUCHLINE_READY <url>"."""
    stream = sys.stdout if out is None else out
    stream.write(line + "\n")
    stream.flush()

def http_port_taken(host: str, port: int) -> str | None:
    """Why the backend could not listen on ``host:port`` (bound as uvicorn binds it), or None."""
    family = socket.AF_INET6 if ":" in host else socket.AF_INET
    with socket.socket(family, socket.SOCK_STREAM) as s:
        s.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        try:
            s.bind((host, port))
        except OSError as exc:
            return exc.strerror or str(exc)
    return None


def _user_path(text: str) -> str:
    """A folder or file flag with ``~`` expanded: zsh (macOS's shell) leaves the ``~`` of
    ``make run TEAM=~/my-team`` as it is, bash expands it."""
    return os.path.expanduser(text)


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
    p.add_argument("--state-dir", type=_user_path, default=None,
                   help="parameters and presets folder (default var/, or TOUCHLINE_STATE_DIR; "
                        "--isolated: a temp dir)")
    p.add_argument("--seed", type=int, default=1)
    p.add_argument("--isolated", action="store_true",
                   help="free non-standard ports for everything (tests)")
    p.add_argument("--vision-port", type=int, default=None,
                   help="vision multicast port (default 10020, real SSL-Vision uses 10006)")
    p.add_argument("--sim-arg", dest="sim_args", action="append", default=[],
                   help="extra flag for fieldsim (repeatable), e.g. --sim-arg=--false-prob=0.2")
    p.add_argument("--relay-arg", dest="relay_args", action="append", default=[])
    p.add_argument("--backend-arg", dest="backend_args", action="append", default=[])
    p.add_argument("--log", type=_user_path, default=None, metavar="FILE",
                   help="replay this SSL log (.log or .log.gz) instead of live input: no "
                        "simulator, nothing sent to robots (make run LOG=FILE)")
    p.add_argument("--log-dir", type=_user_path, dest="log_dirs", action="append", default=[],
                   metavar="DIR",
                   help="a folder whose logs the page may open (repeatable)")
    p.add_argument("--no-record", action="store_true",
                   help="do not record this session into the recording folder (var/logs)")
    p.add_argument("--record-dir", type=_user_path, default=None, metavar="DIR",
                   help="record into DIR (default: logs/ in the state folder; or "
                        "TOUCHLINE_RECORD_DIR)")
    p.add_argument("--scripts-dir", type=_user_path, default=None, metavar="DIR",
                   help="the .m files the Octave engine runs (default engine_scripts/; or "
                        "TOUCHLINE_SCRIPTS_DIR). Folders are set here, never as parameters")
    p.add_argument("--reports-dir", type=_user_path, default=None, metavar="DIR",
                   help="the Evaluate tab's reports (default: reports/ in the state folder; "
                        "or TOUCHLINE_REPORTS_DIR)")
    p.add_argument("--suite-dir", type=_user_path, dest="suite_dirs", action="append",
                   default=[], metavar="DIR",
                   help="a folder of scenario suites the Evaluate tab offers (repeatable)")
    p.add_argument("--class-dir", type=_user_path, default=None, metavar="DIR",
                   help="a class: one sub-folder per student (the Evaluate tab grades them)")
    p.add_argument("--eval-cluster", default=None, metavar="ADDRESS",
                   help="the Evaluate tab's jobs on a Dask cluster (tcp://host:8786, or "
                        "local:N) instead of a local pool (docs/evaluate.md)")
    p.add_argument("--allow-host", dest="allow_hosts", action="append", default=[],
                   metavar="NAME", help="a name the station may be reached by besides the "
                   "bound address and localhost (repeatable; see python -m backend --help)")
    p.add_argument("--require-token", action="store_true",
                   help="every change needs the operator token even on loopback (always off "
                        "loopback); the login URL is printed at start (docs/security.md)")
    p.add_argument("--view-token", action="store_true",
                   help="viewing needs a token too (see python -m backend --help)")
    p.add_argument("--estop-for-all", action="store_true",
                   help="a viewer without the operator token may press the emergency stop")
    p.add_argument("--no-standby", action="store_true",
                   help="keep no warm spare backend: a crashed backend is then started cold "
                        "(its imports take 1-8 s on a busy 2-core machine instead of none; "
                        "the spare costs the memory of an idle backend)")
    p.add_argument("--team-dir", type=_user_path, default=None, metavar="DIR",
                   help="the team's code: plays, processors, libraries (make run TEAM=DIR; "
                        "default $TOUCHLINE_TEAM_DIR, else the example folder team/)")
    p.add_argument("--allow-code-edit", action="store_true",
                   help="operators on other machines may save team code from the page (it "
                        "runs on this machine: docs/security.md)")
    p.add_argument("--team-memory-mb", type=int, default=None, metavar="MB",
                   help="address-space limit of each team-code worker (default 1024)")
    a = p.parse_args()
    logging.basicConfig(level=logging.INFO,
                        format="%(asctime)s %(levelname)s launcher: %(message)s")

    if not loopback_multicast_ok() and a.interface == "127.0.0.1":
        log.error("multicast on loopback does not work on this machine. As root run:\n"
                  "  ip link set lo multicast on\n"
                  "  ip route replace 224.0.0.0/4 dev lo src 127.0.0.1\n"
                  "(make run does this for you when run as root)")
        return 2
    if (warning := lo_flag_warning(a.interface)) is not None:
        log.warning(warning)

    replay_args: list[str] = []
    if a.log is not None:
        if not os.path.isfile(a.log):
            log.error("no such log file: %s", a.log)
            return 2
        a.sim = "none"  # a replay has no simulator, and nothing is sent to robots
        replay_args.append(f"--log={os.path.abspath(a.log)}")
    replay_args += [f"--log-dir={os.path.abspath(d)}" for d in a.log_dirs]
    replay_args += [f"--suite-dir={os.path.abspath(d)}" for d in a.suite_dirs]
    if a.eval_cluster:
        replay_args.append(f"--eval-cluster={a.eval_cluster}")
    if a.team_dir is not None:
        if not os.path.isdir(a.team_dir):
            log.error("no such team folder: %s", a.team_dir)
            return 2
        replay_args.append(f"--team-dir={os.path.abspath(a.team_dir)}")
    if a.allow_code_edit:
        replay_args.append("--allow-code-edit")
    if a.team_memory_mb is not None:
        replay_args.append(f"--team-memory-mb={a.team_memory_mb}")
    if a.no_record:
        replay_args.append("--no-record")
    replay_args += [f"--{flag.replace('_', '-')}" for flag in
                    ("require_token", "view_token", "estop_for_all") if getattr(a, flag)]
    # the station's folders (backend/config.py): given here, or the TOUCHLINE_* variables
    # the backend inherits
    replay_args += [f"--{flag.replace('_', '-')}={os.path.abspath(getattr(a, flag))}"
                    for flag in ("record_dir", "scripts_dir", "reports_dir", "class_dir")
                    if getattr(a, flag)]
    ports = Ports.isolated(a.port) if a.isolated else Ports(http=a.port or defaults.BACKEND_PORT)
    own_state_dir: str | None = None  # a temporary state folder of ours: removed at exit
    if a.isolated and a.state_dir is None:
        a.state_dir = own_state_dir = tempfile.mkdtemp(prefix="touchline-state-")
    if a.vision_port:
        ports.vision = a.vision_port
    sup = Supervisor(command_lines(StationConfig(
        sim=a.sim, seed=a.seed, interface=a.interface, output=a.output, sim_host=a.sim_host,
        host=a.host, our_team=a.our_team, state_dir=a.state_dir, sim_args=a.sim_args,
        relay_args=a.relay_args,
        backend_args=[*(f"--allow-host={h}" for h in a.allow_hosts), *replay_args,
                      *a.backend_args]), ports),
        restart=True, standby=not a.no_standby,
        status_file=Path(a.state_dir or Settings.from_env().state_dir or ROOT_VAR)
        / "supervisor.json")
    stopping = False

    def on_signal(signum: int, _frame: object) -> None:
        nonlocal stopping
        stopping = True

    signal.signal(signal.SIGINT, on_signal)
    signal.signal(signal.SIGTERM, on_signal)

    taken = http_port_taken(a.host, ports.http)
    if taken is not None:  # the backend would fail to bind it and be restarted for ever
        log.error("the web port %s:%d is taken (%s): is a station already running? Stop it, "
                  "or start this one on another port (make run PORT=8001, --port 8001)",
                  a.host, ports.http, taken)
        if own_state_dir is not None:
            shutil.rmtree(own_state_dir, ignore_errors=True)
        return 2
    sup.start()
    url = f"http://{a.host}:{ports.http}"
    if wait_http(url + "/api/health", 30.0):
        print(f"\n  Touchline is running: {url}\n", flush=True)  # noqa: T201
        if a.require_token or a.view_token or not is_loopback(a.host):
            hint = ("  Changes need the operator token: open the login URL printed above "
                    "once on each operator laptop (docs/security.md)\n")
            print(hint, flush=True)  # noqa: T201
        # machine-readable lines for tests and scripts (read back by launcher/started.py)
        announce(f"{PORTS} {json.dumps(asdict(ports))}")
        if own_state_dir is not None:
            announce(f"{STATE_DIR} {own_state_dir}")
        pids = {c.name: c.proc.pid for c in sup.children if c.proc is not None}
        announce(f"{PIDS} {json.dumps(pids)}")
        announce(f"{READY} {url}")
    else:
        log.error("backend did not answer on %s within 30 s", url)

    try:
        while not stopping:
            why = sup.watch()
            if why is not None:
                log.error("%s", why)
                break
            sup.wait_exit(0.2)  # a child's exit wakes it at once
    finally:
        sup.stop(timeout_s=5.0)
        if own_state_dir is not None:
            shutil.rmtree(own_state_dir, ignore_errors=True)
        log.info("stopped")
    return 0

if __name__ == "__main__":
    raise SystemExit(main())
