"""The compute engine (the paper's MATLAB Engine role): stateless named functions run in
worker processes and awaited without blocking the event loop.

- ``NumpyEngine``: Python functions from registered modules (the geometry library,
  strategy code); arguments and results pickled.
- ``OctaveEngine``: a team's .m scripts run unchanged by GNU Octave (``octave-cli``), one
  persistent interpreter per worker; ``file.function`` calls functions exported by a
  multi-function source file in the paper's style.

Both: ``await engine.call(name, *args, timeout_s=...)``, ``engine.health()`` for the
dashboard, ``async with engine:`` to start and close. Errors: ``EngineError`` (remote
exception, with traceback text), ``EngineTimeout``, ``EngineWorkerDied``, ``EngineClosed``.
"""

from .base import (
    EngineClosed,
    EngineError,
    EngineStats,
    EngineTimeout,
    EngineWorkerDied,
    PoolEngine,
)
from .numpy_engine import NumpyEngine
from .octave_engine import OctaveEngine, find_octave

__all__ = [
    "EngineClosed",
    "EngineError",
    "EngineStats",
    "EngineTimeout",
    "EngineWorkerDied",
    "NumpyEngine",
    "OctaveEngine",
    "PoolEngine",
    "find_octave",
]
