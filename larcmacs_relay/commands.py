"""The command table: latest command per robot, staleness, stop-all and hold (pure, clocked
by the caller with monotonic seconds)."""

from __future__ import annotations

from dataclasses import dataclass, field
from enum import Enum

from larcmacs_relay.codecs import Command


class RobotState(Enum):
    ACTIVE = "active"  # fresh command, repeated every cycle
    STALE = "stale"  # command older than the timeout: zero velocity is sent
    STOPPED = "stopped"  # zeroed by stop_all: zero velocity is sent
    IDLE = "idle"  # held at zero for the hold time: nothing is sent


@dataclass
class _Entry:
    command: Command
    arrival: float
    state: RobotState = RobotState.ACTIVE
    zero_since: float = 0.0


@dataclass
class CommandTable:
    """Latest command per (team, id).

    Every output cycle ``due(now)`` returns what to send: the latest command while it is
    younger than ``timeout_s``; zero velocity once it is older (counted once in
    ``stale_stops``) or after a stop_all; nothing once the robot has been held at zero for
    ``hold_time_s``. A newer command revives a robot; stop_all zeroes every robot known.
    """

    timeout_s: float = 0.1
    hold_time_s: float = 1.0
    stale_stops: int = 0
    _entries: dict[tuple[int, int], _Entry] = field(default_factory=dict)
    #: the entries' keys sorted, made again only when a robot is new (``due`` runs in every
    #: output cycle, several hundred a second)
    _order: list[tuple[int, int]] = field(default_factory=list)

    def update(self, command: Command, now: float) -> None:
        self.update_all([command], now)

    def update_all(self, commands: list[Command], now: float) -> None:
        """Each of ``commands`` in order becomes its robot's command (a command set's robots:
        one call, not one per robot)."""
        entries = self._entries
        active = RobotState.ACTIVE
        for command in commands:
            key = (command.team, command.id)
            entry = entries.get(key)
            if entry is None:
                entries[key] = _Entry(command, now)
                self._order = sorted(entries)
                continue
            entry.command, entry.arrival = command, now
            entry.state, entry.zero_since = active, 0.0

    def stop_all(self, now: float) -> None:
        for entry in self._entries.values():
            entry.command = entry.command.zero()
            entry.state = RobotState.STOPPED
            entry.zero_since = now

    def due(self, now: float) -> list[Command]:
        """Commands to send this cycle, sorted by (team, id)."""
        out: list[Command] = []
        entries = self._entries
        for key in self._order:
            entry = entries[key]
            if entry.state is RobotState.ACTIVE and now - entry.arrival > self.timeout_s:
                entry.state = RobotState.STALE
                entry.zero_since = now
                self.stale_stops += 1
            if entry.state is RobotState.ACTIVE:
                out.append(entry.command)
                continue
            if entry.state is RobotState.IDLE:
                continue
            if now - entry.zero_since >= self.hold_time_s:
                entry.state = RobotState.IDLE
                continue
            out.append(entry.command.zero())
        return out

    def all_zero(self) -> list[Command]:
        """A zero command for every robot ever commanded (the relay's last word)."""
        return [self._entries[k].command.zero() for k in self._order]

    def count(self, state: RobotState) -> int:
        return sum(1 for e in self._entries.values() if e.state is state)

    @property
    def known(self) -> int:
        return len(self._entries)
