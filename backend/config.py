"""Backend settings: one typed model, defaults in code, flags override (see __main__)."""

from __future__ import annotations

from pathlib import Path

from pydantic import BaseModel, Field

from sslnet import defaults

ROOT = Path(__file__).resolve().parent.parent


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
    state_dir: Path | None = ROOT / "var"  # parameters and presets; None: not persisted
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
    #: folders whose logs the page may open (besides the recording folder)
    log_dirs: list[Path] = Field(default_factory=list)
    #: False: this run records nothing, whatever the recording.enabled parameter says
    record: bool = True
    #: records into this folder for this run, whatever the recording.folder parameter says
    record_dir: Path | None = None
    #: the operator token for every change even on loopback (always off loopback)
    require_token: bool = False
    #: viewing (GET /api/*, the websocket) needs a token too (implies require_token)
    view_token: bool = False
    #: a viewer (no operator token) may press the emergency stop (a class)
    estop_for_all: bool = False
    #: keep the start-up objects out of the garbage collector (backend.station_loop.
    #: freeze_start_up); ``python -m backend`` sets it, a test process with many stations not
    freeze_gc: bool = False
    allowed_origins: list[str] = Field(
        default_factory=lambda: ["http://localhost:5173", "http://127.0.0.1:5173"]
    )
