"""Several operators (issue 12): who is connected, who drives each team, what each one did.

Pure (no I/O; the clocks are injected): the station keeps one ``Operators``, station state
like any other: it is used on the station thread only (the routes, backend/routes/operators.py,
submit their calls to the station's queue; the health reads it there), so it needs no lock.

* **Identity**: an operator is a *key* (backend/routes/operators.py: the name given at login and the
  address) with a name, a role and an address. Each websocket client is a *session* (id,
  name, role, address, connected since).
* **Driving** is held by one operator per team: the first who drives (a target, a play, a
  teleported robot) takes it; another gets a refusal naming the holder, may ask for it (the
  holder's page shows the request with an accept) or take it over (the page confirms first).
  The holder keeps it while one of its websocket sessions is open, and for
  ``release_after_s`` after its last one closed or its last drive (a script holds it for that
  long after each request: a lease it renews by driving). The emergency stop is never locked.
* **Actions**: every operator action with who and when, the newest ``max_actions`` kept for
  the page (the session log keeps them all).
"""

from __future__ import annotations

import time
import unicodedata
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from domain.wallclock import clock

from .contract import DrivingInfo, OperatorAction, OperatorInfo

MAX_NAME = 32


def clean_name(raw: str | None) -> str | None:
    """A name fit to show: control and format characters dropped, spaces collapsed, at most
    ``MAX_NAME`` characters; None when nothing is left."""
    if not raw:
        return None
    kept = "".join(c for c in raw if unicodedata.category(c)[0] != "C")
    name = " ".join(kept.split())[:MAX_NAME].strip()
    return name or None


@dataclass(frozen=True)
class Who:
    """The operator behind a request or a websocket."""

    key: str
    name: str
    role: str
    address: str

    def __str__(self) -> str:
        """As the session log and the action list say it."""
        return f"{self.name} ({self.role} at {self.address})"


@dataclass
class _Session:
    id: int
    who: Who
    since_unix: float


@dataclass
class _Hold:
    who: Who
    since_unix: float
    last_mono: float  # last drive (or take): a holder without a websocket keeps it this long
    requested_by: Who | None = None
    requested_unix: float = 0.0


class DrivingRefused(Exception):
    """Another operator drives this team (the message names them)."""

    def __init__(self, team: str, holder: Who, since_unix: float) -> None:
        super().__init__(f"{team} is driven by {holder.name} ({holder.address}, since "
                         f"{clock(since_unix)}): ask for driving, or take over")
        self.team = team
        self.holder = holder


class Operators:
    def __init__(self, release_after_s: float = 5.0, max_actions: int = 200,
                 clock: Callable[[], float] = time.monotonic,
                 wall: Callable[[], float] = time.time) -> None:
        self.release_after_s = release_after_s
        self.clock = clock
        self.wall = wall
        self._sessions: dict[int, _Session] = {}
        self._next_id = 1
        self._gone_mono: dict[str, float] = {}  # key -> when its last session closed
        self._holds: dict[str, _Hold] = {}  # team -> holder
        self._actions: deque[OperatorAction] = deque(maxlen=max_actions)
        self._action_seq = 0

    # ---- sessions (websocket clients) ----

    def connect(self, who: Who) -> int:
        sid = self._next_id
        self._next_id += 1
        self._sessions[sid] = _Session(sid, who, self.wall())
        self._gone_mono.pop(who.key, None)
        return sid

    def disconnect(self, sid: int) -> None:
        s = self._sessions.pop(sid, None)
        if s is not None and not self._live(s.who.key):
            self._gone_mono[s.who.key] = self.clock()
            if len(self._gone_mono) > 1000:  # bounded: the oldest are of no use
                for k in sorted(self._gone_mono, key=self._gone_mono.__getitem__)[:500]:
                    del self._gone_mono[k]

    def sessions(self) -> list[OperatorInfo]:
        return [{"session": s.id, "name": s.who.name, "role": s.who.role,
                 "address": s.who.address, "since_unix": s.since_unix}
                for s in self._sessions.values()]

    def _live(self, key: str) -> bool:
        return any(s.who.key == key for s in self._sessions.values())

    # ---- driving ----

    def _current(self, team: str) -> _Hold | None:
        """The team's hold, released first if its holder has gone for ``release_after_s``."""
        h = self._holds.get(team)
        if h is None or self._live(h.who.key):
            return h
        gone = max(h.last_mono, self._gone_mono.get(h.who.key, h.last_mono))
        if self.clock() - gone >= self.release_after_s:
            del self._holds[team]
            return None
        return h

    def drive(self, who: Who, team: str) -> bool:
        """May ``who`` drive ``team``? Takes it when free (True: taken now, to be recorded);
        raises DrivingRefused when another operator holds it."""
        h = self._current(team)
        if h is None:
            self._holds[team] = _Hold(who, self.wall(), self.clock())
            return True
        if h.who.key != who.key:
            raise DrivingRefused(team, h.who, h.since_unix)
        h.last_mono = self.clock()
        h.who = who  # a new name given at login shows at once
        return False

    def holder(self, team: str) -> Who | None:
        h = self._current(team)
        return None if h is None else h.who

    def request(self, who: Who, team: str) -> Who | None:
        """``who`` asks the holder for ``team``: the holder (None: it was free and ``who``
        took it)."""
        h = self._current(team)
        if h is None:
            self._holds[team] = _Hold(who, self.wall(), self.clock())
            return None
        if h.who.key != who.key:
            h.requested_by = who
            h.requested_unix = self.wall()
        return h.who

    def give(self, who: Who, team: str) -> Who:
        """The holder accepts the pending request: the requester drives now (returned)."""
        h = self._current(team)
        if h is None or h.who.key != who.key:
            raise ValueError(f"{who.name} does not drive {team}: nothing to give")
        if h.requested_by is None:
            raise ValueError(f"nobody asked to drive {team}")
        to = h.requested_by
        self._holds[team] = _Hold(to, self.wall(), self.clock())
        return to

    def take_over(self, who: Who, team: str) -> Who | None:
        """``who`` drives ``team`` from now on, whoever held it (returned, None: nobody)."""
        h = self._current(team)
        self._holds[team] = _Hold(who, self.wall(), self.clock())
        return None if h is None or h.who.key == who.key else h.who

    def release(self, who: Who, team: str) -> bool:
        """The holder lets go (False: ``who`` did not hold it)."""
        h = self._current(team)
        if h is None or h.who.key != who.key:
            return False
        del self._holds[team]
        return True

    def driving(self) -> list[DrivingInfo]:
        out: list[DrivingInfo] = []
        for team in sorted(self._holds):
            h = self._current(team)
            if h is None:
                continue
            req = h.requested_by
            out.append({"team": team, "key": h.who.key, "name": h.who.name,
                        "address": h.who.address, "since_unix": h.since_unix,
                        "connected": self._live(h.who.key),
                        "requested_by": None if req is None else req.name,
                        "requested_key": None if req is None else req.key,
                        "requested_unix": None if req is None else h.requested_unix})
        return out

    # ---- actions ----

    def record(self, action: str, by: str, details: dict[str, Any] | None = None) -> None:
        """One operator action for the page's list (bounded: the newest are kept)."""
        summary = ", ".join(f"{k}={_short(v)}" for k, v in (details or {}).items()
                            if v is not None)
        self._action_seq += 1
        self._actions.append({"seq": self._action_seq, "time_unix": self.wall(),
                              "action": action, "by": by, "details": summary[:200]})

    def actions(self) -> list[OperatorAction]:
        """Newest first."""
        return list(reversed(self._actions))


def _short(v: Any) -> str:
    if isinstance(v, float):
        return f"{v:.0f}" if abs(v) >= 10 else f"{v:.2f}"
    text = str(v)
    return text if len(text) <= 80 else text[:77] + "..."
