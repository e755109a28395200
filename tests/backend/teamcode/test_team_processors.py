"""The team's processors: a worker each, at their rate or on every new world, reading bus
topics as plain data; their outputs as the topic team/<name>, the world's team block, the
session log (type 1006) and Game.topics for plays; failures like a play's."""

from __future__ import annotations

import json
import math
import time
from collections import namedtuple
from collections.abc import AsyncIterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import pytest

from backend import topics
from backend.bus import DataBus
from backend.params.model import PLAYS, StationParams
from backend.teamcode.plain import plain
from backend.teamcode.processors import TeamProcessors, team_topic
from backend.teamcode.registry import TeamRegistry
from backend.world.state import RobotState, WorldState
from ssllog.format import TYPE_TL_TEAM

from .helpers import until, write

COUNTER = ("from touchline import Processor\n"
           "class Counter(Processor):\n"
           "    rate_hz = {rate}\n"
           "    trigger = {trigger!r}\n"
           "    max_hz = 50.0\n"
           "    reads = {reads!r}\n"
           "    def __init__(self):\n        self.n = 0\n"
           "    def tick(self, game, inputs):\n"
           "        self.n += 1\n"
           "        return {{'n': self.n, 'robots': len(game.mine), 'ok': True,\n"
           "                 'inputs': len(inputs)}}\n")


class Host:
    def __init__(self, folder: Path) -> None:
        self.bus = DataBus(check_types=True)
        for spec in topics.ALL:
            self.bus.of(spec)
        self.registry = TeamRegistry(folder, PLAYS)
        self.registry.rescan()
        self.procs = TeamProcessors(self.bus, self.registry, 1024)
        self.procs.configure(StationParams.model_validate(
            {"strategy": {"team_budget_ms": 200.0}}))
        self.records: list[tuple[int, int, bytes]] = []
        self.procs.record = lambda t, k, b: self.records.append((t, k, b))
        self.now = 1000.0

    def see(self) -> None:
        robots = (RobotState("blue", 1, 0.0, 0.0, 0.0), RobotState("blue", 2, 10.0, 0.0, 0.0),
                  RobotState("yellow", 1, 500.0, 0.0, 0.0))
        self.bus.of(topics.WORLD).write(WorldState(time.time(), time.time_ns(), None, robots))

    async def loaded(self, name: str) -> None:
        self.procs.run_due(self.now)  # starts the worker
        await until(lambda: self.registry.runs[name].state in ("running", "error"), 30.0)

    async def answered(self, name: str, ticks: int) -> None:
        await until(lambda: self.registry.runs[name].ticks >= ticks
                    or self.registry.runs[name].state == "error")


@pytest.fixture
async def host(tmp_path: Path) -> AsyncIterator[Host]:
    h = Host(tmp_path)
    try:
        yield h
    finally:
        await h.procs.close()


async def test_a_processor_at_its_rate_publishes_everywhere(tmp_path: Path) -> None:
    write(tmp_path, "counter.py", COUNTER.format(rate=10.0, trigger=None, reads=("world",)))
    h = Host(tmp_path)
    try:
        h.see()
        await h.loaded("counter.py")
        assert h.procs.runners["counter.py"].info["rate_hz"] == 10.0
        sent = [h.procs.run_due(h.now + dt) for dt in (0.0, 0.05, 0.09)]
        assert sent == [1, 0, 0]  # 10 Hz: one call, the next due 0.1 s later
        await h.answered("counter.py", 1)
        assert h.procs.run_due(h.now + 0.1) == 1
        await h.answered("counter.py", 2)
        values = {"n": 2.0, "robots": 2.0, "ok": 1.0, "inputs": 1.0}
        assert h.bus.of(team_topic("counter")).latest_value() == values
        assert "team/counter" in [t.name for t in h.bus.topics()]
        assert h.procs.world_view() == {"counter": values}
        assert h.registry.runs["counter.py"].outputs == values
        t, kind, body = h.records[-1]
        assert kind == TYPE_TL_TEAM and abs(t - time.time_ns()) < 10e9
        assert json.loads(body) == {"name": "counter", "values": values}
    finally:
        await h.procs.close()


async def test_on_every_new_world_at_most_max_hz(host: Host, tmp_path: Path) -> None:
    write(tmp_path, "on_world.py", COUNTER.format(rate=1.0, trigger="world", reads=()))
    host.registry.rescan()
    host.see()
    await host.loaded("on_world.py")
    assert host.procs.run_due(host.now) == 1
    await host.answered("on_world.py", 1)
    host.see()
    assert host.procs.run_due(host.now + 0.01) == 0  # a new world within 1/max_hz = 20 ms
    assert host.procs.run_due(host.now + 0.021) == 1
    await host.answered("on_world.py", 2)
    assert host.procs.run_due(host.now + 5.0) == 0  # no new world: not at its rate either
    assert host.bus.of(team_topic("on_world")).latest_value()["n"] == 2.0  # type: ignore[index]


async def test_reads_and_plain_data(host: Host, tmp_path: Path) -> None:
    write(tmp_path, "reader.py",
          "from touchline import Processor\n"
          "class Reader(Processor):\n"
          "    reads = ('world', 'team/other')\n"
          "    def tick(self, game, inputs):\n"
          "        w = inputs['world']\n"
          "        other = inputs['team/other'] or {}\n"
          "        return {'robots': len(w['robots']), 'x': w['robots'][1]['x'],\n"
          "                'other': other.get('v', -1.0),\n"
          "                'topic': game.topics.get('other', {}).get('v', -1.0)}\n")
    host.registry.rescan()
    host.bus.of(team_topic("other"))  # a topic of another processor, existing
    host.procs.publish("other", {"v": 7.0})
    host.see()
    await host.loaded("reader.py")
    assert host.registry.runs["reader.py"].state == "running"
    host.procs.run_due(host.now)
    await host.answered("reader.py", 1)
    assert host.procs.outputs["reader"] == {"robots": 3.0, "x": 10.0, "other": 7.0,
                                            "topic": 7.0}


async def test_a_topic_it_cannot_read_is_an_import_error(host: Host, tmp_path: Path) -> None:
    write(tmp_path, "bad_reads.py", COUNTER.format(rate=10.0, trigger=None,
                                                   reads=("no-such-topic",)))
    write(tmp_path, "bad_rate.py", COUNTER.format(rate=-1, trigger=None, reads=()))
    write(tmp_path, "bad_trigger.py", COUNTER.format(rate=1.0, trigger="vision", reads=()))
    host.registry.rescan()
    host.see()
    for name, words in (("bad_reads.py", "'no-such-topic': no such topic"),
                        ("bad_rate.py", "rate_hz must be a positive number"),
                        ("bad_trigger.py", "trigger must be None")):
        await host.loaded(name)
        e = host.registry.runs[name].error
        assert e is not None and e.kind == "import" and words in e.message, e


async def test_bad_outputs_fail_and_the_topic_stops(host: Host, tmp_path: Path) -> None:
    src = ("import math\nfrom touchline import Processor\n"
           "class P(Processor):\n    rate_hz = 100.0\n"
           "    def __init__(self):\n        self.n = 0\n"
           "    def tick(self, game, inputs):\n        self.n += 1\n"
           "        {body}\n")
    write(tmp_path, "nan_out.py", src.format(
        body="return {'a': 1.0 if self.n < 2 else math.nan}"))
    write(tmp_path, "renames.py", src.format(
        body="return {'a': 1.0} if self.n < 2 else {'b': 1.0}"))
    host.registry.rescan()
    host.see()
    for name in ("nan_out.py", "renames.py"):
        await host.loaded(name)
    stem = {"nan_out.py": "nan_out", "renames.py": "renames"}
    for k in range(1, 3):
        host.procs.run_due(host.now + k)
        for name in stem:
            await host.answered(name, k)
    await until(lambda: all(host.registry.runs[n].state == "error" for n in stem))
    e1, e2 = host.registry.runs["nan_out.py"].error, host.registry.runs["renames.py"].error
    assert e1 is not None and e1.kind == "output" and "'a' is nan" in e1.message
    assert e2 is not None and e2.kind == "output" and "names changed (a -> b)" in e2.message
    assert host.procs.world_view() == {}  # the failed ones are no longer shown
    assert host.bus.of(team_topic("nan_out")).latest_value() == {"a": 1.0}  # stopped there
    # a save may change the names
    write(tmp_path, "renames.py", src.format(body="return {'c': float(self.n)}"))
    host.registry.rescan()
    await until(lambda: host.registry.runs["renames.py"].state == "running", 30.0)
    host.procs.run_due(host.now + 10)
    await until(lambda: "renames" in host.procs.outputs)
    assert host.procs.outputs["renames"] == {"c": 1.0}  # a new instance: n from 0 (no keep)


def test_plain_data() -> None:
    @dataclass(frozen=True)
    class D:
        a: int
        b: tuple[float, ...]

    P = namedtuple("P", "x y")
    got: Any = plain({("blue", 3): D(1, (1.0, math.inf)), "p": P(1, "s"), "raw": b"\x00\x01",
                      "set": {1}})
    assert got == {"blue/3": {"a": 1, "b": [1.0, math.inf]}, "p": {"x": 1, "y": "s"},
                   "raw": {"bytes": 2}, "set": [1]}
    deep: Any = []
    for _ in range(20):
        deep = [deep]
    assert plain(deep) is not None


async def test_the_shipped_processor(tmp_path: Path) -> None:
    h = Host(Path(__file__).resolve().parents[3] / "team")
    try:
        h.see()
        await h.loaded("possession.py")
        assert h.registry.runs["possession.py"].state == "running"
        h.procs.run_due(h.now)
        await h.answered("possession.py", 1)
        out = h.procs.outputs["possession"]
        assert set(out) == {"ours", "near_ours_mm", "near_theirs_mm"}
        assert 0.0 <= out["ours"] <= 1.0
    finally:
        await h.procs.close()
