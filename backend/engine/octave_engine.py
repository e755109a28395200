"""OctaveEngine: a team's existing .m scripts run unchanged by GNU Octave.

    engine = OctaveEngine("engine_scripts", workers=1)
    async with engine:
        target = await engine.call("goalkeeper", ball, vel, -4500.0, 1000.0)
        angle = await engine.call("geometry_src.get_angle", [1, 0], [0, 1])
        x, y = await engine.call("to_xy", p, nargout=2)

Each worker is one persistent ``octave-cli`` process running
``backend/engine/octave/touchline_engine_server.m`` with the scripts folder on its path.
Protocol: the engine writes the request (function name, nargout, arguments) to a file in a
private temporary folder (on /dev/shm when there is one), writes a line to Octave's stdin,
and reads Octave's stdout until a done marker; then it reads the response file. Values use
the binary format of ``mcodec`` (what converts to what is listed there). Anything a script
prints (``disp``, a missing semicolon) is kept as the call's printed output
(``last_output``), never confused with results.

Several functions in one file (the paper's section 3.1 workaround, without the header file):
``file.function`` calls ``function`` exported by ``file.m``, a *source file* whose main
function returns a cell array of handles to its own subfunctions (``{@get_angle, ...}``, the
paper's ``geometry_src.m`` as it is) or a struct of handles (``s.get_angle = @get_angle``).
The worker calls ``file()`` once, names each handle with ``func2str`` and keeps the table,
so the subfunctions stay private to their file: no global names, no header script. A file
is read once per worker: restart the engine (``await engine.restart_workers()``) after
editing scripts. Plain names (``goalkeeper``, ``sin``) are ordinary Octave functions.

``nargout`` (keyword, default 1) is how many outputs to ask for: 0 returns None, 1 the
value, more a tuple.
"""

from __future__ import annotations

import asyncio
import os
import re
import shutil
import tempfile
from pathlib import Path
from typing import Any

from . import mcodec
from ._process import ProcessWorker, worker_env
from .base import EngineError, PoolEngine, RemoteError, Worker

SERVER_DIR = Path(__file__).resolve().parent / "octave"
_NAME = re.compile(r"^[A-Za-z]\w*(\.[A-Za-z]\w*)?$")
_MARK = "\x1e"


def find_octave() -> str | None:
    """Path of ``octave-cli`` (or ``octave``), None when GNU Octave is not installed."""
    return shutil.which("octave-cli") or shutil.which("octave")


def _octave_str(s: str) -> str:
    return "'" + s.replace("'", "''") + "'"


class _OctaveWorker(ProcessWorker):
    def __init__(self, octave: str, paths: list[Path]) -> None:
        super().__init__()
        self.octave = octave
        self.paths = paths
        self.seq = 0
        self.tmp = ""
        self.last_output = ""

    async def start(self) -> None:
        shm = "/dev/shm" if os.path.isdir("/dev/shm") and os.access("/dev/shm", os.W_OK) else None
        self.tmp = tempfile.mkdtemp(prefix="touchline-octave-", dir=shm)
        req, resp = os.path.join(self.tmp, "req.bin"), os.path.join(self.tmp, "resp.bin")
        adds = "".join(f"addpath({_octave_str(str(p))});" for p in reversed(self.paths))
        script = f"{adds}touchline_engine_server({_octave_str(req)}, {_octave_str(resp)});"
        await self._spawn(self.octave, "--norc", "--no-history", "--quiet",
                          "--no-window-system", "--eval", script, env=worker_env(),
                          cwd=self.tmp)
        await self._read_until(f"{_MARK}TOUCHLINE_READY")

    async def _read_until(self, marker: str) -> str:
        _, reader = self._pipes()
        printed: list[str] = []
        while True:
            raw = await reader.readline()
            if not raw:
                if self.proc is not None:
                    await self.proc.wait()
                raise self._died("octave closed its output")
            line = raw.decode("utf-8", errors="replace").rstrip("\n")
            if line == marker:
                return "\n".join(printed)
            printed.append(line)

    async def request(self, name: str, args: tuple[Any, ...], kwargs: dict[str, Any]) -> Any:
        nargout = int(kwargs.pop("nargout", 1))
        if kwargs:
            raise RemoteError(f"unexpected keyword arguments {sorted(kwargs)}", "")
        writer, _ = self._pipes()
        self.seq += 1
        path = os.path.join(self.tmp, "req.bin")
        with open(path, "wb") as f:
            f.write(mcodec.encode([name, float(nargout), list(args)]))
        try:
            writer.write(f"{self.seq % 10_000_000:07d}\n".encode())  # 8 bytes exactly
            await writer.drain()
        except (ConnectionError, BrokenPipeError) as exc:
            raise self._died("octave closed its input") from exc
        printed = await self._read_until(f"{_MARK}TOUCHLINE_DONE {self.seq % 10_000_000:07d}")
        # the server prints a newline before the marker so unterminated output ends there
        self.last_output = printed[:-1] if printed.endswith("\n") or printed == "" else printed
        with open(os.path.join(self.tmp, "resp.bin"), "rb") as f:
            data = f.read()
        if not data:
            raise RemoteError("empty response from octave", "")
        values = mcodec.decode_many(data[1:])
        if data[0] != 0:
            message = str(values[0]) if values else "octave error"
            tb = str(values[1]) if len(values) > 1 else ""
            raise RemoteError(message, tb)
        out = values[0] if values else []
        if nargout == 0:
            return None
        if nargout == 1:
            return out[0]
        return tuple(out)

    async def wait_closed(self) -> None:
        await super().wait_closed()
        if self.tmp:
            shutil.rmtree(self.tmp, ignore_errors=True)


class OctaveEngine(PoolEngine):
    """.m functions from ``scripts_dir`` (and ``extra_paths``) in ``workers`` octave-cli
    processes. Raises EngineError on start when Octave is not installed."""

    kind = "octave"

    def __init__(self, scripts_dir: str | os.PathLike[str], *,
                 extra_paths: list[str | os.PathLike[str]] | None = None, workers: int = 1,
                 default_timeout_s: float = 2.0, start_timeout_s: float = 30.0,
                 octave: str | None = None) -> None:
        super().__init__(workers, default_timeout_s, start_timeout_s)
        self.scripts_dir = Path(scripts_dir).resolve()
        if not self.scripts_dir.is_dir():
            raise ValueError(f"scripts folder {self.scripts_dir} does not exist")
        self.paths = [self.scripts_dir, *(Path(p).resolve() for p in extra_paths or []),
                      SERVER_DIR]
        self.octave = octave or find_octave() or "octave-cli"

    def _new_worker(self) -> Worker:
        return _OctaveWorker(self.octave, self.paths)

    async def start(self) -> None:
        if shutil.which(self.octave) is None:
            raise EngineError(f"GNU Octave not found ({self.octave}); install Debian's "
                              "'octave' package")
        await super().start()

    async def call(self, name: str, *args: Any, timeout_s: float | None = None,
                   **kwargs: Any) -> Any:
        """Call .m function ``name`` (``file`` or ``file.function``); ``nargout=`` keyword."""
        if not _NAME.match(name):
            raise ValueError(f"not an Octave function name: {name!r}")
        mcodec.encode(list(args))  # TypeError for unsupported arguments, before any worker
        return await super().call(name, *args, timeout_s=timeout_s, **kwargs)

    async def restart_workers(self) -> None:
        """Replace every idle worker (e.g. to pick up edited scripts)."""
        idle: list[Worker] = []
        while not self._idle.empty():
            idle.append(self._idle.get_nowait())
        for w in idle:
            self._replace(w)
            self.stats.restarts -= 1  # a planned restart is not a failure
        await asyncio.sleep(0)
