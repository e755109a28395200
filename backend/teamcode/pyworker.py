"""The station's end of a team-code worker process (``backend.teamcode.worker``): spawn it,
send requests, read replies in a task of its own (so an answer may come after the tick that
asked stopped waiting), say how much CPU time it has used (its limits are judged on that), and
say why it ended (a stuck call's stack from its dump file)."""

from __future__ import annotations

import asyncio
import contextlib
import json
import os
import pickle
import re
import signal
import struct
import sys
import tempfile
from collections.abc import Callable
from pathlib import Path
from typing import Any

from sslnet.proc import process_cpu_s

from ..engine._process import PROJECT_ROOT, worker_env

_FRAME = re.compile(r'^\s*File "(.+)", line (\d+) in (.+)$')


class _PlainUnpickler(pickle.Unpickler):
    """Replies are plain data (tuples, lists, dicts, str, numbers, None): anything that would
    import a class is refused (the worker runs the team's code; its replies are checked)."""

    def find_class(self, module: str, name: str) -> Any:
        raise pickle.UnpicklingError(f"not plain data: {module}.{name}")


def plain_loads(data: bytes) -> Any:
    import io

    return _PlainUnpickler(io.BytesIO(data)).load()


class WorkerGone(Exception):
    """The worker process ended: its exit status and what its dump file says."""

    def __init__(self, returncode: int | None, dump: str, reason: str = "") -> None:
        self.returncode = returncode
        self.dump = dump
        self.reason = reason
        super().__init__(reason or self.describe())

    def describe(self) -> str:
        rc = self.returncode
        if rc is None:
            return "the worker ended"
        if rc < 0:
            try:
                return f"the worker was killed by {signal.Signals(-rc).name}"
            except ValueError:
                return f"the worker was killed by signal {-rc}"
        if "Fatal Python error" in self.dump:
            first = next((ln for ln in self.dump.splitlines() if "Fatal Python error" in ln),
                         "")
            return f"the worker crashed ({first.strip()})"
        return f"the worker exited with status {rc}"

    def where(self, team_name: Callable[[str], str | None]) -> tuple[str | None, int | None,
                                                                    str]:
        """(team file, line, the stack as text) of the first stack in the dump inside the
        team folder (most recent call first), or (None, None, "")."""
        lines: list[str] = []
        found: tuple[str | None, int | None] = (None, None)
        for ln in self.dump.splitlines():
            m = _FRAME.match(ln)
            if m is None:
                if lines:
                    break  # the first thread's stack is the one that ran the call
                continue
            name = team_name(m.group(1))
            if name is not None:
                lines.append(f'  File "{name}", line {m.group(2)} in {m.group(3)}')
                if found == (None, None):
                    found = (name, int(m.group(2)))
            elif lines and not lines[-1].startswith("  ("):
                lines.append("  (called by the station's worker)")
        return found[0], found[1], "Stack (most recent call first):\n" + "\n".join(lines) \
            if lines else ""


class PyWorker:
    """One worker process. ``request`` sends a message and returns a future for its reply;
    the replies are read by the worker's own task. When the process ends, every pending
    future fails with ``WorkerGone`` and ``gone`` says why."""

    def __init__(self, team_dir: Path, memory_mb: int, start_timeout_s: float = 20.0) -> None:
        self.team_dir = team_dir
        self.memory_mb = memory_mb
        self.start_timeout_s = start_timeout_s
        self.proc: asyncio.subprocess.Process | None = None
        self.pid = 0
        self.seq = 0
        self.pending: dict[int, asyncio.Future[Any]] = {}
        self.gone: WorkerGone | None = None
        self.kill_reason = ""
        self._reader: asyncio.Task[None] | None = None
        shm = "/dev/shm" if os.path.isdir("/dev/shm") and os.access("/dev/shm", os.W_OK) \
            else None
        fd, self.dump_path = tempfile.mkstemp(prefix="touchline-team-", suffix=".dump",
                                              dir=shm)
        os.close(fd)
        #: called (on the loop) once the process has ended
        self.on_gone: Callable[[WorkerGone], None] | None = None

    @property
    def alive(self) -> bool:
        return self.proc is not None and self.gone is None

    async def start(self) -> None:
        config = json.dumps({"team_dir": str(self.team_dir), "memory_mb": self.memory_mb,
                             "dump": self.dump_path})
        env = worker_env({"PYTHONPATH": str(PROJECT_ROOT), "PYTHONDONTWRITEBYTECODE": "1"})
        self.proc = await asyncio.create_subprocess_exec(
            sys.executable, "-m", "backend.teamcode.worker", config,
            stdin=asyncio.subprocess.PIPE, stdout=asyncio.subprocess.PIPE, stderr=None,
            env=env, cwd=str(PROJECT_ROOT), start_new_session=True, limit=1 << 24)
        try:
            async with asyncio.timeout(self.start_timeout_s):
                first = await self._read_frame()
        except (TimeoutError, asyncio.IncompleteReadError, pickle.UnpicklingError) as exc:
            self.kill()
            await self.proc.wait()
            raise WorkerGone(self.proc.returncode, self._dump(),
                             f"the worker did not start ({type(exc).__name__})") from None
        if not (isinstance(first, tuple) and first[:1] == ("ready",)):
            self.kill()
            raise WorkerGone(None, "", f"the worker said {first!r} instead of ready")
        self.pid = int(first[1])
        self._reader = asyncio.get_running_loop().create_task(self._read_replies())

    async def _read_frame(self) -> Any:
        assert self.proc is not None and self.proc.stdout is not None
        head = await self.proc.stdout.readexactly(4)
        (n,) = struct.unpack(">I", head)
        return plain_loads(await self.proc.stdout.readexactly(n))

    async def _read_replies(self) -> None:
        assert self.proc is not None
        try:
            while True:
                reply = await self._read_frame()
                seq = reply[1] if isinstance(reply, tuple) and len(reply) > 1 else None
                fut = self.pending.pop(seq, None) if isinstance(seq, int) else None
                if fut is not None and not fut.done():
                    fut.set_result(reply)
        except (asyncio.IncompleteReadError, ConnectionError):
            pass
        except (pickle.UnpicklingError, ValueError, TypeError, EOFError, IndexError) as exc:
            self.kill_reason = self.kill_reason or f"the worker sent something unreadable: {exc}"
            self.kill()
        await self.proc.wait()
        gone = WorkerGone(self.proc.returncode, self._dump(), self.kill_reason)
        self.gone = gone
        for fut in self.pending.values():
            if not fut.done():
                fut.set_exception(gone)
                fut.exception()  # retrieved: nobody may be waiting for it any more
        self.pending.clear()
        if self.on_gone is not None:
            self.on_gone(gone)

    def _dump(self) -> str:
        try:
            with open(self.dump_path, errors="replace") as f:
                return f.read(64 * 1024)
        except OSError:
            return ""

    def request(self, *msg: Any) -> asyncio.Future[Any]:
        """Sends ``(msg[0], seq, *msg[1:])``; the future gets the reply (or WorkerGone)."""
        fut: asyncio.Future[Any] = asyncio.get_running_loop().create_future()
        if self.gone is not None or self.proc is None or self.proc.stdin is None:
            fut.set_exception(self.gone or WorkerGone(None, "", "the worker is not running"))
            fut.exception()
            return fut
        self.seq += 1
        data = pickle.dumps((msg[0], self.seq, *msg[1:]), protocol=pickle.HIGHEST_PROTOCOL)
        self.pending[self.seq] = fut
        try:
            self.proc.stdin.write(struct.pack(">I", len(data)) + data)
        except (ConnectionError, RuntimeError) as exc:
            self.pending.pop(self.seq, None)
            fut.set_exception(WorkerGone(self.proc.returncode, "", f"cannot write: {exc}"))
            fut.exception()
        return fut

    def cpu_s(self) -> float | None:
        """The process's CPU time so far (user + system, every thread; /proc), or None
        when it cannot be read (ended)."""
        if not self.alive or self.pid <= 0:
            return None
        try:
            return process_cpu_s(self.pid)
        except (OSError, ValueError, IndexError):
            return None

    def ask_stack(self) -> None:
        """Asks the worker to write its threads' stacks to the dump file (its faulthandler
        answers SIGUSR1 at C level, whatever the call is doing): where a call that does not
        answer is waiting."""
        if self.alive and self.pid > 0:
            with contextlib.suppress(ProcessLookupError, PermissionError):
                os.kill(self.pid, signal.SIGUSR1)

    def kill(self, reason: str = "") -> None:
        if reason and not self.kill_reason:
            self.kill_reason = reason
        if self.proc is not None and self.proc.returncode is None:
            with contextlib.suppress(ProcessLookupError):
                self.proc.kill()

    async def close(self) -> None:
        """Ends the process (closing its input; killed if it does not end at once)."""
        if self.proc is not None:
            if self.proc.stdin is not None:
                with contextlib.suppress(Exception):
                    self.proc.stdin.close()
            try:
                async with asyncio.timeout(1.0):
                    await self.proc.wait()
            except TimeoutError:
                self.kill()
                await self.proc.wait()
        if self._reader is not None:
            with contextlib.suppress(asyncio.CancelledError, Exception):
                await self._reader
        with contextlib.suppress(OSError):
            os.unlink(self.dump_path)
