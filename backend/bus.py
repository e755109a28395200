"""The Data Bus: named topics, each a bounded ring that evicts its oldest records.

Producers never wait for consumers. Every record gets a topic-wide sequence number; a
reader keeps its own cursor and sees each record at most once (``read_new``), and learns how
many records it missed when it fell more than a ring behind.
"""

from __future__ import annotations

import asyncio
import os
import time
from collections import deque
from collections.abc import Callable, Iterator
from typing import TYPE_CHECKING, Any, Generic, NamedTuple, TypeVar

if TYPE_CHECKING:
    from .topics import TopicSpec

T = TypeVar("T")
_monotonic = time.monotonic
#: a record made as the tuple it is (``Record(...)`` goes through the named tuple's
#: ``__new__``, a Python function: 0.42 against 0.20 us, three or four writes a camera frame)
_tuple_new = tuple.__new__


class Record(NamedTuple, Generic[T]):
    """One record of a topic (a tuple: built in a call, not a frozen dataclass's three
    ``object.__setattr__``; hundreds are written a second)."""

    seq: int
    time_mono: float  # time.monotonic() when written (the bus's clock)
    value: T


class Topic(Generic[T]):
    """A bounded queue of records plus the latest value and a change notification."""

    def __init__(self, name: str, capacity: int, check: type[Any] | None = None,
                 clock: Callable[[], float] = _monotonic) -> None:
        if capacity < 1:
            raise ValueError(f"topic {name!r}: capacity must be >= 1, got {capacity}")
        self.name = name
        self._check = check  # with DataBus(check_types=True): every record's type
        #: the time records are stamped with (``time.monotonic``; a virtual clock headless:
        #: evaluate/ runs the station's processors faster than real time)
        self._clock = clock
        self._ring: deque[Record[T]] = deque(maxlen=capacity)
        #: the ring's size (a plain attribute, not a property: the relay ingest reads three
        #: in every tick)
        self.capacity = capacity
        self._seq = 0
        self._waiters: list[asyncio.Event] = []
        #: called after every write (the processor runner: a pass runs what reads this topic)
        self.on_write: Callable[[], None] | None = None

    def resize(self, capacity: int) -> None:
        if capacity < 1:
            raise ValueError(f"topic {self.name!r}: capacity must be >= 1, got {capacity}")
        self._ring = deque(self._ring, maxlen=capacity)
        self.capacity = capacity

    @property
    def seq(self) -> int:
        """Sequence number of the newest record (0 before the first write)."""
        return self._seq

    def __len__(self) -> int:
        return len(self._ring)

    def write(self, value: T) -> Record[T]:
        if self._check is not None and not isinstance(value, self._check):
            raise TypeError(f"topic {self.name!r} carries {self._check.__name__}, "
                            f"not {type(value).__name__}")
        self._seq = seq = self._seq + 1
        rec: Record[T] = _tuple_new(Record, (seq, self._clock(), value))
        self._ring.append(rec)
        if self._waiters:
            for ev in self._waiters:
                ev.set()
        if self.on_write is not None:
            self.on_write()
        return rec

    def latest(self) -> Record[T] | None:
        return self._ring[-1] if self._ring else None

    def clear(self) -> None:
        """Forgets every record (time jumped: a replay was seeked); sequence numbers go on, so
        readers' cursors stay valid."""
        self._ring.clear()

    def latest_value(self) -> T | None:
        return self._ring[-1].value if self._ring else None

    def records_after(self, seq: int) -> Iterator[Record[T]]:
        """Records with a sequence number greater than ``seq``, oldest first."""
        ring = self._ring
        if not ring or ring[-1].seq <= seq:
            return iter(())
        first = ring[0].seq
        start = max(0, seq + 1 - first)
        return (ring[i] for i in range(start, len(ring)))

    def age_s(self, now: float | None = None) -> float:
        rec = self.latest()
        if rec is None:
            return -1.0
        return (self._clock() if now is None else now) - rec.time_mono

    def subscribe_event(self) -> asyncio.Event:
        """An event set on every write; the owner clears it. Used to wake waiting readers."""
        ev = asyncio.Event()
        self._waiters.append(ev)
        return ev

    def add_waiter(self, ev: asyncio.Event) -> None:
        """Also set ``ev`` on every write (one event can watch several topics)."""
        self._waiters.append(ev)

    def unsubscribe_event(self, ev: asyncio.Event) -> None:
        if ev in self._waiters:
            self._waiters.remove(ev)


class Reader(Generic[T]):
    """A cursor over one topic: each record is returned by ``read_new`` exactly once."""

    def __init__(self, topic: Topic[T], *, from_start: bool = False) -> None:
        self.topic = topic
        self.cursor = 0 if from_start else topic.seq
        self.missed = 0  # records evicted before this reader saw them

    def read_new(self) -> list[T]:
        topic = self.topic
        seq = topic._seq
        if seq == self.cursor:  # nothing new (most readers, most passes)
            return []
        ring = topic._ring
        n = seq - self.cursor
        if 0 < n <= len(ring):
            # none evicted: the ring holds consecutive records up to ``seq`` (a write appends
            # the next number, eviction takes the oldest, ``clear`` empties it), so the new
            # ones are its last n; taken by index (a record or two per pass: without
            # read_new_records' generator and lists, 1.7 -> ~0.5 us for two)
            self.cursor = seq
            if n == 1:
                return [ring[-1].value]
            if n == 2:
                return [ring[-2].value, ring[-1].value]
            return [ring[i].value for i in range(-n, 0)]
        return [r.value for r in self.read_new_records()]

    def read_new_records(self) -> list[Record[T]]:
        recs = list(self.topic.records_after(self.cursor))
        if recs:
            gap = recs[0].seq - self.cursor - 1
            if gap > 0:
                self.missed += gap
            self.cursor = recs[-1].seq
        elif self.topic.seq > self.cursor:  # everything new was already evicted
            self.missed += self.topic.seq - self.cursor
            self.cursor = self.topic.seq
        return recs

    def has_new(self) -> bool:
        return self.topic.seq > self.cursor


class DataBus:
    """The registry of topics, each declared once in ``backend.topics``. Capacities come from
    the declaration unless ``sizes`` (the ``bus`` parameter group) sets one.

    ``check_types``: every write is checked against the topic's declared type (default: the
    environment's ``TOUCHLINE_CHECK_TOPICS=1``, which the test suite sets).

    ``clock``: what records are stamped with (monotonic seconds; a virtual clock when the
    processors run headless, evaluate/)."""

    def __init__(self, sizes: dict[str, int] | None = None,
                 check_types: bool | None = None,
                 clock: Callable[[], float] = _monotonic) -> None:
        self._topics: dict[str, Topic[Any]] = {}
        self.clock = clock
        self._sizes = dict(sizes or {})
        self.check_types = (os.environ.get("TOUCHLINE_CHECK_TOPICS") == "1"
                            if check_types is None else check_types)

    def of(self, spec: TopicSpec[T]) -> Topic[T]:
        """The topic declared by ``spec`` (created on first use)."""
        t = self._topics.get(spec.name)
        if t is None:
            t = Topic[T](spec.name, self._sizes.get(spec.name, spec.capacity),
                         spec.type if self.check_types else None, self.clock)
            self._topics[spec.name] = t
        return t

    def topics(self) -> list[Topic[Any]]:
        return list(self._topics.values())
