"""Starts a whole match on isolated ports and tears it down again, whatever happens.

Children (each in its own session, its output in a log file, and told by the kernel to stop if
the runner dies): fieldsim with both teams and a truth publisher, one relay, and two backends on
that relay (blue: our strategy, yellow: the opponent), under the one supervisor
(``launcher.supervisor``), which builds their command lines.
"""

from __future__ import annotations

import http.client
import json
import logging
import shutil
import signal
import sys
import tempfile
import time
import urllib.request
from dataclasses import asdict, dataclass, field, replace
from pathlib import Path
from typing import IO, Any

from launcher.supervisor import (
    Child,
    Ports,
    StationConfig,
    Supervisor,
    command_lines,
    free_tcp_port,
)
from match.config import MatchConfig
from match.director import Director
from match.report import format_result, write_outputs
from match.shell import DirectorShell
from sslnet.multicast import loopback_multicast_ok

log = logging.getLogger("touchline.match")

EXIT_OK = 0
EXIT_DIED = 1  # something died or stalled during the match
EXIT_START = 2  # something failed to start
EXIT_INTERRUPTED = 130

TRUTH_STALE_S = 5.0  # no truth for this long during the match: fieldsim is considered dead


@dataclass
class Options:
    minutes: float = 3.0
    seed: int = 1
    division: str = "B"
    engine: str | None = None
    out: Path | None = None
    blue_play: str = "match"
    yellow_play: str = "simple"
    interface: str = "127.0.0.1"
    startup_timeout_s: float = 90.0
    status_every_s: float = 10.0
    backend_args: list[str] = field(default_factory=list)
    #: speed limit v (m/s) of every speed controller in both backends; None: the station's
    #: default (the paper's classroom 1.0 m/s)
    robot_speed_mps: float | None = 2.0

    @property
    def half_s(self) -> float:
        return self.minutes * 60.0 / 2.0

    @property
    def max_wall_s(self) -> float:
        """A bound on the whole match: the halves, every interlude and set piece timing out,
        half time, and slack for a loaded machine."""
        return self.minutes * 60.0 * 2.0 + 300.0


#: the controllers whose speed limit ``v_mps`` --robot-speed sets
SPEED_CONTROLLERS = ("algorithm1", "algorithm2", "proportional")


class StartupError(RuntimeError):
    pass


def build(opts: Options, ports: Ports, truth_endpoint: str, http: dict[str, int],
          state_dirs: dict[str, str]) -> list[Child]:
    plays = {"blue": opts.blue_play, "yellow": opts.yellow_play}
    sides = {"blue": -1, "yellow": 1}  # fieldsim puts blue on the negative half
    children: list[Child] = []
    for team in ("blue", "yellow"):
        backend_args = ["--our-side", str(sides[team]), *opts.backend_args]
        backend_args += ["--play", plays[team]]
        if team == "yellow":  # one relay, one tracker source: blue's estimate
            backend_args += ["--set", "tracker.publish=false"]
        if team == "blue" and opts.engine:
            backend_args += ["--set", f"strategy.engine={opts.engine}"]
        if opts.robot_speed_mps is not None:
            for ctrl in SPEED_CONTROLLERS:
                backend_args += ["--set", f"control.params.{ctrl}.v_mps={opts.robot_speed_mps}"]
        cfg = StationConfig(
            sim="builtin", seed=opts.seed, interface=opts.interface,
            sim_args=["--blue", "6", "--yellow", "6", "--division", opts.division,
                      "--truth-pub", truth_endpoint],
            our_team=team, state_dir=state_dirs[team], backend_args=backend_args)
        built = command_lines(cfg, replace(ports, http=http[team]))
        if team == "blue":
            children.extend(built[:-1])  # fieldsim and the relay, once
        backend = built[-1]
        backend.name = f"backend-{team}"
        children.append(backend)
    return children


def _health_ok(port: int) -> bool:
    try:
        with urllib.request.urlopen(f"http://127.0.0.1:{port}/api/health", timeout=2.0) as r:
            return r.status == 200 and bool(json.loads(r.read()).get("ok"))
    except (OSError, ValueError, http.client.HTTPException):
        # not (yet) our backend: nothing listening, or another program's protocol on the
        # port (a ZeroMQ greeting once: BadStatusLine crashed the runner)
        return False


class MatchRunner:
    def __init__(self, opts: Options, out: IO[str] = sys.stdout) -> None:
        self.opts = opts
        self.out = out
        self.stop_requested = False
        self.reason = ""
        self.died: set[str] = set()

    def say(self, text: str) -> None:
        self.out.write(text + "\n")
        self.out.flush()

    def _on_signal(self, signum: int, _frame: object) -> None:
        self.stop_requested = True
        self.reason = f"interrupted by {signal.Signals(signum).name}"

    def run(self) -> int:
        opts = self.opts
        if not loopback_multicast_ok() and opts.interface == "127.0.0.1":
            self.say("multicast on loopback does not work here; as root run "
                     "scripts/setup-multicast.sh .venv/bin/python (make match does it)")
            return EXIT_START
        old = {s: signal.signal(s, self._on_signal) for s in (signal.SIGINT, signal.SIGTERM)}
        tmp = Path(tempfile.mkdtemp(prefix="touchline-match-"))
        code = EXIT_START
        try:
            code = self._run(tmp)
            return code
        finally:
            for s, h in old.items():
                signal.signal(s, h)
            if opts.out is None and code != EXIT_OK:
                self.say(f"(process logs kept in {tmp / 'logs'})")
            else:
                shutil.rmtree(tmp, ignore_errors=True)

    def _run(self, tmp: Path) -> int:
        opts = self.opts
        ports = Ports.isolated(None)
        http = {"blue": free_tcp_port(), "yellow": free_tcp_port()}
        truth = f"tcp://127.0.0.1:{free_tcp_port()}"
        state_dirs = {t: str(tmp / f"state-{t}") for t in ("blue", "yellow")}
        log_dir = (opts.out / "logs") if opts.out is not None else tmp / "logs"
        procs = Supervisor(build(opts, ports, truth, http, state_dirs), log_dir=log_dir,
                           detach=True)
        director = Director(MatchConfig(
            half_s=opts.half_s, division=opts.division,
            plays={"blue": opts.blue_play, "yellow": opts.yellow_play}),
            wall_offset_s=time.time() - time.monotonic())
        shell = DirectorShell(director, truth_endpoint=truth, referee_group=ports.referee_group,
                              referee_port=ports.referee, sim_control=("127.0.0.1",
                                                                       ports.sim_control),
                              interface=opts.interface)
        code = EXIT_OK
        started = False
        self.say(f"MATCH_PORTS {json.dumps({**asdict(ports), 'http': http, 'truth': truth})}")
        try:
            procs.start()
            pids = {c.name: c.proc.pid for c in procs.children if c.proc is not None}
            self.say(f"MATCH_PIDS {json.dumps(pids)}")
            shell.open()
            self._wait_ready(procs, shell, http)
            started = True
            self.say(f"match: {opts.minutes} min, blue ({opts.blue_play}) v yellow "
                     f"({opts.yellow_play}), division {opts.division}, seed {opts.seed}; "
                     f"backends http://127.0.0.1:{http['blue']} and "
                     f"http://127.0.0.1:{http['yellow']}")
            self.say("MATCH_STARTED")
            code = self._play(procs, shell, director)
        except StartupError as exc:
            self.reason = str(exc)
            code = EXIT_INTERRUPTED if self.stop_requested else EXIT_START
            self.say(f"match could not start: {exc}")
        finally:
            shell.close()
            procs.stop()
        res = self._result(director, shell, procs, ports, http, started)
        res["exit_code"] = code
        if started:
            self.say("")
            self.say(format_result(res))
        if opts.out is not None:
            write_outputs(opts.out, res, director.timeline)
            self.say(f"result: {opts.out / 'result.json'}, events: {opts.out / 'events.csv'}")
        return code

    def _wait_ready(self, procs: Supervisor, shell: DirectorShell, http: dict[str, int]) -> None:
        deadline = time.monotonic() + self.opts.startup_timeout_s
        healthy: set[str] = set()
        truth = 0
        next_health = 0.0
        while True:
            if self.stop_requested:
                raise StartupError(self.reason)
            dead = procs.dead()
            if dead:
                c = dead[0]
                assert c.proc is not None
                raise StartupError(f"{c.name} exited with {c.proc.returncode} while starting:\n"
                                   f"{procs.log_tail(c.name)}")
            truth += len(shell.receive(0.1))
            now = time.monotonic()
            if now >= next_health:
                next_health = now + 0.5
                healthy |= {t for t, p in http.items() if t not in healthy and _health_ok(p)}
            if truth > 0 and healthy == set(http):
                return
            if now > deadline:
                raise StartupError(
                    f"not ready after {self.opts.startup_timeout_s:.0f} s: truth frames {truth}, "
                    f"healthy backends {sorted(healthy) or 'none'}")

    def _play(self, procs: Supervisor, shell: DirectorShell, director: Director) -> int:
        start = time.monotonic()
        next_status = start + self.opts.status_every_s
        while not director.finished:
            if self.stop_requested:
                return EXIT_INTERRUPTED
            shell.step(shell.receive(0.02))
            now = time.monotonic()
            dead = procs.dead()
            if dead:
                self.died |= {c.name for c in dead}
                c = dead[0]
                assert c.proc is not None
                self.reason = f"{c.name} exited with {c.proc.returncode} during the match"
                self.say(f"{self.reason}:\n{procs.log_tail(c.name)}")
                return EXIT_DIED
            if shell.last_truth_mono is None or now - shell.last_truth_mono > TRUTH_STALE_S:
                self.reason = f"no truth from fieldsim for {TRUTH_STALE_S:.0f} s"
                self.say(self.reason)
                return EXIT_DIED
            if now - start > self.opts.max_wall_s:
                self.reason = f"the match overran {self.opts.max_wall_s:.0f} s"
                self.say(self.reason)
                return EXIT_DIED
            if now >= next_status:
                next_status = now + self.opts.status_every_s
                self.say(self._status(director))
        # let every backend hear the final state (POST_GAME, HALT) before the teardown
        end = time.monotonic() + 1.0
        while time.monotonic() < end:
            shell.step(shell.receive(0.05))
        return EXIT_OK

    @staticmethod
    def _status(d: Director) -> str:
        r = d.referee
        left = (r.stage_time_left_us or 0) / 1e6
        t = d.now - d.t0 if d.t0 is not None else 0.0
        return (f"  {t:6.1f} s  {r.stage:<22} {r.command:<22} "
                f"blue {r.blue.score} : {r.yellow.score} yellow   stage time left {left:5.1f} s")

    def _result(self, director: Director, shell: DirectorShell, procs: Supervisor, ports: Ports,
                http: dict[str, int], started: bool) -> dict[str, Any]:
        res = director.result()
        o = self.opts
        res = {
            "version": 1,
            "options": {"minutes": o.minutes, "seed": o.seed, "division": o.division,
                        "engine": o.engine, "blue_play": o.blue_play,
                        "yellow_play": o.yellow_play, "robot_speed_mps": o.robot_speed_mps},
            "reason": self.reason,
            **res,
            "referee": {"source_identifier": director.referee.source_identifier,
                        "sent": shell.referee_sent, "send_errors": shell.referee_errors,
                        "teleports_sent": shell.teleports_sent,
                        "simulator_errors": shell.sim_errors[:20]},
            "truth_frames": shell.truth_frames,
            "processes": {c.name: {"alive_throughout": started and c.name not in self.died,
                                   "exit_code": procs.exit_codes.get(c.name)}
                          for c in procs.children},
            "ports": {**asdict(ports), "http": http},
        }
        return res
