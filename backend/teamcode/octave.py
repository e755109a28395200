"""The team's Octave (MATLAB-style) plays: ``team/<name>.m`` run by the compute engine's
OctaveEngine, one worker per play in use, the paper's way: matrices in, a matrix out (the
layouts of ``touchline.octave``).

    orders = name(ours, theirs, ball, game)

The Octave path is the team folder and its ``lib/``; several functions in one file work as
in any Octave function file (local functions after the main one). A save of the play or of
any ``.m`` file restarts its worker: a clean workspace (``persistent`` variables start
afresh), the paper's complaint about MATLAB's cleared workspace solved; the file is read
and parsed when the worker starts (a parse error is a load error, with its line). The budget
is the engine's timeout (``strategy.engine_timeout_s``): a call that takes longer is
stopped (its worker restarted, its robots stopped meanwhile); three in a row and the play
fails until its next save, as a Python play over its CPU budget.
"""

from __future__ import annotations

import asyncio
import math
import re
import time
from pathlib import Path
from typing import Any

import numpy as np

from touchline import Game
from touchline.octave import BALL_COLUMNS, ORDER_COLUMNS, OURS_COLUMNS, THEIRS_COLUMNS

from ..engine import EngineError, EngineTimeout, EngineWorkerDied, OctaveEngine
from .discovery import Found
from .runner import LOAD_LIMIT_S, OVER_BUDGET_IN_A_ROW, Pending, Runner
from .state import ErrorInfo, ErrorKind, FileRun

#: "at name (FILE, line N)" in the engine's traceback text
_AT = re.compile(r"at (\S+) \((.+), line (\d+)\)")
_PARSE = re.compile(r"parse error near line (\d+) of file (\S+)")
_NAN = math.nan


def _bool(v: bool | None) -> float:
    return _NAN if v is None else 1.0 if v else 0.0


def octave_args(game: Game) -> tuple[Any, Any, Any, dict[str, Any]]:
    """(ours, theirs, ball, game) as the play gets them (``touchline.octave``)."""
    mine = set(game.mine)
    ours = np.array([[r.id, r.x, r.y, r.orientation, r.vx, r.vy, r.omega, float(r.visible),
                      1.0 if r.id in mine else 0.0, _bool(r.ball_contact)]
                     for r in game.ours], dtype=np.float64).reshape(-1, len(OURS_COLUMNS))
    theirs = np.array([[r.id, r.x, r.y, r.orientation, r.vx, r.vy, r.omega, float(r.visible)]
                       for r in game.theirs],
                      dtype=np.float64).reshape(-1, len(THEIRS_COLUMNS))
    b = game.ball
    ball = np.zeros((0, len(BALL_COLUMNS))) if b is None else \
        np.array([[b.x, b.y, b.z, b.vx, b.vy, float(b.visible)]], dtype=np.float64)
    ref = game.referee
    f = game.field
    topics = {name: {k: float(v) for k, v in values.items() if k.isidentifier()}
              for name, values in game.topics.items() if name.isidentifier()}
    struct: dict[str, Any] = {
        "version": float(game.version), "t": game.t, "our_team": game.our_team,
        "our_side": game.our_side, "command": ref.command, "situation": ref.situation,
        "ours": _bool(ref.ours),
        "designated": None if ref.designated is None else np.array([ref.designated]),
        "goalkeeper": _NAN if ref.goalkeeper is None else float(ref.goalkeeper),
        "field": {"length": f.length, "width": f.width, "goal_width": f.goal_width,
                  "goal_depth": f.goal_depth, "boundary_width": f.boundary_width,
                  "penalty_area_depth": f.penalty_area_depth,
                  "penalty_area_width": f.penalty_area_width,
                  "center_circle_radius": f.center_circle_radius,
                  "robot_radius": f.robot_radius, "ball_radius": f.ball_radius},
        "topics": topics, "replay": 1.0 if game.replay else 0.0,
    }
    return ours, theirs, ball, struct


class OctaveOutputError(ValueError):
    pass


def plain_matrix_orders(result: Any) -> list[tuple[Any, ...]]:
    """An orders matrix (one row a robot: ``ORDER_COLUMNS``) as the plain tuples of
    ``worker.plain_orders`` (checked again by ``orders.validate_orders``)."""
    if result is None or (isinstance(result, list) and not result):
        return []
    try:
        m = np.asarray(result, dtype=np.float64)
    except (TypeError, ValueError):
        raise OctaveOutputError(f"the play returned {type(result).__name__}: expected a "
                                f"matrix of {len(ORDER_COLUMNS)} columns ("
                                f"{' '.join(ORDER_COLUMNS)})") from None
    if m.size == 0:
        return []
    if m.ndim == 0 or (m.ndim == 2 and m.shape[1] != len(ORDER_COLUMNS)) or m.ndim > 2:
        raise OctaveOutputError(f"the orders matrix is {'x'.join(map(str, m.shape)) or '1x1'}"
                                f": it needs {len(ORDER_COLUMNS)} columns ("
                                f"{' '.join(ORDER_COLUMNS)}), one row a robot")
    if m.ndim == 1:
        m = m.reshape(1, -1)
        if m.shape[1] != len(ORDER_COLUMNS):
            raise OctaveOutputError(f"the orders row has {m.shape[1]} columns: it needs "
                                    f"{len(ORDER_COLUMNS)} ({' '.join(ORDER_COLUMNS)})")
    out: list[tuple[Any, ...]] = []
    for k, row in enumerate(m.tolist(), start=1):
        rid, mode, x, y, ori, vmax, kick, chip, dribble = row
        if not math.isfinite(rid) or rid != int(rid):
            raise OctaveOutputError(f"row {k}: the robot id is {rid!r}, not a whole number")
        rid = int(rid)
        if mode == 0:
            out.append(("T", rid, x, y, None if math.isnan(ori) else ori,
                        None if math.isnan(vmax) or vmax == 0.0 else vmax, kick,
                        chip != 0.0, dribble != 0.0, True, ""))
        elif mode == 1:
            out.append(("V", rid, x, y, ori, kick, chip != 0.0, dribble != 0.0, ""))
        else:
            raise OctaveOutputError(f"row {k} (robot {rid}): mode is {mode!r}: 0 drives to "
                                    "(x, y), 1 is a velocity")
    return out


def octave_error(exc: EngineError, name: str, team_dir: Path) -> ErrorInfo:
    """An Octave error with the team file and line it names."""
    text = exc.remote_traceback or str(exc)
    root = team_dir.resolve()

    def team_name(path: str) -> str | None:
        try:
            return Path(path).resolve().relative_to(root).as_posix()
        except (ValueError, OSError):
            return None
    m = _PARSE.search(text)
    if m is not None:
        return ErrorInfo("import", "parse error (syntax error)",
                         team_name(m.group(2)) or name, int(m.group(1)),
                         text.replace(str(root) + "/", ""))
    file, line = name, None
    for _function, path, ln in _AT.findall(text):
        t = team_name(path)
        if t is not None:
            file, line = t, int(ln)
            break
    first = text.splitlines()[0] if text else str(exc)
    return ErrorInfo("exception", first.removeprefix("error: "), file, line,
                     text.replace(str(root) + "/", ""))


class OctaveRunner(Runner):
    """An Octave play in an OctaveEngine of its own (one worker)."""

    language = "octave"

    def __init__(self, found: Found, run: FileRun, team_dir: Path,
                 timeout_s: float = 0.2) -> None:
        super().__init__(found, run)
        self.team_dir = team_dir
        self.timeout_s = timeout_s
        self.engine: OctaveEngine | None = None
        self._task: asyncio.Task[None] | None = None
        self._want = 0
        self._done = 0
        self._calls: set[asyncio.Task[Any]] = set()

    @property
    def function(self) -> str:
        return self.found.stem

    def ensure(self) -> None:
        if self.closed or self.failed or self._task is not None or self.engine is not None:
            return
        self._restart_soon()

    def update(self, found: Found) -> None:
        """The play or an .m library changed: a new worker (a clean workspace)."""
        self.found = found
        if found.error is not None:
            self.fail(ErrorInfo(found.error.kind, found.error.message, found.name,
                                found.error.line))
            return
        if self.run.state == "error":
            self.run.error = None
        self.run.state = "starting"
        self._restart_soon()

    def _restart_soon(self) -> None:
        if self.run.state != "running":
            self.run.state = "starting"
        self._start_soon(self._restart)

    async def _restart(self) -> None:
        old, self.engine = self.engine, None
        self.inflight = None
        if old is not None:
            await old.close()
        self.run.state = "starting"
        lib = self.team_dir / "lib"
        try:
            eng = OctaveEngine(self.team_dir, extra_paths=[lib] if lib.is_dir() else [],
                               workers=1, default_timeout_s=self.timeout_s)
            await eng.start()
        except (EngineError, ValueError) as exc:
            self.fail(ErrorInfo("crash", f"the Octave worker did not start: {exc}",
                                self.name))
            return
        if self.closed or self._done < self._want:
            await eng.close()
            return
        # the play's file read and parsed now (Octave does it at the first call, which then
        # takes longer than a tick may; a parse error is a load error, with its line)
        try:
            await eng.call("nargin", self.function, timeout_s=LOAD_LIMIT_S)
        except EngineError as exc:
            await eng.close()
            if not isinstance(exc, EngineTimeout):
                err = octave_error(exc, self.name, self.team_dir)
                kind: ErrorKind = "import" if err.kind in ("import", "exception") else "crash"
                self.fail(ErrorInfo(kind, err.message, err.file, err.line, err.traceback))
            else:
                self.fail(ErrorInfo("import", f"stuck: not read within {LOAD_LIMIT_S:g} s",
                                    self.name))
            return
        if self.closed or self._done < self._want:
            await eng.close()
            return
        self.engine = eng
        self.run.loaded_version = self.found.version
        self.run.reloaded_at_unix = time.time()
        self.run.reloads += 1
        self.fresh = True
        if not self.failed:  # (a save that does not parse may have come meanwhile)
            self.run.state = "running"

    def send(self, game: Any, inputs: Any, budget_s: float,
             now: float | None = None) -> Pending | None:
        """One call of the play (``budget_s``: not used, the engine's timeout is Octave's)."""
        now = time.monotonic() if now is None else now
        eng = self.engine
        if self.closed or self.run.state != "running" or eng is None:
            return None
        if self.inflight is not None or eng.health()["idle"] == 0:
            return None  # its worker is busy, or being restarted after a timeout
        args = octave_args(game)
        version = self.found.version
        timeout = self.timeout_s

        async def call() -> Any:
            t0 = time.perf_counter()
            try:
                res = await eng.call(self.function, *args, timeout_s=timeout)
            except EngineTimeout:
                return ("timeout", 0, time.perf_counter() - t0)
            except EngineWorkerDied as exc:
                return ("error", 0, {"kind": "crash", "message": str(exc).splitlines()[0],
                                     "file": self.name, "line": None, "traceback": ""},
                        time.perf_counter() - t0)
            except EngineError as exc:
                e = octave_error(exc, self.name, self.team_dir)
                return ("error", 0, {"kind": e.kind, "message": e.message, "file": e.file,
                                     "line": e.line, "traceback": e.traceback},
                        time.perf_counter() - t0)
            wall = time.perf_counter() - t0
            try:
                plain = plain_matrix_orders(res)
            except OctaveOutputError as exc:
                return ("error", 0, {"kind": "output", "message": str(exc), "file": self.name,
                                     "line": None, "traceback": ""}, wall)
            return ("out", 0, plain, wall, version)

        task = asyncio.get_running_loop().create_task(call())
        p = self._warmup(Pending(task, now, timeout))
        self.inflight = p
        self._calls.add(task)
        task.add_done_callback(lambda t: self._replied(p, t))
        return p

    def _replied(self, p: Pending, t: asyncio.Task[Any]) -> None:
        self._calls.discard(t)
        if t.cancelled():
            p.done = True
            p.reason = "cancelled"
            if self.inflight is p:
                self.inflight = None
            return
        reply = t.result()
        if reply[0] == "timeout":
            # over its budget: the engine restarted the worker; like a Python play's CPU
            # budget, three in a row and the play fails until its next save
            p.done = True
            if self.inflight is p:
                self.inflight = None
            self.run.overruns += 1
            self.over_in_a_row += 1
            p.reason = f"over its budget (strategy.engine_timeout_s = {self.timeout_s:g} s)"
            if self.over_in_a_row >= OVER_BUDGET_IN_A_ROW:
                self.fail(ErrorInfo("budget", (
                    f"did not return within strategy.engine_timeout_s = {self.timeout_s:g} s "
                    f"{self.over_in_a_row} ticks in a row (its Octave worker was restarted "
                    "each time)"), self.name))
            return
        self.accept(p, reply)

    async def close(self) -> None:
        await self._close_start()
        for t in list(self._calls):
            t.cancel()
        eng, self.engine = self.engine, None
        if eng is not None:
            await eng.close()
        if self.run.state in ("running", "starting"):
            self.run.state = "idle"

