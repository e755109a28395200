"""The NumpyEngine's worker process: ``python -m backend.engine._numpy_worker CONFIG_JSON``.

Protocol on stdin/stdout: frames of a 4-byte big-endian length and a pickle. The first frame
out is ``("ready", pid)``; then for each request ``(name, args, kwargs)`` one response
``("ok", result)`` or ``("err", message, traceback_text)``. The function's own prints go to
stderr: fd 1 is pointed there so nothing can corrupt the protocol.
"""

from __future__ import annotations

import importlib
import json
import os
import pickle
import sys
import traceback
from collections.abc import Callable
from typing import Any, BinaryIO

from ..workerpipe import read_frame, send, take_stdio


def _send(out: BinaryIO, obj: Any) -> None:
    try:
        send(out, obj)
    except Exception as exc:  # an unpicklable result becomes an error of that call
        send(out, ("err", f"result not picklable: {exc!r}", traceback.format_exc()))


class Resolver:
    def __init__(self, modules: dict[str, str], functions: dict[str, str]) -> None:
        self.modules = modules
        self.functions = functions
        self.cache: dict[str, Callable[..., Any]] = {}

    def __call__(self, name: str) -> Callable[..., Any]:
        cached = self.cache.get(name)
        if cached is not None:
            return cached
        if name in self.functions:
            mod_name, _, attr = self.functions[name].partition(":")
        else:
            prefix, _, attr = name.rpartition(".")
            if prefix not in self.modules:
                raise LookupError(f"unknown function {name!r}: no module registered as "
                                  f"{prefix!r} (registered: {sorted(self.modules)})")
            mod_name = self.modules[prefix]
        if not attr or attr.startswith("_"):
            raise LookupError(f"function {name!r} is not public")
        obj: Any = getattr(importlib.import_module(mod_name), attr, None)
        if not callable(obj):
            raise LookupError(f"{mod_name} has no function {attr!r}")
        fn: Callable[..., Any] = obj
        self.cache[name] = fn
        return fn


def main() -> None:
    config = json.loads(sys.argv[1])
    proto_in, proto_out = take_stdio()
    resolve = Resolver(config["modules"], config["functions"])
    for mod in config.get("preload", []):
        importlib.import_module(mod)
    _send(proto_out, ("ready", os.getpid()))
    while True:
        body = read_frame(proto_in)
        if body is None:
            return
        try:
            name, args, kwargs = pickle.loads(body)
            result = resolve(name)(*args, **kwargs)
            reply: Any = ("ok", result)
        except Exception as exc:
            reply = ("err", f"{type(exc).__name__}: {exc}", traceback.format_exc())
        _send(proto_out, reply)


if __name__ == "__main__":
    main()
