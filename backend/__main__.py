"""`python -m backend`: the strategy-bridge and the web station on one port.

The start is ordered for the robots (after a crash the first command counts): the station
(ZeroMQ, the processors, the e-stop and arming from the state folder) starts first, and what
its first command does not need (the web side's imports and server, the session recorder's
file, the compute engine) once that command went to the relay (backend/startup.py).

``--standby`` (the launcher's warm spare): the process imports everything, then waits for a
line on its standard input and starts only then, with that line's flags added after its
own (the supervisor sends ``start --restarted`` when the running backend has crashed). The
imports, most of a start on a busy machine, are then done before the crash."""

from __future__ import annotations

import argparse
import logging
import os
import signal
import sys
import threading
import time
from pathlib import Path
from typing import TYPE_CHECKING

from .config import Settings
from .security import MAX_BODY_BYTES, MAX_JSON_DEPTH
from .startup import StartupTimeline, process_start_mono

if TYPE_CHECKING:
    from .access import AccessRule

log = logging.getLogger("touchline.startup")

#: the web side waits at most this long for the station's first command (no vision: it
#: starts anyway)
LATE_START_MAX_S = 2.0


#: the first word of the line that starts a standby backend (then its flags)
STANDBY_START = "start"


def main() -> None:
    t0 = process_start_mono()
    p = _parser()
    argv = sys.argv[1:]
    a = p.parse_args(argv)
    logging.basicConfig(level=a.log_level.upper(),
                        format="%(asctime)s %(levelname)s %(name)s: %(message)s")
    if a.standby:
        words = _stand_by()
        if words is None:
            return
        a = p.parse_args([*argv, *words])
        t0 = time.monotonic()  # the steps count from the word to start
    timeline = StartupTimeline(t0)
    timeline.standby = a.standby
    settings = Settings(host=a.host, port=a.port, relay_pub=a.relay_pub, relay_sub=a.relay_sub,
                        our_team=a.our_team, our_side=a.our_side, allowed_hosts=a.allow_hosts,
                        relay_output=a.relay_output, require_arming=a.require_arming,
                        play="idle" if a.no_demo else a.play,
                        set_params=a.set_params, state_dir=a.state_dir, log=a.log,
                        log_dirs=(Settings.from_env().log_dirs if a.log_dirs is None
                                  else a.log_dirs),
                        record=not a.no_record, scripts_dir=a.scripts_dir,
                        record_dir=a.record_dir, require_token=a.require_token,
                        reports_dir=a.reports_dir, class_dir=a.class_dir,
                        suite_dirs=(Settings.from_env().suite_dirs if a.suite_dirs is None
                                    else a.suite_dirs),
                        eval_workers=a.eval_workers, eval_cluster=a.eval_cluster,
                        view_token=a.view_token, estop_for_all=a.estop_for_all,
                        team_dir=a.team_dir,
                        allow_code_edit=a.allow_code_edit, team_memory_mb=a.team_memory_mb,
                        freeze_gc=True, restarted=a.restarted,
                        late_start_max_s=LATE_START_MAX_S)
    run(settings, timeline, a.log_level)


def _stand_by() -> list[str] | None:
    """A warm spare: imports what a start imports (the station and the web side), then waits
    for the supervisor's line. Returns its flags, or None when told nothing (standard input
    closed: the station stops, or the spare is not needed)."""
    import uvicorn  # noqa: F401

    from . import api, station  # noqa: F401

    log.info("standby (pid %d): imported, waiting for the word to start", os.getpid())
    line = sys.stdin.readline()
    words = line.split()
    if not words or words[0] != STANDBY_START:
        log.info("standby: not needed, exiting")
        return None
    log.warning("standby: starting (%s)", " ".join(words[1:]) or "no flags added")
    return words[1:]


def _parser() -> argparse.ArgumentParser:
    d = Settings.from_env()  # the folders may come from TOUCHLINE_* variables (config.py)
    p = argparse.ArgumentParser(
        prog="python -m backend", description=__doc__,
        epilog="Web security (docs/api.md, Security): the Host header must be the bound "
               "address, localhost, 127.0.0.1, ::1 or an --allow-host name (else 400); a "
               "browser's Origin must be one of those too; POST/PUT/PATCH/DELETE need "
               "Content-Type: application/json or X-Touchline: 1; bodies and websocket "
               f"messages at most {MAX_BODY_BYTES / (1 << 20):g} MiB, JSON at most "
               f"{MAX_JSON_DEPTH} levels deep. Access (docs/security.md): on any address but "
               "loopback, or with --require-token, changes need the operator token "
               "(var/token, or TOUCHLINE_TOKEN; the login URL is printed at start).")
    p.add_argument("--host", default=d.host, help="bind address (default %(default)s)")
    p.add_argument("--port", type=int, default=d.port)
    p.add_argument("--relay-pub", default=d.relay_pub, help="relay PUB endpoint to subscribe to")
    p.add_argument("--relay-sub", default=d.relay_sub, help="relay SUB endpoint to publish to")
    p.add_argument("--our-team", choices=["blue", "yellow"], default=None,
                   help="override the stored parameter team.our_team")
    p.add_argument("--our-side", type=int, choices=[-1, 1], default=None,
                   help="override team.our_side: -1 our goal at negative x")
    p.add_argument("--play", default=None,
                   help="override strategy.play (match, defend, attack-drill, formation, "
                        "simple, idle)")
    p.add_argument("--no-demo", action="store_true", help="same as --play idle")
    p.add_argument("--set", dest="set_params", action="append", default=[], metavar="KEY=VALUE",
                   help="override a parameter, e.g. --set strategy.engine=octave (VALUE is "
                        "JSON, or text); repeatable")
    p.add_argument("--state-dir", type=Path, default=d.state_dir,
                   help="where parameters and presets are kept (default %(default)s; "
                        "TOUCHLINE_STATE_DIR)")
    p.add_argument("--scripts-dir", type=Path, default=d.scripts_dir, metavar="DIR",
                   help="the .m files the Octave engine runs (default %(default)s; "
                        "TOUCHLINE_SCRIPTS_DIR). Folders are never parameters: "
                        "docs/security.md")
    p.add_argument("--allow-host", dest="allow_hosts", action="append", default=[],
                   metavar="NAME",
                   help="a host name or address this station may be reached by besides the "
                        "bound address and localhost (repeatable; '*' for any: not on a "
                        "shared network). Other Host headers get 400 (DNS rebinding).")
    p.add_argument("--require-token", action="store_true",
                   help="every change needs the operator token even on loopback (it always "
                        "does on any other address; docs/security.md)")
    p.add_argument("--view-token", action="store_true",
                   help="viewing (GET /api/*, the websocket) needs a token too: the viewer "
                        "token (var/view-token, or TOUCHLINE_VIEW_TOKEN) or the operator's")
    p.add_argument("--estop-for-all", action="store_true",
                   help="a viewer without the operator token may press (not release) the "
                        "emergency stop (a class)")
    p.add_argument("--relay-output", choices=["sim", "grsim", "robot-box"], default=None,
                   help="the relay's output (the launcher passes it): on robot-box, whose "
                        "datagrams have no team field, only our team is ever commanded")
    p.add_argument("--require-arming", action="store_true",
                   help="the relay drives real robots or an external simulator (the launcher "
                        "passes it): the station starts disarmed, an operator arms it")
    p.add_argument("--log", type=Path, default=None, metavar="FILE",
                   help="replay this SSL log file (.log or .log.gz) instead of live input: "
                        "nothing is sent to robots or a simulator")
    p.add_argument("--log-dir", dest="log_dirs", type=Path, action="append", default=None,
                   metavar="DIR", help="a folder whose logs the page may open (repeatable; the "
                   "recording folder always is; TOUCHLINE_LOG_DIRS, separated by "
                   f"{os.pathsep!r})")
    p.add_argument("--record-dir", type=Path, default=d.record_dir, metavar="DIR",
                   help="record into DIR (default: logs/ in the state folder; "
                        "TOUCHLINE_RECORD_DIR)")
    p.add_argument("--reports-dir", type=Path, default=d.reports_dir, metavar="DIR",
                   help="the Evaluate tab's reports and their runs' logs (default: reports/ "
                        "in the state folder; TOUCHLINE_REPORTS_DIR)")
    p.add_argument("--suite-dir", dest="suite_dirs", type=Path, action="append", default=None,
                   metavar="DIR", help="a folder of scenario suites the Evaluate tab offers "
                   "(repeatable; TOUCHLINE_SUITE_DIRS)")
    p.add_argument("--class-dir", type=Path, default=d.class_dir, metavar="DIR",
                   help="a class: one sub-folder per student, each a team folder "
                        "(TOUCHLINE_CLASS_DIR)")
    p.add_argument("--eval-workers", type=int, default=None, metavar="N",
                   help="the Evaluate tab's pool workers (default: cores - 1, at least 1)")
    p.add_argument("--eval-cluster", default=None, metavar="ADDRESS",
                   help="run the Evaluate tab's jobs on a Dask cluster: a scheduler's "
                        "tcp://host:8786, or local:N (docs/evaluate.md)")
    p.add_argument("--no-record", action="store_true",
                   help="do not record this session (the recording.enabled parameter stays as "
                        "it is, for the next start)")
    p.add_argument("--team-dir", type=Path, default=d.team_dir, metavar="DIR",
                   help="the team's code: plays, processors and libraries (default "
                        "%(default)s, the example folder; TOUCHLINE_TEAM_DIR; "
                        "docs/team-code.md)")
    p.add_argument("--allow-code-edit", action="store_true",
                   help="operators on other machines may save team code from the page (it "
                        "runs on this machine: docs/security.md); from loopback it always may")
    p.add_argument("--team-memory-mb", type=int, default=d.team_memory_mb, metavar="MB",
                   help="address-space limit of each team-code worker process "
                        "(default %(default)s)")
    p.add_argument("--restarted", action="store_true",
                   help="the launcher's supervisor restarts this backend after a crash (it "
                        "adds this flag): the operator's arming is taken back from the state "
                        "folder. Any other start is disarmed (docs/security.md)")
    p.add_argument("--standby", action="store_true",
                   help="a warm spare (the launcher starts one): import, then wait for a line "
                        f"'{STANDBY_START} [FLAGS]' on standard input and start with FLAGS "
                        "added; any other line, or none, exits")
    p.add_argument("--log-level", default="INFO")
    return p


def run(settings: Settings, timeline: StartupTimeline, log_level: str) -> None:
    """The station first, the web side once its first command is out."""
    # a stop asked for before the web side runs (uvicorn's own handlers take over then) is
    # still an orderly one: the station sends its last stop
    stopping = threading.Event()
    for sig in (signal.SIGINT, signal.SIGTERM):
        signal.signal(sig, lambda *_: stopping.set())
    from .station import Station  # numpy, scipy, ZeroMQ, the strategy: the first command's

    timeline.mark("imports")
    station = Station(settings, timeline)
    timeline.mark("station built")
    station.start_thread()
    # the web side once the first command is out: its imports and start would otherwise take
    # the CPU and the GIL from it
    while not station.late_started.wait(0.05) and not stopping.is_set():
        pass
    if stopping.is_set():
        station.stop_thread()
        return
    import uvicorn

    from .access import base_url, print_login
    from .api import create_app

    timeline.mark("web imports")
    if stopping.is_set():
        station.stop_thread()
        return
    app = create_app(settings, station)
    rule: AccessRule = app.state.access
    if rule.required:
        # the URL to open once per laptop (the launcher's output shows it)
        print_login(rule, base_url(settings.host, settings.port, settings.allowed_hosts))
    # the page sends nothing on the websocket: a client's message is capped like a body
    uvicorn.run(app, host=settings.host, port=settings.port, ws_per_message_deflate=False,
                ws_max_size=MAX_BODY_BYTES, log_level=log_level.lower(), access_log=False)


if __name__ == "__main__":
    main()
