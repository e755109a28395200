"""The command table: latest command per robot, staleness, stop-all and hold (pure, clocked
by the caller with monotonic seconds)."""

from __future__ import annotations

import math
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
    #: counts every change of what ``due`` returns (a command, a state, a robot): while it
    #: stays the same, the commands due are the same objects as before (the output reuses
    #: what it made of them)
    version: int = 0
    _entries: dict[tuple[int, int], _Entry] = field(default_factory=dict)
    #: the entries' keys sorted, made again only when a robot is new (``due`` runs in every
    #: output cycle, several hundred a second)
    _order: list[tuple[int, int]] = field(default_factory=list)
    #: the last full pass of ``due``: its commands, each active robot's place in them (a new
    #: command of an active robot is put in its place), and the time before which no entry
    #: changes state (an active command goes stale, a held stop ends); None: a pass is due
    _due: list[Command] | None = None
    _due_at: dict[tuple[int, int], int] = field(default_factory=dict)
    _recheck_at: float = -math.inf

    def update(self, command: Command, now: float) -> None:
        self.update_all([command], now)

    def update_all(self, commands: list[Command], now: float) -> None:
        """Each of ``commands`` in order becomes its robot's command (a command set's robots:
        one call, not one per robot)."""
        entries = self._entries
        active = RobotState.ACTIVE
        due = self._due
        due_at = self._due_at
        for command in commands:
            key = (command.team, command.id)
            entry = entries.get(key)
            if entry is None:
                entries[key] = _Entry(command, now)
                self._order = sorted(entries)
                self._due = due = None
                self.version += 1
                continue
            entry.arrival = now  # later than before: the recheck time stays a lower bound
            if entry.state is active:
                if entry.command is not command:
                    entry.command = command
                    self.version += 1
                    if due is not None:
                        due[due_at[key]] = command
                continue
            entry.command, entry.state, entry.zero_since = command, active, 0.0
            self._due = due = None
            self.version += 1

    def stop_all(self, now: float) -> None:
        for entry in self._entries.values():
            entry.command = entry.command.zero()
            entry.state = RobotState.STOPPED
            entry.zero_since = now
        self._due = None
        self.version += 1

    def due(self, now: float) -> list[Command]:
        """Commands to send this cycle, sorted by (team, id). Between state changes (a
        command going stale, a held stop ending, an update of a robot not active) it is the
        last full pass's list with the active robots' newest commands in their places."""
        due = self._due
        if due is not None and now < self._recheck_at:
            return list(due)
        out: list[Command] = []
        entries = self._entries
        due_at: dict[tuple[int, int], int] = {}
        recheck = math.inf
        timeout, hold = self.timeout_s, self.hold_time_s
        changed = due is None
        for key in self._order:
            entry = entries[key]
            if entry.state is RobotState.ACTIVE and now - entry.arrival > timeout:
                entry.state = RobotState.STALE
                entry.zero_since = now
                entry.command = entry.command.zero()  # made once, sent for the hold time
                self.stale_stops += 1
                changed = True
            if entry.state is RobotState.ACTIVE:
                due_at[key] = len(out)
                out.append(entry.command)
                recheck = min(recheck, entry.arrival + timeout)
                continue
            if entry.state is RobotState.IDLE:
                continue
            if now - entry.zero_since >= hold:
                entry.state = RobotState.IDLE
                changed = True
                continue
            out.append(entry.command)
            recheck = min(recheck, entry.zero_since + hold)
        if changed:
            self.version += 1
        self._due, self._due_at = out, due_at
        # a little early: ``now - t > timeout`` and ``now > t + timeout`` can differ in the
        # last bit, and a pass too early only finds nothing changed
        self._recheck_at = recheck - 1e-6
        return list(out)

    def all_zero(self) -> list[Command]:
        """A zero command for every robot ever commanded (the relay's last word)."""
        return [self._entries[k].command.zero() for k in self._order]

    def count(self, state: RobotState) -> int:
        return sum(1 for e in self._entries.values() if e.state is state)

    @property
    def known(self) -> int:
        return len(self._entries)
