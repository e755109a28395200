"""The station's side of the session recorder: where and whether it records, what it takes
besides datagrams and commands (parameters, operator actions, health, stages), its buttons."""

from __future__ import annotations

import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

from ssllog.format import TYPE_TL_ACTION, TYPE_TL_HEALTH, TYPE_TL_PARAMS

from . import contract, topics
from .bus import DataBus
from .config import ROOT, Settings
from .jsonsafe import dumps
from .params.model import StationParams
from .params.store import ParamStore, diff
from .processor import Every, Processor
from .recorder import SessionRecorder


class RecordingControl:
    """Makes the recorder (``open``), follows the parameters (``configure``), records
    operator actions, answers the page's recording buttons and status. ``settings``: where
    and whether to record (set at start); ``params``: the recording switch the buttons set."""

    def __init__(self, settings: Settings, params: ParamStore) -> None:
        self.settings = settings
        self.params = params
        self.recorder: SessionRecorder | None = None  # made in open() (it opens a file)
        self._params_recorded: dict[str, Any] | None = None

    def folder(self) -> Path:
        """Set when the station starts (--record-dir, else logs/ in the state folder), never
        by a parameter: a page must not make the station write where it likes."""
        return self.settings.recording_folder() or ROOT / "var" / "logs"

    def wanted(self, p: StationParams) -> bool:
        """Records live sessions unless told not to (the parameter, --no-record), when
        replaying from the command line, or for a station that keeps no state (tests)."""
        s = self.settings
        return (p.recording.enabled and s.record and s.log is None
                and s.recording_folder() is not None)

    def open(self, p: StationParams) -> SessionRecorder:
        rp = p.recording
        self.recorder = SessionRecorder(
            self.folder(), enabled=self.wanted(p), max_bytes=rp.max_mb << 20,
            rotate_on_stage=rp.rotate_on_stage, our_team=p.team.our_team)
        return self.recorder

    def configure(self, p: StationParams, version: int) -> None:
        rec = self.recorder
        if rec is None:
            return
        rec.max_bytes = p.recording.max_mb << 20
        rec.rotate_on_stage = p.recording.rotate_on_stage
        rec.our_team = p.team.our_team
        rec.set_enabled(self.wanted(p))
        values = p.model_dump(mode="json")
        changes = values if self._params_recorded is None else \
            diff(self._params_recorded, values)
        self._params_recorded = values
        if changes:
            rec.record(time.time_ns(), TYPE_TL_PARAMS, dumps(
                {"version": version, "changes": changes, "by": ""}, "params").encode())

    def operator_action(self, action: str, by: str = "",
                        details: dict[str, Any] | None = None) -> None:
        """Records an operator's action (target, e-stop, play, referee, teleport) in the
        session log, with who and when."""
        if self.recorder is not None:
            body = {"action": action, "by": by, "time_unix": time.time(), **(details or {})}
            self.recorder.record(time.time_ns(), TYPE_TL_ACTION,
                                 dumps(body, "action").encode())

    def command(self, action: str) -> contract.Recording:
        """The page's recording buttons: a new file now, or recording on/off (the parameter,
        persisted, so the next start does the same)."""
        if action == "new-file":
            if self.recorder is None or not self.recorder.status()["recording"]:
                raise ValueError("not recording: start recording first")
            self.recorder.new_file("operator")
        else:
            self.params.patch({"recording": {"enabled": action == "start"}})
        return self.status()

    def status(self) -> contract.Recording:
        if self.recorder is None:
            return {"enabled": False, "recording": False, "file": "",
                    "folder": str(self.folder()), "size_bytes": 0,
                    "duration_s": 0.0, "records": 0, "dropped": 0, "error": ""}
        s = self.recorder.status()
        return {"enabled": bool(s["enabled"]), "recording": bool(s["recording"]),
                "file": str(s["file"]), "folder": str(s["folder"]),
                "size_bytes": int(s["size_bytes"]), "duration_s": float(s["duration_s"]),
                "records": int(s["records"]), "dropped": int(s["dropped"]),
                "error": str(s["error"] or "")}


class RecordingProcessor(Processor):
    """What the recorder takes besides datagrams and commands: the station's health once a
    second, and the game stage (a new file per stage)."""

    name = "recording"

    def __init__(self, recording: RecordingControl, bus: DataBus,
                 replaying: Callable[[], bool], health: Callable[[], contract.Health]) -> None:
        super().__init__(Every(10.0))
        self.recording = recording
        self.referee = bus.of(topics.REFEREE)
        self.replaying = replaying
        self.health = health
        self._next_health = 0.0

    async def tick(self) -> None:
        rec = self.recording.recorder
        if rec is None or self.replaying():
            return
        ref = self.referee.latest_value()
        if ref is not None and ref.stage:
            rec.stage(ref.stage)
        now = time.monotonic()
        if now >= self._next_health:
            self._next_health = now + 1.0
            rec.record(time.time_ns(), TYPE_TL_HEALTH,
                       dumps(self.health(), "health").encode())
