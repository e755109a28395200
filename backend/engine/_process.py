"""A worker as an asyncio subprocess with pipes (shared by the numpy and Octave workers)."""

from __future__ import annotations

import asyncio
import contextlib
import os
from pathlib import Path

from .base import Worker, WorkerDied

#: the repository root, put on the numpy worker's PYTHONPATH
PROJECT_ROOT = Path(__file__).resolve().parents[2]


def worker_env(extra: dict[str, str] | None = None) -> dict[str, str]:
    """The parent's environment with single-threaded BLAS (one worker per core is the plan)."""
    env = dict(os.environ)
    for var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
        env[var] = "1"
    if extra:
        env.update(extra)
    return env


class ProcessWorker(Worker):
    """Owns ``self.proc``; subclasses implement the protocol."""

    def __init__(self) -> None:
        self.proc: asyncio.subprocess.Process | None = None

    async def _spawn(self, *argv: str, env: dict[str, str], cwd: str | None = None) -> None:
        self.proc = await asyncio.create_subprocess_exec(
            *argv, stdin=asyncio.subprocess.PIPE, stdout=asyncio.subprocess.PIPE,
            stderr=None, env=env, cwd=cwd, start_new_session=True,
            limit=1 << 24)

    def _pipes(self) -> tuple[asyncio.StreamWriter, asyncio.StreamReader]:
        if self.proc is None or self.proc.stdin is None or self.proc.stdout is None:
            raise WorkerDied("worker not started")
        return self.proc.stdin, self.proc.stdout

    def _died(self, what: str) -> WorkerDied:
        rc = self.proc.returncode if self.proc is not None else None
        return WorkerDied(f"{what}; exit status {rc}" if rc is not None else what)

    def kill(self) -> None:
        if self.proc is not None and self.proc.returncode is None:
            with contextlib.suppress(ProcessLookupError):
                self.proc.kill()

    async def wait_closed(self) -> None:
        if self.proc is None:
            return
        if self.proc.stdin is not None:
            # closed, not waited for: its close waiter is one future shared by every caller,
            # and a caller cancelled while awaiting it (a worker's reaper, stopped by the
            # engine's close) cancels it for the next one, which then never got to wait()
            # for the process (left running past its event loop)
            self.proc.stdin.close()
        await self.proc.wait()
