"""Backend settings: one typed model, defaults in code, flags override (see __main__).

The folders the station reads code from or writes to (``station_folder`` fields) are set only
when it starts, by the machine's owner: a flag, or one ``TOUCHLINE_<NAME>`` environment
variable each, read here (``Settings.from_env``) and nowhere else. They are never parameters
a page could change (docs/security.md, "What the web can reach on disk"); the page shows them
read-only (GET /api/folders). One more such folder is one more ``station_folder`` field: its
flag, its variable and its line in the page follow from it."""

from __future__ import annotations

import os
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from pydantic import BaseModel, Field, field_validator

from sslnet import defaults

from . import contract

ROOT = Path(__file__).resolve().parent.parent

#: the environment variable of a station folder is this and the field's name in capitals
ENV_PREFIX = "TOUCHLINE_"
_FOLDER = "station_folder"


def station_folder(default: Any, flag: str, label: str, what: str) -> Any:
    """A folder set when the station starts (``flag`` or ``TOUCHLINE_<NAME>``); ``default`` a
    value, or ``list`` for a repeatable flag (the variable then holds os.pathsep-separated
    folders)."""
    kw: dict[str, Any] = {"default_factory": list} if default is list else {"default": default}
    return Field(**kw, json_schema_extra={_FOLDER: {"flag": flag, "label": label,
                                                    "what": what}})


class Settings(BaseModel):
    host: str = "127.0.0.1"
    port: int = defaults.BACKEND_PORT
    relay_pub: str = defaults.RELAY_PUB  # the relay's PUB we subscribe to
    relay_sub: str = defaults.RELAY_SUB  # the relay's SUB we publish commands to
    # start-up overrides of the persisted parameters (None: keep what is stored)
    our_team: str | None = Field(default=None, pattern="^(blue|yellow)$")
    our_side: int | None = None  # -1: our goal at negative x
    play: str | None = None  # strategy.play
    set_params: list[str] = Field(default_factory=list)  # "group.key=value" (value JSON or text)
    static_dir: Path = ROOT / "frontend" / "dist"
    # ---- the station's folders (in the order the page lists them)
    scripts_dir: Path = station_folder(
        ROOT / "engine_scripts", "--scripts-dir", "Octave scripts",
        "the .m files the Octave engine runs (strategy.engine = octave)")
    #: None: logs/ in the state folder
    record_dir: Path | None = station_folder(
        None, "--record-dir", "Recordings",
        "where live sessions are recorded (default: logs/ in the state folder; the log cache "
        "goes beside it)")
    log_dirs: list[Path] = station_folder(
        list, "--log-dir", "Log folders", "more folders whose logs the page may open (the "
        "recordings always are)")
    state_dir: Path | None = station_folder(
        ROOT / "var", "--state-dir", "State",
        "parameters, presets, tokens, the e-stop latch; None: nothing persisted (tests)")
    team_dir: Path = station_folder(
        ROOT / "team", "--team-dir", "Team code",
        "the team's own plays, processors and libraries, run in worker processes and "
        "reloaded on every save (make run TEAM=...; docs/team-code.md)")
    #: None: reports/ in the state folder
    reports_dir: Path | None = station_folder(
        None, "--reports-dir", "Evaluation reports",
        "where the Evaluate tab writes its reports and their runs' logs, and lists them "
        "(default: reports/ in the state folder)")
    suite_dirs: list[Path] = station_folder(
        list, "--suite-dir", "Scenario suites", "more folders of scenario suites the Evaluate "
        "tab offers (the folder, or each sub-folder, with *.toml files; the shipped exercises "
        "and regression always are)")
    class_dir: Path | None = station_folder(
        None, "--class-dir", "Class", "one sub-folder per student (each a team folder): the "
        "Evaluate tab runs the exercises for each of them")
    #: the relay's output as the launcher started it ("sim", "grsim", "robot-box"); the relay's
    #: own stats confirm it. None: unknown until the relay says (the other team is refused)
    relay_output: str | None = None
    #: the relay requires arming (real robots, an external simulator; the launcher says so,
    #: the relay's stats confirm it): the station starts disarmed, an operator arms it
    require_arming: bool = False
    #: names the Host header may carry besides the bound address and loopback ("*": any)
    allowed_hosts: list[str] = Field(default_factory=list)
    #: a log file to replay from the start instead of live input (``make run LOG=...``)
    log: Path | None = None
    #: False: this run records nothing, whatever the recording.enabled parameter says
    record: bool = True
    #: the Evaluate tab's pool workers (None: cores - 1, at least 1)
    eval_workers: int | None = Field(default=None, ge=1, le=256)
    #: the Evaluate tab's jobs on a Dask cluster instead of the local pool: a scheduler's
    #: address (tcp://host:8786) or local:N (a LocalCluster of N workers started per job)
    eval_cluster: str | None = Field(default=None, pattern=r"^((tcp|tls)://\S+|local:\d{1,3})$")
    #: the operator token for every change even on loopback (always off loopback)
    require_token: bool = False
    #: viewing (GET /api/*, the websocket) needs a token too (implies require_token)
    view_token: bool = False
    #: a viewer (no operator token) may press the emergency stop (a class)
    estop_for_all: bool = False
    #: restarted by the launcher's supervisor after a crash (``--restarted``): the
    #: operator's arming is taken back from the state folder; any other start is disarmed
    restarted: bool = False
    #: what the first command does not need (the recorder's file, the compute engine, the
    #: web side in ``python -m backend``) starts once the first command set went to the
    #: relay, or this many seconds after the station runs without one (no vision yet);
    #: 0: everything at once (tests that build a station in-process)
    late_start_max_s: float = 0.0
    #: the page may save team code from another machine (an operator, with the token); from
    #: loopback it always may. It runs code on this machine: docs/security.md
    allow_code_edit: bool = False
    #: the address-space limit of each team-code worker process (RLIMIT_AS), MB
    team_memory_mb: int = Field(default=1024, ge=64, le=65536)
    #: keep the start-up objects out of the garbage collector (backend.station_loop.
    #: freeze_start_up); ``python -m backend`` sets it, a test process with many stations not
    freeze_gc: bool = False
    allowed_origins: list[str] = Field(
        default_factory=lambda: ["http://localhost:5173", "http://127.0.0.1:5173"]
    )

    @field_validator("scripts_dir", "record_dir", "state_dir", "log_dirs", "team_dir",
                     "reports_dir", "suite_dirs", "class_dir")
    @classmethod
    def _absolute(cls, v: Path | list[Path] | None) -> Path | list[Path] | None:
        # shown to the operator and compared with the page's paths: absolute, ~ expanded
        if isinstance(v, list):
            return [p.expanduser().absolute() for p in v]
        return None if v is None else v.expanduser().absolute()

    @classmethod
    def folder_fields(cls) -> dict[str, dict[str, str]]:
        """The station folders: field name -> {"flag", "label", "what"}, in page order."""
        out: dict[str, dict[str, str]] = {}
        for name, f in cls.model_fields.items():
            extra = f.json_schema_extra
            if isinstance(extra, dict) and isinstance(extra.get(_FOLDER), dict):
                out[name] = dict(extra[_FOLDER])  # type: ignore[arg-type]
        return out

    @staticmethod
    def env_name(field: str) -> str:
        return ENV_PREFIX + field.upper()

    @classmethod
    def from_env(cls, environ: Mapping[str, str] | None = None, **values: Any) -> Settings:
        """Settings with the folders the environment sets (``TOUCHLINE_SCRIPTS_DIR``, ...;
        an empty variable is unset); ``values`` (the command line) win over both."""
        env = os.environ if environ is None else environ
        found: dict[str, Any] = {}
        for name in cls.folder_fields():
            raw = env.get(cls.env_name(name), "")
            if not raw:
                continue
            if cls.model_fields[name].default_factory is list:
                found[name] = [Path(p) for p in raw.split(os.pathsep) if p]
            else:
                found[name] = Path(raw)
        return cls(**{**found, **values})

    def recording_folder(self) -> Path | None:
        """Where live sessions are recorded: --record-dir, else logs/ in the state folder;
        None: nowhere (no state kept and no --record-dir: tests)."""
        if self.record_dir is not None:
            return self.record_dir
        return None if self.state_dir is None else self.state_dir / "logs"

    def reports_folder(self) -> Path | None:
        """Where the Evaluate tab's reports go: --reports-dir, else reports/ in the state
        folder (var/reports by default); None: nowhere (no state kept: tests)."""
        if self.reports_dir is not None:
            return self.reports_dir
        return None if self.state_dir is None else self.state_dir / "reports"

    def station_folders(self) -> contract.StationFolders:
        """GET /api/folders: every station folder as this run uses it, read-only."""
        out: list[contract.StationFolder] = []
        for name, meta in self.folder_fields().items():
            value: Any = (self.recording_folder() if name == "record_dir" else
                          self.reports_folder() if name == "reports_dir" else
                          getattr(self, name))
            paths = value if isinstance(value, list) else [] if value is None else [value]
            out.append({"name": name, "label": meta["label"], "what": meta["what"],
                        "paths": [str(p) for p in paths], "flag": meta["flag"],
                        "env": self.env_name(name)})
        return {"folders": out}
