"""The relay's lazily kept state reads the same as the eager bookkeeping it replaced: the
command table's ``due`` between full passes, and the counts of commands sent (SentLog)."""

from __future__ import annotations

import random

from larcmacs_relay.codecs import Command
from larcmacs_relay.commands import CommandTable, RobotState
from larcmacs_relay.feedback import SentLog, sent_items
from sslpb import touchline_pb2

BLUE, YELLOW = touchline_pb2.TEAM_BLUE, touchline_pb2.TEAM_YELLOW


class EagerTable:
    """The table as it was: every ``due`` a full pass, zeros made anew."""

    def __init__(self, timeout_s: float, hold_s: float) -> None:
        self.timeout_s, self.hold_s = timeout_s, hold_s
        self.entries: dict[tuple[int, int], list] = {}  # [command, arrival, state, zero_since]
        self.stale_stops = 0

    def update(self, c: Command, now: float) -> None:
        self.entries[(c.team, c.id)] = [c, now, RobotState.ACTIVE, 0.0]

    def stop_all(self, now: float) -> None:
        for e in self.entries.values():
            e[0], e[2], e[3] = e[0].zero(), RobotState.STOPPED, now

    def due(self, now: float) -> list[Command]:
        out = []
        for key in sorted(self.entries):
            e = self.entries[key]
            if e[2] is RobotState.ACTIVE and now - e[1] > self.timeout_s:
                e[2], e[3] = RobotState.STALE, now
                self.stale_stops += 1
            if e[2] is RobotState.ACTIVE:
                out.append(e[0])
            elif e[2] is not RobotState.IDLE:
                if now - e[3] >= self.hold_s:
                    e[2] = RobotState.IDLE
                else:
                    out.append(e[0].zero())
        return out


def test_due_between_full_passes_is_the_full_pass() -> None:
    rng = random.Random(7)
    pool = [Command(team, rid, forward_mps=0.25 * k) for team in (BLUE, YELLOW)
            for rid in range(4) for k in range(3)]
    table, eager = CommandTable(0.1, 0.5), EagerTable(0.1, 0.5)
    now = 10.0
    versions = set()
    last: list[Command] | None = None
    for step in range(6000):
        now += rng.choice([0.0, 0.001, 0.004, 0.03, 0.09, 0.2])
        r = rng.random()
        if r < 0.4:
            picked = rng.sample(pool, rng.randint(1, 4))
            picked = list({(c.team, c.id): c for c in picked}.values())  # one per robot
            table.update_all(picked, now)
            for c in picked:
                eager.update(c, now)
        elif r < 0.42:
            table.stop_all(now)
            eager.stop_all(now)
        version = table.version
        got = table.due(now)
        want = eager.due(now)
        assert got == want, f"step {step}"
        assert table.stale_stops == eager.stale_stops
        for state in RobotState:
            assert table.count(state) == sum(1 for e in eager.entries.values() if e[2] is state)
        # an unchanged version: the very same command objects as the last call
        if last is not None and version == table.version and table.version in versions:
            assert len(got) == len(last) and all(a is b for a, b in zip(got, last, strict=True))
        versions.add(table.version)
        last = got


def test_sent_log_counts_as_a_per_robot_dict() -> None:
    rng = random.Random(3)
    log = SentLog()
    eager: dict[int, tuple[int, int]] = {}
    snaps = []
    same = (0, 1, 2, 3)
    for k in range(3000):
        ids = same if rng.random() < 0.8 else tuple(sorted(rng.sample(range(6), rng.randint(1, 5))))
        if ids == same and rng.random() < 0.5:
            ids = tuple(same)  # an equal tuple, not the same object
        log.sent(ids, 1000 + k)
        for i in ids:
            eager[i] = (eager.get(i, (0, 0))[0] + 1, 1000 + k)
        if rng.random() < 0.1:
            snaps.append((log.snapshot(), dict(eager)))
    assert sent_items(log.snapshot()) == eager
    for snap, want in snaps:  # a snapshot keeps what had been sent when it was taken
        assert sent_items(snap) == want
