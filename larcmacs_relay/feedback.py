"""The feedback forwarding rule (pure: no sockets; the caller gives the clock).

A simulator answers every RobotControl the relay sends, so at one command set per camera
frame the answers come several hundred times a second, nearly all of them the same bytes
(the same robots, the same ball contact). Forwarding each one cost the relay an envelope and
a ZeroMQ message and the backend a parse and an update per answer, for nothing new. The rule,
per answer stream (kind of answer and team):

- an answer whose bytes differ from the last one forwarded goes on at once (a contact that
  changes is never delayed); answers held back before it are forwarded first, so that every
  envelope stands only for answers with its own bytes;
- an answer with the same bytes goes on at once if the last forward is ``interval_s`` old,
  else it is held: only the latest one held is kept; the next answer after the interval
  takes its place, and if none comes it goes on by itself two intervals after the last
  forward (the relay's timer: while answers keep coming the timer never fires, it is
  cancelled by the forward, so the coalescing costs the relay no wake-up of its own);
- every valid answer is counted: an envelope's ``sequence`` is the stream's count of answers
  at the one it carries, so the backend knows how many answers (all with its bytes) it
  stands for: its sequence minus the previous envelope's of the same stream.

``interval_s`` 0 forwards every answer (grSim's robot status, which comes only on a change,
is never held).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

#: what the relay had sent to a team's robots at one moment (SentLog.snapshot): the counts
#: before the current run, the run's robots, its datagrams and the last one's time (ns)
SentSnapshot = tuple[dict[int, tuple[int, int]], tuple[int, ...], int, int]


class SentLog:
    """Commands sent to one team's robots: per robot the datagrams that carried it and the
    wall clock (ns) of the last one. A cycle's datagram carries the same robots as the one
    before nearly always, so a send is counted in a run (the robots, how many datagrams, the
    last one's time: no per-robot update per cycle); a datagram with other robots folds the
    run into the counts. Read (``items``) only when an answer is forwarded."""

    __slots__ = ("_base", "_ids", "_last_ns", "_run")

    def __init__(self) -> None:
        #: the counts before the run {id: (count, last ns)}: never changed once made (a
        #: snapshot keeps it), a fold makes a new one
        self._base: dict[int, tuple[int, int]] = {}
        self._ids: tuple[int, ...] = ()
        self._run = 0
        self._last_ns = 0

    def sent(self, ids: tuple[int, ...], now_ns: int) -> None:
        """A datagram with robots ``ids`` went out at wall clock ``now_ns``."""
        if ids is not self._ids and ids != self._ids:
            if self._run:
                self._base = sent_items(self.snapshot())
            self._ids, self._run = ids, 0
        self._run += 1
        self._last_ns = now_ns

    def snapshot(self) -> SentSnapshot:
        return self._base, self._ids, self._run, self._last_ns


def sent_items(snapshot: SentSnapshot) -> dict[int, tuple[int, int]]:
    """{id: (datagrams sent, last one's wall clock ns)} of a SentLog snapshot."""
    base, ids, run, last_ns = snapshot
    if not run:
        return base
    out = dict(base)
    for i in ids:
        got = out.get(i)
        out[i] = ((got[0] if got is not None else 0) + run, last_ns)
    return out


@dataclass(slots=True)
class HeldAnswer:
    """An answer not forwarded yet, with what it is forwarded with."""

    data: bytes
    addr: tuple[str, int]
    receive_ns: int
    sequence: int
    #: what the relay had sent to the team's robots when it arrived (``sent_items`` of it:
    #: {id: (count, last ns)})
    sent: SentSnapshot


class FeedbackGate:
    """One answer stream's rule (module docstring)."""

    __slots__ = ("answers", "checked", "held", "interval_s", "kind", "last_forward",
                 "last_payload", "team")

    def __init__(self, kind: int, team: int, interval_s: float) -> None:
        #: the stream: touchline.FeedbackKind and touchline.Team numbers
        self.kind = kind
        self.team = team
        self.interval_s = interval_s
        #: valid answers received so far (the sequence of the latest)
        self.answers = 0
        #: the bytes of the last answer forwarded, and when (the caller's clock)
        self.last_payload: bytes | None = None
        self.last_forward = -math.inf
        #: the latest answer held back (with the bytes of the last one forwarded), or None
        self.held: HeldAnswer | None = None
        #: the last valid answer checked, its errors and the first one (a repeat of the same
        #: bytes is not parsed again: the same bytes say the same)
        self.checked: tuple[bytes, int, str] | None = None

    def arrive(self, data: bytes, now: float) -> bool:
        """A valid answer ``data`` arrived at ``now`` and is counted: True when it goes on
        now (after ``held``, if set and ``data`` differs from it), False when it is to be held
        (``hold``) until ``flush_at``."""
        self.answers += 1
        return (self.interval_s <= 0.0 or data != self.last_payload
                or now - self.last_forward >= self.interval_s)

    def hold(self, answer: HeldAnswer) -> None:
        self.held = answer

    def forwarded(self, data: bytes, now: float) -> None:
        """An answer with ``data`` went on at ``now``: anything held is superseded (it had the
        same bytes, so the newer envelope's sequence counts it)."""
        self.last_payload = data
        self.last_forward = now
        self.held = None

    @property
    def flush_at(self) -> float:
        """When a held answer goes on if no newer one has (the caller's clock)."""
        return self.last_forward + 2.0 * self.interval_s
