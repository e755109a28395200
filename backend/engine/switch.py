"""The strategy's compute engine, started and replaced in the background: the strategy uses it
once it runs and falls back to the built-in code meanwhile."""

from __future__ import annotations

import asyncio
import contextlib
import logging
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING

from ..params.model import StrategyParams
from .base import PoolEngine
from .numpy_engine import NumpyEngine
from .octave_engine import OctaveEngine

if TYPE_CHECKING:
    from ..processors import StrategyProcessor

log = logging.getLogger("touchline.station")


class EngineSwitch:
    """Follows ``strategy.engine``: a change closes the old engine and starts the new one;
    ``error`` says why one did not start. The Octave engine runs the .m files of
    ``scripts_dir``, set when the station starts (--scripts-dir), never by a parameter."""

    def __init__(self, strategy: StrategyProcessor, scripts_dir: Path) -> None:
        self.strategy = strategy
        self.scripts_dir = scripts_dir
        self.error = ""
        self._key: str | None = None
        self._gen = 0
        self._tasks: set[asyncio.Task[None]] = set()
        #: called when an engine has started (the station's start timeline)
        self.started: Callable[[], None] = lambda: None

    def configure(self, sp: StrategyParams) -> None:
        key = sp.engine
        if key == self._key:
            return
        self._key = key
        self._gen += 1
        old = self.strategy.engine
        self.strategy.drop_engine()
        self.error = ""
        task = asyncio.get_running_loop().create_task(self._swap(old, sp, self._gen))
        self._tasks.add(task)
        task.add_done_callback(self._tasks.discard)

    async def _swap(self, old: PoolEngine | None, sp: StrategyParams, gen: int) -> None:
        if old is not None:
            await old.close()
        if sp.engine == "off":
            return
        eng: PoolEngine
        if sp.engine == "numpy":
            # the keeper's rule under the same name as the shipped .m example
            eng = NumpyEngine(functions={"goalkeeper": "backend.geometry.fit:goalkeeper_target"},
                              preload=["backend.geometry.fit"], workers=1,
                              default_timeout_s=sp.engine_timeout_s)
        else:
            eng = OctaveEngine(str(self.scripts_dir), workers=1,
                               default_timeout_s=sp.engine_timeout_s)
        try:
            await eng.start()
        except Exception as exc:
            self.error = f"{sp.engine} engine did not start: {exc}"
            log.error("%s", self.error)
            await eng.close()
            return
        if gen != self._gen:  # configured again meanwhile
            await eng.close()
            return
        self.strategy.engine = eng
        self.started()
        log.info("compute engine %s started for the goalkeeper (%s)", sp.engine,
                 sp.goalkeeper_function)

    async def close(self) -> None:
        for task in list(self._tasks):
            task.cancel()
            with contextlib.suppress(asyncio.CancelledError, Exception):
                await task
        eng = self.strategy.engine
        self.strategy.drop_engine()
        if eng is not None:
            await eng.close()
