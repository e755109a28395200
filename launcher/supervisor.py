"""One supervisor for Touchline's processes, importable: the command lines of fieldsim, the relay
and the backend from one typed :class:`StationConfig`, and a :class:`Supervisor` that starts
them, watches them, restarts a crashed one (when asked) and stops them in mirror order (the
backend first: it sends a last stop; the simulator last).

Used by ``python -m launcher`` (``make run``, the integration and browser tests, the websocket
benchmark) and by ``python -m match`` (two backends on one relay and one simulator)."""

from __future__ import annotations

import contextlib
import json
import logging
import os
import random
import select
import signal
import socket
import subprocess
import sys
import threading
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import IO

from sslnet import defaults

ROOT = Path(__file__).resolve().parent.parent
log = logging.getLogger("touchline.launcher")


#: every port this process has handed out (protocol, port): binding port 0 and closing lets the
#: kernel give the same number to the next call, and two parts of one station (a backend's HTTP
#: port and a relay's ZeroMQ socket, seen in a fresh clone's ``make match``) then collide
_handed_out: set[tuple[int, int]] = set()
_handed_lock = threading.Lock()


def _free_port(kind: int, tries: int = 64) -> int:
    """A port on 127.0.0.1 that is free now and was not handed out before in this process
    (other processes can still take it before it is bound: rare, not excluded)."""
    with _handed_lock:
        for _ in range(tries):
            with socket.socket(socket.AF_INET, kind) as s:
                s.bind(("127.0.0.1", 0))
                port: int = s.getsockname()[1]
            if (kind, port) not in _handed_out:
                _handed_out.add((kind, port))
                return port
    raise OSError(f"no fresh port after {tries} tries")


def free_tcp_port() -> int:
    return _free_port(socket.SOCK_STREAM)


def free_udp_port() -> int:
    return _free_port(socket.SOCK_DGRAM)


@dataclass
class Ports:
    http: int = defaults.BACKEND_PORT
    vision_group: str = defaults.VISION_GROUP
    vision: int = defaults.VISION_PORT_SIM
    referee_group: str = defaults.REFEREE_GROUP
    referee: int = defaults.REFEREE_PORT
    #: where the relay multicasts the station's tracked vision on loopback
    tracker_group: str = defaults.VISION_GROUP
    tracker: int = defaults.TRACKER_PORT
    sim_control: int = defaults.SIM_CONTROL_PORT
    sim_blue: int = defaults.SIM_BLUE_PORT
    sim_yellow: int = defaults.SIM_YELLOW_PORT
    grsim: int = defaults.GRSIM_COMMAND_PORT
    grsim_status_blue: int = defaults.GRSIM_STATUS_BLUE_PORT
    grsim_status_yellow: int = defaults.GRSIM_STATUS_YELLOW_PORT
    relay_pub: str = defaults.RELAY_PUB
    relay_sub: str = defaults.RELAY_SUB

    @staticmethod
    def isolated(http: int | None) -> Ports:
        """Free, non-standard ports for everything (tests: never disturb a running station)."""
        rnd = random.Random(os.getpid() ^ time.time_ns())
        return Ports(
            http=http or free_tcp_port(),
            vision=rnd.randrange(30000, 40000),
            referee=rnd.randrange(40000, 50000),
            tracker=rnd.randrange(50000, 60000),  # never the league's 10010 in a test
            sim_control=free_udp_port(),
            sim_blue=free_udp_port(),
            sim_yellow=free_udp_port(),
            grsim=free_udp_port(),
            grsim_status_blue=free_udp_port(),
            grsim_status_yellow=free_udp_port(),
            relay_pub=f"tcp://127.0.0.1:{free_tcp_port()}",
            relay_sub=f"tcp://127.0.0.1:{free_tcp_port()}",
        )


@dataclass
class StationConfig:
    """What the three processes are started with (the launcher's flags, typed)."""

    sim: str = "builtin"  # "builtin": fieldsim; "none": an external simulator or SSL-Vision
    seed: int = 1
    interface: str = "127.0.0.1"  # multicast interface (vision, referee)
    output: str = "sim"  # the relay's output: "sim", "grsim", "robot-box"
    sim_host: str = "127.0.0.1"
    host: str = "127.0.0.1"  # the backend's HTTP address
    our_team: str | None = None
    state_dir: str | None = None
    sim_args: list[str] = field(default_factory=list)
    relay_args: list[str] = field(default_factory=list)
    backend_args: list[str] = field(default_factory=list)

    @property
    def arming_required(self) -> bool:
        """Real robots or an external simulator (anything but the built-in simulator): the
        relay starts disarmed and the operator arms it from the page."""
        return not (self.sim == "builtin" and self.output == "sim")


#: a child that ran this long before it exited crashed in use, not at its start: it is
#: restarted at once (a child that exits sooner is restarted after a growing pause)
STEADY_S = 10.0
#: the pause before restarting a child that keeps exiting soon after its start, per restart
#: in the last minute, and at most
BACKOFF_STEP_S = 0.2
BACKOFF_MAX_S = 2.0
#: what the backend is told on a restart by the supervisor (not on a start of the station):
#: it takes the operator's arming back from its state folder (docs/security.md)
RESTARTED_FLAG = "--restarted"
#: a child with ``standby_args`` (the backend) gets a warm spare once it has run this long
#: (the spare's imports then do not compete with its own, 1-1.5 s on a quiet machine); a
#: spare that exited on its own is tried again ``SPARE_RETRY_S`` later. 5 s left a crash in
#: the first 5 s of play to a cold start (1.5 s to the first command on a quiet machine,
#: the issue's goal 1 s); a spare still importing at a crash is ready sooner than a cold start
SPARE_AFTER_S = 2.0
SPARE_RETRY_S = 60.0
#: after a spare took over (its start is over within a few hundred ms: nothing to import),
#: the next spare comes sooner, ready for a second crash
SPARE_AFTER_WARM_S = 1.0
#: the line that starts a spare (then the restart's flags): backend/__main__.py
SPARE_START = "start"


@dataclass
class Child:
    name: str
    argv: list[str]
    proc: subprocess.Popen[bytes] | None = None
    restarts: int = 0
    started: float = 0.0
    history: list[float] = field(default_factory=list)
    #: added to ``argv`` when the supervisor restarts the child (after a crash)
    restart_args: list[str] = field(default_factory=list)
    #: the running process's pidfd (Linux): the supervisor waits on it for the exit
    pidfd: int | None = None
    #: with the supervisor's ``standby``: ``argv`` plus these start a warm spare, a process
    #: that imports and waits for a line on its standard input (``SPARE_START`` and the
    #: restart's flags); a crash then costs no imports
    standby_args: list[str] = field(default_factory=list)
    spare: subprocess.Popen[bytes] | None = None
    #: no spare is started before this (monotonic): the child's start, a spare's failure
    spare_after: float = 0.0

    def restart_delay_s(self, now: float) -> float:
        """The pause before the restart due now: none for a child that ran ``STEADY_S``
        (a crash in use: the robots wait for it), else growing with the restarts of the last
        minute (a child that cannot start is not restarted in a tight loop)."""
        if now - self.started >= STEADY_S:
            return 0.0
        recent = sum(1 for t in self.history if now - t < 60)
        return min(BACKOFF_MAX_S, BACKOFF_STEP_S * recent)


def command_lines(cfg: StationConfig, ports: Ports) -> list[Child]:
    """fieldsim (with ``sim="builtin"``), the relay and the backend, in start order."""
    py = sys.executable
    children: list[Child] = []
    if cfg.sim == "builtin":
        children.append(Child("fieldsim", [
            py, "-m", "fieldsim",
            "--seed", str(cfg.seed),
            "--vision-group", ports.vision_group, "--vision-port", str(ports.vision),
            "--interface", cfg.interface,
            "--control-port", str(ports.sim_control), "--blue-port", str(ports.sim_blue),
            "--yellow-port", str(ports.sim_yellow), "--grsim-port", str(ports.grsim),
            "--grsim-status-blue-port", str(ports.grsim_status_blue),
            "--grsim-status-yellow-port", str(ports.grsim_status_yellow),
            *cfg.sim_args,
        ]))
    children.append(Child("relay", [
        py, "-m", "larcmacs_relay",
        "--vision", f"{ports.vision_group}:{ports.vision}",
        "--referee", f"{ports.referee_group}:{ports.referee}",
        "--interface", cfg.interface,
        "--output", cfg.output, "--sim-host", cfg.sim_host,
        "--sim-control-port", str(ports.sim_control), "--sim-blue-port", str(ports.sim_blue),
        "--sim-yellow-port", str(ports.sim_yellow), "--grsim-port", str(ports.grsim),
        "--grsim-status-blue-port", str(ports.grsim_status_blue),
        "--grsim-status-yellow-port", str(ports.grsim_status_yellow),
        "--pub", ports.relay_pub, "--sub", ports.relay_sub,
        # tracked vision on loopback only; the venue network needs --relay-arg=--tracker-out=...
        "--tracker-out-local", f"{ports.tracker_group}:{ports.tracker}",
        *(["--our-team", cfg.our_team] if cfg.our_team else []),
        *(["--require-arming"] if cfg.arming_required else []),
        *cfg.relay_args,
    ]))
    children.append(Child("backend", [
        py, "-m", "backend", "--host", cfg.host, "--port", str(ports.http),
        "--relay-pub", ports.relay_pub, "--relay-sub", ports.relay_sub,
        "--relay-output", cfg.output,
        *(["--require-arming"] if cfg.arming_required else []),
        *(["--our-team", cfg.our_team] if cfg.our_team else []),
        *(["--state-dir", cfg.state_dir] if cfg.state_dir else []),
        *cfg.backend_args,
    ], restart_args=[RESTARTED_FLAG], standby_args=["--standby"]))
    return children


def _die_with_parent() -> None:
    """In the child before exec: SIGTERM when the supervisor dies (Linux), so nothing is
    orphaned even if the supervisor is killed with SIGKILL."""
    with contextlib.suppress(Exception):
        import ctypes

        ctypes.CDLL(None, use_errno=True).prctl(1, signal.SIGTERM)  # PR_SET_PDEATHSIG


class Supervisor:
    """Starts ``children`` and keeps an eye on them.

    ``log_dir``: each child's output goes to ``<name>.log`` there (else it is inherited).
    ``restart``: :meth:`watch` restarts a child that exited, at most ``max_restarts`` times a
    minute (then it gives up and says why). ``standby`` (with ``restart``): a child with
    ``standby_args`` gets a warm spare, which takes over when it crashes (the launcher: the
    backend; kill -> first command then costs no imports). ``detach``: each child in its own
    session. Every child is told by the kernel to stop (SIGTERM) when the supervisor dies,
    killed or not."""

    def __init__(self, children: list[Child], *, log_dir: Path | None = None,
                 restart: bool = False, max_restarts: int = 5, detach: bool = False,
                 status_file: Path | None = None, standby: bool = False,
                 spare_after_s: float = SPARE_AFTER_S) -> None:
        self.children = children
        self.standby = standby
        self.spare_after_s = spare_after_s
        #: where the children's pids and restarts are written (the backend's Health tab reads
        #: it), after every start and restart; atomically
        self.status_file = status_file
        self._last_exit: dict[str, int | None] = {}
        self.log_dir = log_dir
        self.restart = restart
        self.max_restarts = max_restarts
        self.detach = detach
        self.exit_codes: dict[str, int | None] = {}
        self._logs: dict[str, IO[bytes]] = {}

    def start(self) -> None:
        if self.log_dir is not None:
            self.log_dir.mkdir(parents=True, exist_ok=True)
        for c in self.children:
            self._start(c)
        self.write_status()

    def write_status(self) -> None:
        if self.status_file is None:
            return
        status = {"time_unix": time.time(), "children": [
            {"name": c.name, "pid": c.proc.pid if c.proc is not None else None,
             "spare_pid": c.spare.pid if c.spare is not None else None,
             "restarts": c.restarts, "last_exit": self._last_exit.get(c.name),
             "started_unix": time.time() - (time.monotonic() - c.started)}
            for c in self.children]}
        try:
            self.status_file.parent.mkdir(parents=True, exist_ok=True)
            tmp = self.status_file.with_suffix(".tmp")
            tmp.write_text(json.dumps(status))
            tmp.replace(self.status_file)
        except OSError as exc:  # the station runs without it; the page just shows no restarts
            log.warning("cannot write %s: %s", self.status_file, exc)

    def _start(self, c: Child, restart: bool = False) -> None:
        argv = [*c.argv, *c.restart_args] if restart else c.argv
        log.info("starting %s: %s", c.name, " ".join(argv[1:]))
        self._close_pidfd(c)
        c.proc = self._popen(c, argv, self._log_file(c))
        self._running(c)

    def _log_file(self, c: Child) -> IO[bytes] | None:
        if self.log_dir is None:
            return None
        old = self._logs.pop(c.name, None)
        if old is not None:
            old.close()
        out = self._logs[c.name] = (self.log_dir / f"{c.name}.log").open("ab")
        return out

    def _popen(self, c: Child, argv: list[str], out: IO[bytes] | None,
               spare: bool = False) -> subprocess.Popen[bytes]:
        stdin = subprocess.PIPE if spare else subprocess.DEVNULL if self.detach else None
        return subprocess.Popen(
            argv, cwd=ROOT, stdout=out, stderr=subprocess.STDOUT if out else None,
            stdin=stdin, start_new_session=self.detach,
            preexec_fn=_die_with_parent)  # never orphaned, even by a SIGKILL of ours

    def _running(self, c: Child, warm: bool = False) -> None:
        """``c.proc`` runs as the child from now on (``warm``: a spare that took over)."""
        assert c.proc is not None
        c.started = time.monotonic()
        after = min(self.spare_after_s, SPARE_AFTER_WARM_S) if warm else self.spare_after_s
        c.spare_after = max(c.spare_after, c.started + after)
        with contextlib.suppress(AttributeError, OSError):  # not Linux >= 5.3: polled
            c.pidfd = os.pidfd_open(c.proc.pid)

    def _keep_spares(self) -> None:
        """A warm spare for each child that has ``standby_args`` and has run a while; a
        spare that exited on its own is said, and tried again a minute later."""
        now = time.monotonic()
        for c in self.children:
            if not c.standby_args or c.proc is None:
                continue
            if c.spare is not None and c.spare.poll() is not None:
                log.warning("the warm spare of %s exited with %s; another in %.0f s", c.name,
                            c.spare.returncode, SPARE_RETRY_S)
                c.spare = None
                c.spare_after = now + SPARE_RETRY_S
            if c.spare is None and now >= c.spare_after and c.proc.poll() is None:
                argv = [*c.argv, *c.standby_args]
                out = self._logs.get(c.name)
                c.spare = self._popen(c, argv, out, spare=True)
                log.info("warm spare of %s started (pid %d)", c.name, c.spare.pid)
                self.write_status()

    def _take_spare(self, c: Child) -> bool:
        """The crashed child's warm spare becomes the child, told to start with the
        restart's flags; False when there is none (or it is gone)."""
        spare, c.spare = c.spare, None
        if spare is None:
            return False
        line = " ".join([SPARE_START, *c.restart_args]) + "\n"
        try:
            assert spare.stdin is not None
            spare.stdin.write(line.encode())
            spare.stdin.close()
        except (OSError, ValueError):  # it died just now
            self._end_spare(spare)
            return False
        if spare.poll() is not None:
            return False
        log.info("%s: the warm spare (pid %d) takes over", c.name, spare.pid)
        self._close_pidfd(c)
        c.proc = spare
        self._running(c, warm=True)
        return True

    @staticmethod
    def _end_spare(spare: subprocess.Popen[bytes], timeout_s: float = 5.0) -> None:
        """A spare not needed: its standard input closed (a waiting spare exits at once);
        one still importing is stopped (SIGTERM: it has nothing to clean up), then killed."""
        with contextlib.suppress(OSError, ValueError):
            if spare.stdin is not None:
                spare.stdin.close()
        try:
            spare.wait(timeout=min(1.0, timeout_s))
            return
        except subprocess.TimeoutExpired:
            spare.terminate()
        try:
            spare.wait(timeout=timeout_s)
        except subprocess.TimeoutExpired:
            spare.kill()
            spare.wait(timeout=timeout_s)

    @staticmethod
    def _close_pidfd(c: Child) -> None:
        if c.pidfd is not None:
            with contextlib.suppress(OSError):
                os.close(c.pidfd)
            c.pidfd = None

    def wait_exit(self, timeout_s: float) -> None:
        """Returns when a child has exited or after ``timeout_s``: the launcher's loop calls
        :meth:`watch` right after, so a crashed child is seen at once, not at the next poll
        (it polled every 0.2 s). Without pidfds (not Linux) it just waits."""
        if self.dead():
            return
        fds = [c.pidfd for c in self.children if c.pidfd is not None]
        if not fds:
            time.sleep(timeout_s)
            return
        poller = select.poll()
        for fd in fds:
            poller.register(fd, select.POLLIN)  # readable: the process has exited
        poller.poll(timeout_s * 1000)

    def child(self, name: str) -> Child:
        return next(c for c in self.children if c.name == name)

    def dead(self) -> list[Child]:
        return [c for c in self.children if c.proc is not None and c.proc.poll() is not None]

    def watch(self) -> str | None:
        """Restarts children that exited (with ``restart``); returns why it gives up, if it
        does (a child crashing more than ``max_restarts`` times a minute)."""
        for c in self.dead():
            assert c.proc is not None
            code = c.proc.returncode
            if not self.restart:
                return f"{c.name} exited with {code}"
            now = time.monotonic()
            c.history = [t for t in c.history if now - t < 60] + [now]
            if len(c.history) > self.max_restarts:
                return f"{c.name} exited {code} and keeps crashing; giving up"
            c.restarts += 1
            self._last_exit[c.name] = code
            if self._take_spare(c):
                log.warning("%s exited with %s; restarting: its warm spare took over", c.name,
                            code)
                self.write_status()
                continue
            delay = c.restart_delay_s(now)
            log.warning("%s exited with %s; restarting%s", c.name, code,
                        f" in {delay:.1f} s" if delay else "")
            if delay:
                time.sleep(delay)
            self._start(c, restart=True)
            self.write_status()
        if self.restart and self.standby:
            self._keep_spares()
        return None

    def log_tail(self, name: str, lines: int = 25) -> str:
        if self.log_dir is None:
            return ""
        try:
            text = (self.log_dir / f"{name}.log").read_text(errors="replace")
        except OSError:
            return ""
        return "\n".join(text.splitlines()[-lines:])

    def stop(self, timeout_s: float = 10.0) -> None:
        """Mirror order, one after the other: the backend first (it sends a last stop to the
        relay), then the relay (its own last stop to the robots), the simulator last; a child
        that does not stop within ``timeout_s`` is killed."""
        for c in self.children:  # spares first: nothing of theirs to stop
            if c.spare is not None:
                self._end_spare(c.spare, timeout_s)
                c.spare = None
        for c in reversed(self.children):
            if c.proc is None:
                continue
            if c.proc.poll() is None:
                c.proc.send_signal(signal.SIGTERM)
                try:
                    c.proc.wait(timeout=timeout_s)
                except subprocess.TimeoutExpired:
                    log.warning("%s did not stop in %.0f s: killing it", c.name, timeout_s)
                    c.proc.kill()
                    c.proc.wait(timeout=timeout_s)
            self.exit_codes[c.name] = c.proc.returncode
            self._close_pidfd(c)
        for f in self._logs.values():
            f.close()
        self._logs.clear()
