"""A team file's worker process: ``python -m backend.teamcode.worker CONFIG_JSON``.

It runs ONE play or processor of the team folder, never in the station's process: a
``while True:``, a crash or a memory hog in team code stalls nothing of the station's.

Protocol on stdin/stdout, as the compute engine's (``backend.engine._numpy_worker``): frames
of a 4-byte big-endian length and a pickle. The first frame out is ``("ready", pid)``; then
each request carries a sequence number its reply repeats:

* ``("load", seq, name, kind, entry, cpu_s)`` -> ``("loaded", seq, version, info)`` (a
  processor's ``rate_hz``, ``trigger``, ``max_hz``, ``reads``; {} for a play) or
  ``("error", seq, error, 0.0)``: imports the file (again: a reload drops every module of the
  team folder and imports it anew, keeping numpy and touchline loaded; a class play or
  processor that defines ``keep()``/``restore()`` carries its state across).
* ``("tick", seq, game, inputs, cpu_s)`` -> ``("out", seq, output, cpu_s, version)`` or
  ``("error", seq, error, cpu_s)``: one call of ``play(game)``, ``Play().tick(game)`` or the
  processor's ``tick(game, inputs)``. ``cpu_s`` is this thread's CPU time for the call (the
  budget is judged on it: a busy machine does not make a play late), with the garbage
  collector off during the call and a young-generation collection after the reply.
  ``output``: plain data (``plain_orders``, ``plain_outputs``); the station checks it again.

The request's ``cpu_s`` is the call's CPU limit: this process's CPU time (``ITIMER_PROF``),
not the wall clock, so a loaded machine that does not schedule the worker never counts
against the play. Past it the call is spinning: ``SIGPROF`` raises ``CpuLimitExceeded``
where the team code is (the error names that line; a ``BaseException``, so a play's
``except Exception`` does not swallow it), and faulthandler writes every thread's stack to
the dump file named in the config first (the line, should the raise never come: a long C
call). The station watches the worker's CPU time from outside too and ends it if it goes
on (``runner.PythonRunner``), and asks for a stack (``SIGUSR1``) before ending one that gives
no answer for far longer in wall time. The address space is limited (RLIMIT_AS,
``memory_mb``); team code's prints go to stderr (the station's log): fd 1 is pointed there
so nothing can corrupt the protocol.
"""

from __future__ import annotations

import faulthandler
import gc
import hashlib
import json
import operator
import os
import pickle
import resource
import signal
import sys
import time
import traceback
import types
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from touchline import Target, Velocity

from ..workerpipe import read_frame, send, take_stdio

#: a reply that is not an order: ("?", what it is), for the station's message
Plain = tuple[Any, ...]


class OutputError(Exception):
    """The team code returned something that is not what the interface asks."""


class CpuLimitExceeded(BaseException):
    """One call of team code used its CPU limit (raised by ``SIGPROF``). A BaseException, as
    KeyboardInterrupt: a play's ``except Exception`` does not swallow it."""


class CpuLimit:
    """The CPU-time limit of one call: ``ITIMER_PROF`` (this process's CPU time, user and
    system, every thread) armed around it; its ``SIGPROF`` raises ``CpuLimitExceeded`` in the
    call. One shot: at most one raise per call, and none once the call is over."""

    def __init__(self) -> None:
        self.armed = False
        self.limit_s = 0.0
        #: the limit was reached in the latest call (its stacks are in the dump file)
        self.fired = False
        signal.signal(signal.SIGPROF, self._expired)

    def _expired(self, _signum: int, _frame: Any) -> None:
        # a signal that came as the call ended runs its Python handler a few bytecodes
        # later: not armed any more, nothing to stop
        if self.armed:
            self.armed, self.fired = False, True
            raise CpuLimitExceeded(f"over its CPU limit ({self.limit_s:g} s of CPU time)")

    def call(self, limit_s: float, fn: Any, *args: Any) -> Any:
        """``fn(*args)`` under the limit (raises CpuLimitExceeded past it; the raise may come
        from this function's own last lines, still for this call)."""
        self.limit_s = limit_s
        self.armed, self.fired = True, False
        signal.setitimer(signal.ITIMER_PROF, max(limit_s, 1e-3))
        try:
            return fn(*args)
        finally:
            self.armed = False  # before the timer stops: a late handler does nothing
            signal.setitimer(signal.ITIMER_PROF, 0.0)


def _describe(v: Any) -> str:
    r = repr(v)
    return f"{type(v).__name__} {r[:60]}{'...' if len(r) > 60 else ''}"


def _num(v: Any, what: str) -> float:
    if isinstance(v, bool) or not isinstance(v, int | float):
        try:  # numpy scalars and the like: anything float() takes without a string
            if isinstance(v, str | bytes):
                raise TypeError
            return float(v)
        except (TypeError, ValueError):
            raise OutputError(f"{what} is {_describe(v)}, not a number") from None
    return float(v)


def _opt_num(v: Any, what: str) -> float | None:
    return None if v is None else _num(v, what)


def _not_a_dict_hint(result: Any) -> str:
    """The usual slips behind an answer that is not a dict, said where the error is shown."""
    if result is None:
        return " (no return statement reached?)"
    if isinstance(result, Target | Velocity):
        return " (one order: say for which robot, {robot id: order})"
    return ""


def plain_orders(result: Any) -> list[Plain]:
    """A play's answer as plain tuples (the station checks values, ids and limits):
    ``("T", id, x, y, orientation|None, max_speed|None, kick, chip, dribble, avoid, role)``
    or ``("V", id, forward, left, turn, kick, chip, dribble, role)``."""
    if not isinstance(result, Mapping):
        raise OutputError(f"the play returned {_describe(result)}{_not_a_dict_hint(result)}: "
                          "expected a dict {robot id: Target or Velocity}")
    out: list[Plain] = []
    for rid, order in result.items():
        try:  # an int, or an integer numpy scalar (never a bool, a float, a string)
            if isinstance(rid, bool):
                raise TypeError
            rid = operator.index(rid)
        except TypeError:
            raise OutputError(f"a key of the play's dict is {_describe(rid)}: expected a "
                              "robot id (int)") from None
        what = f"robot {rid}'s order"
        if isinstance(order, Target):
            out.append(("T", rid, _num(order.x, f"{what} x"), _num(order.y, f"{what} y"),
                        _opt_num(order.orientation, f"{what} orientation"),
                        _opt_num(order.max_speed_mps, f"{what} max_speed_mps"),
                        _num(order.kick_mps, f"{what} kick_mps"), bool(order.chip),
                        bool(order.dribble), bool(order.avoid), str(order.role)[:40]))
        elif isinstance(order, Velocity):
            out.append(("V", rid, _num(order.forward_mps, f"{what} forward_mps"),
                        _num(order.left_mps, f"{what} left_mps"),
                        _num(order.turn_radps, f"{what} turn_radps"),
                        _num(order.kick_mps, f"{what} kick_mps"), bool(order.chip),
                        bool(order.dribble), str(order.role)[:40]))
        else:
            raise OutputError(f"{what} is {_describe(order)}: expected a touchline Target or "
                              "Velocity")
    return out


def plain_outputs(result: Any) -> dict[str, float]:
    """A processor's answer as {name: float} (booleans as 0/1)."""
    if not isinstance(result, Mapping):
        raise OutputError(f"tick returned {_describe(result)}{_not_a_dict_hint(result)}: "
                          "expected a dict {name: number}")
    out: dict[str, float] = {}
    for k, v in result.items():
        if not isinstance(k, str) or not k.isidentifier():
            raise OutputError(f"an output name is {_describe(k)}: expected a name like "
                              "'ours' (letters, digits, _)")
        out[k] = 1.0 if v is True else 0.0 if v is False else _num(v, f"output {k!r}")
    return out


class Loaded:
    """The team file as loaded: its module, the object called each tick, its version."""

    def __init__(self, module: types.ModuleType, call: Any, instance: Any, version: str) -> None:
        self.module, self.call, self.instance, self.version = module, call, instance, version


class Host:
    """The worker's state: the team folder, the file it runs, what it loaded."""

    def __init__(self, team_dir: Path, memory_mb: int = 0) -> None:
        self.team_dir = team_dir.resolve()
        self.memory_mb = memory_mb  # the address-space limit (0: none), named in a MemoryError
        self.lib_dir = self.team_dir / "lib"
        self.loaded: Loaded | None = None
        #: what the last instance's keep() gave, until a version loads that restores it (a
        #: save that does not import keeps it for the next one)
        self.kept: Any = None
        self.kind = "play"
        self.base_modules = set(sys.modules)
        for p in (str(self.lib_dir), str(self.team_dir)):
            if p not in sys.path:
                sys.path.insert(0, p)

    # ---- where an error happened, in team terms ----

    def team_name(self, filename: str) -> str | None:
        """``filename`` as a team file name ("pass_drill.py", "lib/util.py"), or None when it
        is not in the team folder."""
        try:
            rel = Path(filename).resolve().relative_to(self.team_dir)
        except (ValueError, OSError):
            return None
        return rel.as_posix()

    def error(self, kind: str, exc: BaseException, name: str,
              to_team_end: bool = False) -> dict[str, Any]:
        """An exception as the station shows it: the deepest frame in the team folder
        (``to_team_end``: the traceback ends there too, the worker's frames below it are
        how it was stopped, not what the team wrote)."""
        file, line = name, None
        frames = traceback.extract_tb(exc.__traceback__)
        team_frames = [(i, f) for i, f in enumerate(frames) if self.team_name(f.filename)]
        if isinstance(exc, SyntaxError) and exc.filename and self.team_name(exc.filename):
            file, line = self.team_name(exc.filename) or name, exc.lineno
        elif team_frames:
            f = team_frames[-1][1]
            file, line = self.team_name(f.filename) or name, f.lineno
        # the traceback from the first team frame on (the worker's own frames say nothing)
        first = team_frames[0][0] if team_frames else len(frames)
        end = team_frames[-1][0] + 1 if team_frames and to_team_end else len(frames)
        lines = ["Traceback (most recent call last):\n",
                 *traceback.format_list(frames[first:end]),
                 *traceback.format_exception_only(type(exc), exc)]
        text = "".join(lines)
        for root in (str(self.team_dir) + os.sep,):
            text = text.replace(root, "")
        message = "".join(traceback.format_exception_only(type(exc), exc)).strip()
        if isinstance(exc, MemoryError) and self.memory_mb > 0:
            # a bare "MemoryError" says neither that the worker has a limit nor where it is set
            message += (f" (over the worker's memory limit of {self.memory_mb} MB, the "
                        "station's --team-memory-mb: allocate less, or raise the limit)")
        return {"kind": kind, "message": message, "file": file, "line": line,
                "traceback": text}

    # ---- load, reload ----

    def drop_team_modules(self) -> None:
        """Forgets every module imported from the team folder (numpy, touchline stay)."""
        for mod_name, mod in list(sys.modules.items()):
            f = getattr(mod, "__file__", None)
            if mod_name not in self.base_modules and f and self.team_name(f) is not None:
                del sys.modules[mod_name]
        sys.path_importer_cache.clear()

    def load(self, name: str, kind: str, entry: str) -> str:
        """Imports team file ``name`` (again); returns its version. Raises on failure."""
        self.kind = kind
        old = self.loaded
        self.loaded = None
        if old is not None and old.instance is not None and hasattr(old.instance, "keep"):
            self.kept = old.instance.keep()
        self.drop_team_modules()
        path = self.team_dir / name
        data = path.read_bytes()
        version = hashlib.sha256(data).hexdigest()[:12]
        mod_name = name.rsplit("/", 1)[-1][:-3]
        module = types.ModuleType(mod_name)
        module.__file__ = str(path)
        sys.modules[mod_name] = module
        try:
            code = compile(data, str(path), "exec")
            exec(code, module.__dict__)  # team code: the point of this process
        except BaseException:
            sys.modules.pop(mod_name, None)
            raise
        instance: Any = None
        if kind == "processor":
            cls = getattr(module, entry, None)
            if not isinstance(cls, type):
                raise ImportError(f"{name} has no processor class {entry}")
            instance = cls()
            call = instance.tick
        elif entry == "class" or (not hasattr(module, "play") and hasattr(module, "Play")):
            cls = getattr(module, "Play", None)
            if not isinstance(cls, type):
                raise ImportError(f"{name} defines no class Play")
            instance = cls()
            call = getattr(instance, "tick", None)
            if not callable(call):
                raise ImportError(f"{name}: class Play has no method tick(self, game)")
        else:
            call = getattr(module, "play", None)
            if not callable(call):
                raise ImportError(f"{name} defines no function play(game)")
        if self.kept is not None and instance is not None and hasattr(instance, "restore"):
            instance.restore(self.kept)
        self.kept = None
        self.loaded = Loaded(module, call, instance, version)
        return version

    def info(self) -> dict[str, Any]:
        """What the station needs to know of a processor to schedule it (its class
        attributes, as plain data; the station checks them)."""
        inst = self.loaded.instance if self.loaded is not None else None
        if self.kind != "processor" or inst is None:
            return {}
        out: dict[str, Any] = {}
        for key in ("rate_hz", "max_hz"):
            v = getattr(inst, key, None)
            out[key] = float(v) if isinstance(v, int | float) and not isinstance(v, bool) \
                else repr(v)[:60]
        trigger = getattr(inst, "trigger", None)
        out["trigger"] = trigger if trigger is None or isinstance(trigger, str) \
            else repr(trigger)[:60]
        reads = getattr(inst, "reads", ())
        out["reads"] = [r if isinstance(r, str) else repr(r)[:60] for r in reads] \
            if isinstance(reads, list | tuple) else repr(reads)[:60]
        return out

    # ---- one tick ----

    def tick(self, game: Any, inputs: Any) -> Any:
        loaded = self.loaded
        if loaded is None:
            raise RuntimeError("nothing loaded")
        if self.kind == "processor":
            return plain_outputs(loaded.call(game, inputs))
        return plain_orders(loaded.call(game))


def main() -> None:
    config = json.loads(sys.argv[1])
    proto_in, proto_out = take_stdio()
    mb = int(config.get("memory_mb", 0))
    if mb > 0:
        limit = mb * (1 << 20)
        _soft, hard = resource.getrlimit(resource.RLIMIT_AS)
        if hard != resource.RLIM_INFINITY:
            limit = min(limit, hard)
        resource.setrlimit(resource.RLIMIT_AS, (limit, hard))
    dump = open(config["dump"], "w")  # noqa: SIM115 (open for the process's life)
    faulthandler.enable(file=dump)  # a crash in C (a segfault) says where it was too
    cpu_limit = CpuLimit()
    # past the CPU limit the stacks are written first (C level, whatever the call is doing),
    # then the Python handler raises; SIGUSR1: the station asks where a call that does not
    # answer is waiting, before it ends the worker
    faulthandler.register(signal.SIGPROF, file=dump, all_threads=True, chain=True)
    faulthandler.register(signal.SIGUSR1, file=dump, all_threads=True)
    host = Host(Path(config["team_dir"]), mb)
    name = ""
    send(proto_out, ("ready", os.getpid()))
    while True:
        body = read_frame(proto_in)
        if body is None:
            return
        msg = pickle.loads(body)
        op, seq = msg[0], msg[1]
        if op == "load":
            _, _, name, kind, entry, cpu_s = msg
            try:
                version = cpu_limit.call(cpu_s, host.load, name, kind, entry)
                reply: Any = ("loaded", seq, version, host.info())
            except CpuLimitExceeded as exc:
                reply = ("error", seq, spinning(host, "import", exc, name, cpu_s,
                                                "while loading"), 0.0)
            except BaseException as exc:  # SystemExit from team code's import too
                reply = ("error", seq, host.error("import", exc, name), 0.0)
            send(proto_out, reply)
            forget_stacks(cpu_limit, dump)
        elif op == "tick":
            _, _, game, inputs, cpu_s = msg
            gc.disable()
            t0 = time.thread_time()
            try:
                out = cpu_limit.call(cpu_s, host.tick, game, inputs)
                cpu = time.thread_time() - t0
                version = host.loaded.version if host.loaded else ""
                reply = ("out", seq, out, cpu, version)
            except CpuLimitExceeded as exc:
                cpu = time.thread_time() - t0
                reply = ("error", seq, spinning(host, "budget", exc, name, cpu_s,
                                                "in one call"), cpu)
            except OutputError as exc:
                cpu = time.thread_time() - t0
                reply = ("error", seq, {"kind": "output", "message": str(exc), "file": name,
                                        "line": None, "traceback": ""}, cpu)
            except BaseException as exc:  # SystemExit and KeyboardInterrupt from team code too
                cpu = time.thread_time() - t0
                reply = ("error", seq, host.error("exception", exc, name), cpu)
            try:
                send(proto_out, reply)
            except (pickle.PicklingError, TypeError, AttributeError) as exc:
                send(proto_out, ("error", seq, {
                    "kind": "output", "message": f"the answer cannot be sent: {exc}",
                    "file": name, "line": None, "traceback": ""}, cpu))
            forget_stacks(cpu_limit, dump)
            gc.collect(0)
            gc.enable()
        else:
            send(proto_out, ("error", seq, {"kind": "crash", "message": f"unknown request "
                                             f"{op!r}", "file": name, "line": None,
                                             "traceback": ""}, 0.0))


def forget_stacks(cpu_limit: CpuLimit, dump: Any) -> None:
    """After a call that reached its CPU limit (answered all the same when the team's code
    caught CpuLimitExceeded: this worker goes on), the stacks written then must not pass
    for a later crash's."""
    if cpu_limit.fired:
        cpu_limit.fired = False
        dump.seek(0)
        dump.truncate()


def spinning(host: Host, kind: str, exc: CpuLimitExceeded, name: str, cpu_s: float,
             when: str) -> dict[str, Any]:
    """A call stopped at its CPU limit, as the station shows it: where it was (the
    traceback's deepest team frame), and a message that says what happened (the station
    ends this worker: the next save starts a new one)."""
    err = host.error(kind, exc, name, to_team_end=True)
    err["message"] = (f"spinning: over its CPU limit {when} ({cpu_s:g} s of CPU time; "
                      "a loop that does not end?)")
    err["spinning"] = True
    return err


if __name__ == "__main__":
    main()
