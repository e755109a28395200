"""NumpyEngine: Python functions, registered by name, run in worker processes.

    engine = NumpyEngine({"geometry": "backend.geometry"}, workers=2)
    async with engine:
        d = await engine.call("geometry.distance", a, b, timeout_s=0.05)

A name ``prefix.function`` resolves to ``function`` of the module registered as ``prefix``
(public names only); ``functions={"gk": "backend.strategy.keeper:target"}`` registers single
functions under any name. Functions must be importable in the worker (module-level, in the
repository or installed); arguments and results travel as pickles, so numpy arrays, numbers,
tuples, dicts and dataclasses work, lambdas and open files do not. Functions should be
stateless: a call may run in any worker, and workers are replaced after a crash or timeout.
"""

from __future__ import annotations

import json
import pickle
import struct
import sys
from collections.abc import Mapping, Sequence
from typing import Any

from ._process import PROJECT_ROOT, ProcessWorker, worker_env
from .base import PoolEngine, RemoteError, Worker, WorkerDied

DEFAULT_MODULES: dict[str, str] = {"geometry": "backend.geometry"}


class _NumpyWorker(ProcessWorker):
    def __init__(self, config: str) -> None:
        super().__init__()
        self.config = config

    async def start(self) -> None:
        pythonpath = str(PROJECT_ROOT)
        env = worker_env()
        if env.get("PYTHONPATH"):
            pythonpath += ":" + env["PYTHONPATH"]
        env["PYTHONPATH"] = pythonpath
        await self._spawn(sys.executable, "-m", "backend.engine._numpy_worker", self.config,
                          env=env, cwd=str(PROJECT_ROOT))
        reply = await self._recv()
        if not (isinstance(reply, tuple) and reply and reply[0] == "ready"):
            raise WorkerDied(f"unexpected first message {reply!r}")

    async def _recv(self) -> Any:
        _, reader = self._pipes()
        try:
            head = await reader.readexactly(4)
            (n,) = struct.unpack(">I", head)
            body = await reader.readexactly(n)
        except (EOFError, ConnectionError) as exc:  # IncompleteReadError is an EOFError
            if self.proc is not None:
                await self.proc.wait()
            raise self._died("worker closed its output") from exc
        return pickle.loads(body)

    async def request(self, name: str, args: tuple[Any, ...], kwargs: dict[str, Any]) -> Any:
        writer, _ = self._pipes()
        data = pickle.dumps((name, args, kwargs), protocol=pickle.HIGHEST_PROTOCOL)
        try:
            writer.write(struct.pack(">I", len(data)) + data)
            await writer.drain()
        except (ConnectionError, BrokenPipeError) as exc:
            raise self._died("worker closed its input") from exc
        reply = await self._recv()
        if reply[0] == "ok":
            return reply[1]
        raise RemoteError(reply[1], reply[2])


class NumpyEngine(PoolEngine):
    """Python/numpy functions in ``workers`` processes (default 1; 2 on a 2-core machine
    leaves no core for the event loop under load)."""

    kind = "numpy"

    def __init__(self, modules: Mapping[str, str] | None = None, *,
                 functions: Mapping[str, str] | None = None, preload: Sequence[str] = (),
                 workers: int = 1, default_timeout_s: float = 1.0,
                 start_timeout_s: float = 30.0) -> None:
        super().__init__(workers, default_timeout_s, start_timeout_s)
        mods = dict(DEFAULT_MODULES if modules is None else modules)
        self._config = json.dumps({"modules": mods, "functions": dict(functions or {}),
                                   "preload": list(preload) or sorted(set(mods.values()))})

    def _new_worker(self) -> Worker:
        return _NumpyWorker(self._config)
