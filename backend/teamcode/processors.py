"""The team's processors (the paper's abstraction, opened to the team): each processor file
of the team folder runs in a worker of its own, at its ``rate_hz`` or on every new world
(``trigger = "world"``, at most ``max_hz``), with the Game (every robot of ours in ``mine``)
and the latest values of the topics it ``reads`` as plain data.

Its outputs (a flat mapping of finite numbers and booleans, the same names every tick)
become the Data Bus topic ``team/<name>`` (made when first written), the world message's
``team`` block (so the Plots tab lists ``team.<name>.<key>``), session log records of type
1006 (``TYPE_TL_TEAM``), and ``Game.topics[<name>]`` for the plays. A processor fails as a
play does (import, exception, malformed output, over budget, stuck, crashed): its topic stops
updating and the error is shown until the next save.

The host is one station processor at ``HOST_HZ``: it sends each processor's request when due
and never waits for an answer (answers are handled when they arrive)."""

from __future__ import annotations

import asyncio
import json
import math
import time
from collections.abc import Callable, Mapping
from typing import Any

from ssllog.format import TYPE_TL_TEAM

from .. import topics as topic_specs
from ..bus import DataBus, Topic
from ..params.model import StationParams
from ..processor import Every, Processor
from ..topics import TopicSpec
from ..world.state import Team
from .discovery import Found
from .game import GameBuilder
from .plain import plain
from .registry import TeamRegistry
from .runner import Pending, PythonRunner
from .state import ErrorInfo

#: how often the host looks whether a processor is due (the highest rate a processor gets)
HOST_HZ = 100.0
MAX_OUTPUTS = 64
TEAM_TOPIC_CAPACITY = 100


def team_topic(name: str) -> TopicSpec[dict[str, float]]:
    return TopicSpec[dict[str, float]](f"team/{name}", dict, TEAM_TOPIC_CAPACITY,
                                       f"the team processor {name}'s outputs")


class Schedule:
    """When a processor runs next."""

    def __init__(self) -> None:
        self.next_due = 0.0
        self.world_seq = -1
        self.keys: tuple[str, ...] | None = None  # its outputs' names since its last load
        self.version: str | None = None


class TeamProcessors(Processor):
    name = "team-processors"

    def __init__(self, bus: DataBus, registry: TeamRegistry, memory_mb: int) -> None:
        super().__init__(Every(HOST_HZ))
        self.bus = bus
        self.registry = registry
        self.memory_mb = memory_mb
        self.world = bus.of(topic_specs.WORLD)
        self.geometry = bus.of(topic_specs.GEOMETRY)
        self.referee = bus.of(topic_specs.REFEREE)
        self.runners: dict[str, PythonRunner] = {}
        self.schedules: dict[str, Schedule] = {}
        #: the latest outputs of each running processor, by name (the world message, plays)
        self.outputs: dict[str, dict[str, float]] = {}
        self.builder = GameBuilder()
        self.budget_s = 0.010
        self.our_team: Team = "blue"
        self.our_side_negative = True
        self.side_from_referee = True
        #: set by the station
        self.referee_source: Callable[[], Any] = self.referee.latest_value
        self.contacts: Callable[[Team], Mapping[int, bool]] = lambda _team: {}
        self.replaying: Callable[[], bool] = lambda: False
        self.record: Callable[[int, int, bytes], None] | None = None
        self._t0 = time.monotonic()
        self._closing: set[asyncio.Task[None]] = set()
        registry.listeners.append(self._changed)

    def configure(self, params: StationParams) -> None:
        self.budget_s = params.strategy.team_budget_ms / 1000.0
        t = params.team
        self.our_team = t.our_team
        self.our_side_negative = t.our_side == "negative-x"
        self.side_from_referee = t.side_from_referee

    # ---- the folder ----

    def _changed(self, changed: set[str], found: Mapping[str, Found]) -> None:
        py_libs = any(n.endswith(".py") and (n not in found or found[n].kind == "library")
                      for n in changed)
        for name in list(self.runners):
            f = found.get(name)
            if f is None or f.kind != "processor":
                self._close(name)
            elif name in changed or py_libs:
                self.schedules[name] = Schedule()
                self.runners[name].update(f)

    def _close(self, name: str) -> None:
        r = self.runners.pop(name, None)
        self.schedules.pop(name, None)
        if r is not None:
            self.outputs.pop(r.found.stem, None)
            task = asyncio.get_running_loop().create_task(r.close())
            self._closing.add(task)
            task.add_done_callback(self._closing.discard)

    def _runner(self, f: Found) -> PythonRunner:
        r = self.runners.get(f.name)
        if r is None or r.closed:
            r = PythonRunner(f, self.registry.run(f.name), self.registry.dir, self.memory_mb,
                             "processor")
            r.info_check = self.check_info
            self.runners[f.name] = r
            self.schedules[f.name] = Schedule()
            if f.error is not None:
                r.update(f)
        return r

    def check_info(self, info: dict[str, Any]) -> str | None:
        """A processor's schedule, as its class says (None: usable)."""
        for key in ("rate_hz", "max_hz"):
            v = info.get(key)
            if not isinstance(v, float) or not math.isfinite(v) or v <= 0.0:
                return f"{key} must be a positive number of Hz, not {v}"
        trigger = info.get("trigger")
        if trigger not in (None, "world"):
            return f"trigger must be None (run at rate_hz) or 'world', not {trigger!r}"
        reads = info.get("reads")
        if not isinstance(reads, list) or not all(isinstance(r, str) for r in reads):
            return f"reads must be a tuple of topic names, not {reads!r}"
        known = {t.name for t in self.bus.topics()}
        unknown = [r for r in reads if r not in known]
        if unknown:
            return (f"reads {', '.join(map(repr, unknown))}: no such topic (topics: "
                    f"{', '.join(sorted(known))})")
        return None

    # ---- ticks ----

    async def tick(self) -> None:
        self.run_due(time.monotonic())

    def run_due(self, now: float) -> int:
        """Sends the requests of the processors due at ``now`` (monotonic s); how many."""
        sent = 0
        processors = [f for f in self.registry.found.values() if f.kind == "processor"]
        rec = self.world.latest()
        game = None
        for f in processors:
            r = self._runner(f)
            r.ensure()
            if r.run.state != "running" or r.inflight is not None or rec is None:
                continue
            s = self.schedules[f.name]
            if s.version != r.run.loaded_version:  # loaded again: its names may change
                s.version, s.keys = r.run.loaded_version, None
            info = r.info
            if info.get("trigger") == "world":
                if rec.seq == s.world_seq or now < s.next_due:
                    continue
                s.world_seq = rec.seq
                s.next_due = now + 1.0 / min(float(info["max_hz"]), HOST_HZ)
            else:
                if now < s.next_due:
                    continue
                period = 1.0 / min(float(info.get("rate_hz", 10.0)), HOST_HZ)
                # the next one a period later, or now when it fell behind
                s.next_due = max(s.next_due + period, now) if s.next_due else now + period
            if game is None:
                game = self.builder.build(
                    rec.value, self.geometry.latest_value(), self.referee_source(),
                    self.our_team, self.our_side_negative, self.side_from_referee,
                    now - self._t0, self.contacts(self.our_team), self.outputs,
                    self.replaying())
                game = _with_mine(game)
            inputs = {name: plain(self.bus.of(_spec(name)).latest_value())
                      for name in info.get("reads", ())}
            p = r.send(game, inputs, self.budget_s, now)
            if p is not None:
                sent += 1
                p.fut.add_done_callback(self._on_answer(r, p))
        return sent

    def _on_answer(self, r: PythonRunner, p: Pending) -> Callable[[Any], None]:
        return lambda _fut: self._answered(r, p)

    def _answered(self, r: PythonRunner, p: Pending) -> None:
        """A processor's answer (accounted by its runner already): published."""
        if r.closed or p.output is None or not isinstance(p.output, dict):
            if r.failed:
                self.outputs.pop(r.found.stem, None)
            return
        values: dict[str, float] = {}
        for k, v in p.output.items():
            if not isinstance(k, str) or isinstance(v, bool) or not isinstance(v, float):
                r.fail(ErrorInfo("output", f"output {k!r} is not a number", r.name))
                break
            if not math.isfinite(v):
                r.fail(ErrorInfo("output", f"output {k!r} is {v!r}: outputs must be finite",
                                 r.name))
                break
            values[k] = v
        else:
            s = self.schedules.get(r.name)
            keys = tuple(sorted(values))
            if len(keys) > MAX_OUTPUTS:
                r.fail(ErrorInfo("output", f"{len(keys)} outputs: at most {MAX_OUTPUTS}",
                                 r.name))
            elif s is not None and s.keys is not None and keys != s.keys:
                r.fail(ErrorInfo("output", f"the outputs' names changed ({', '.join(s.keys)}"
                                 f" -> {', '.join(keys)}): a processor gives the same names "
                                 "every tick (a save may change them)", r.name))
            else:
                if s is not None:
                    s.keys = keys
                self.publish(r.found.stem, values)
                r.run.outputs = values
                return
        self.outputs.pop(r.found.stem, None)

    def publish(self, name: str, values: dict[str, float]) -> None:
        self.outputs = {**self.outputs, name: values}  # a new dict: readers hold the old one
        topic: Topic[dict[str, float]] = self.bus.of(team_topic(name))
        topic.write(values)
        if self.record is not None and not self.replaying():
            self.record(time.time_ns(), TYPE_TL_TEAM,
                        json.dumps({"name": name, "values": values}).encode())

    def world_view(self) -> dict[str, dict[str, float]]:
        """The world message's ``team`` block: running processors' latest outputs."""
        return dict(self.outputs)

    async def teardown(self) -> None:
        await self.close()

    async def close(self) -> None:
        for name in list(self.runners):
            self._close(name)
        if self._closing:
            await asyncio.gather(*self._closing, return_exceptions=True)


def _spec(name: str) -> TopicSpec[Any]:
    """The spec of an existing topic by name (checked at load: ``check_info``)."""
    for spec in topic_specs.ALL:
        if spec.name == name:
            return spec
    if name.startswith("team/"):
        return team_topic(name[5:])
    return TopicSpec[Any](name, object, 1, "")


def _with_mine(game: Any) -> Any:
    from dataclasses import replace

    return replace(game, mine=tuple(r.id for r in game.ours if r.visible))
