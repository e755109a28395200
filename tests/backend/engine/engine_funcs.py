"""Functions the engine tests run in worker processes (importable by module path)."""

from __future__ import annotations

import os
import time

import numpy as np
from numpy.typing import NDArray


def add(a: float, b: float) -> float:
    return a + b


def scale(v: NDArray[np.float64], k: float = 2.0) -> NDArray[np.float64]:
    return v * k


def sleep_s(seconds: float) -> float:
    time.sleep(seconds)
    return seconds


def forever() -> None:
    while True:
        time.sleep(0.01)


def fail(message: str) -> None:
    raise ValueError(message)


def crash() -> None:
    os._exit(7)


def pid() -> int:
    return os.getpid()


def chatty() -> int:
    print("this goes to stderr, not into the protocol")
    os.write(1, b"raw bytes on fd 1\n")
    return 42


def unpicklable() -> object:
    return lambda: None


# keeper stand-ins with the goalkeeper function's signature, for the strategy fallback tests
def keeper_fail(*args: object) -> None:
    raise ValueError("boom")


def keeper_hang(*args: object) -> None:
    forever()


def keeper_crash(*args: object) -> None:
    crash()


def keeper_scalar(*args: object) -> float:
    return 1.0
