import random

import pytest

from backend import topics
from backend.bus import DataBus, Reader, Topic
from backend.params.model import StationParams


def test_topic_evicts_oldest_and_keeps_latest() -> None:
    t: Topic[int] = Topic("t", 3)
    for i in range(5):
        t.write(i)
    assert len(t) == 3
    assert t.latest_value() == 4
    assert [r.value for r in t.records_after(0)] == [2, 3, 4]
    assert t.seq == 5


def test_reader_sees_each_record_once_and_counts_missed() -> None:
    t: Topic[int] = Topic("t", 3)
    r = Reader(t)
    t.write(1)
    t.write(2)
    assert r.read_new() == [1, 2]
    assert r.read_new() == []
    for i in range(3, 9):  # 6 writes into a ring of 3: 3 are evicted before the reader looks
        t.write(i)
    assert r.read_new() == [6, 7, 8]
    assert r.missed == 3


def test_reader_one_record_at_a_time_and_after_a_clear() -> None:
    """The one-new-record way and the general one agree: each record once, in order, misses
    counted (a ring of 1 overwritten, a cleared topic whose records were never read)."""
    t: Topic[int] = Topic("t", 1)
    r = Reader(t)
    for i in range(1, 4):
        t.write(i)
        assert r.read_new() == [i]
        assert r.read_new() == []
    t.write(4)
    t.write(5)  # 4 overwritten in the ring of 1
    assert r.read_new() == [5]
    assert r.missed == 1
    t.write(6)
    t.clear()  # 6 forgotten before it was read
    assert r.read_new() == []
    assert r.missed == 2
    t.write(7)
    assert r.read_new() == [7]
    assert r.missed == 2


def test_two_readers_have_independent_cursors() -> None:
    t: Topic[str] = Topic("t", 10)
    a, b = Reader(t), Reader(t)
    t.write("x")
    assert a.read_new() == ["x"]
    t.write("y")
    assert b.read_new() == ["x", "y"]
    assert a.read_new() == ["y"]


def test_reader_created_late_starts_at_the_end_unless_asked() -> None:
    t: Topic[int] = Topic("t", 10)
    t.write(1)
    assert Reader(t).read_new() == []
    assert Reader(t, from_start=True).read_new() == [1]


def test_bus_sizes_come_from_the_declarations_unless_configured() -> None:
    bus = DataBus({"vision-detections": 30, "robot-commands": 20})
    assert bus.of(topics.VISION_DETECTIONS).capacity == 30
    assert bus.of(topics.ROBOT_COMMANDS).capacity == 20
    assert bus.of(topics.WORLD).capacity == topics.WORLD.capacity
    assert bus.of(topics.VISION_DETECTIONS) is bus.of(topics.VISION_DETECTIONS)


def test_every_topic_is_declared_once_with_a_type_and_a_capacity() -> None:
    names = [s.name for s in topics.ALL]
    assert len(names) == len(set(names))
    assert all(isinstance(s.type, type) and s.capacity >= 1 and s.what for s in topics.ALL)
    # every bus parameter sizes a declared topic
    assert set(StationParams().bus.sizes()) <= set(names)


def test_a_record_of_another_type_is_refused_when_types_are_checked() -> None:
    checked = DataBus(check_types=True)
    with pytest.raises(TypeError, match="topic 'world' carries WorldState, not dict"):
        checked.of(topics.WORLD).write({"robots": []})  # type: ignore[arg-type]
    assert checked.of(topics.WORLD).seq == 0
    DataBus(check_types=False).of(topics.WORLD).write({"robots": []})  # type: ignore[arg-type]


def test_resize_keeps_newest() -> None:
    t: Topic[int] = Topic("t", 5)
    for i in range(5):
        t.write(i)
    t.resize(2)
    assert [r.value for r in t.records_after(0)] == [3, 4]
    assert t.capacity == 2


def test_read_new_takes_the_same_records_as_read_new_records() -> None:
    """read_new's by-index path (none evicted) against read_new_records, through writes of
    one to many records between reads, evictions, clears and resizes."""
    rng = random.Random(5)
    topic: Topic[int] = Topic("t", 8)
    fast, ref = Reader(topic), Reader(topic)
    value = 0
    for step in range(3000):
        op = rng.random()
        if op < 0.02:
            topic.clear()
        elif op < 0.04:
            topic.resize(rng.randint(1, 12))
        else:
            for _ in range(rng.choice([0, 1, 1, 2, 2, 3, 5, 9, 20])):
                value += 1
                topic.write(value)
        if rng.random() < 0.7:
            got = fast.read_new()
            want = [r.value for r in ref.read_new_records()]
            assert got == want, step
            assert (fast.cursor, fast.missed) == (ref.cursor, ref.missed), step
    assert fast.missed > 0  # evictions happened and were counted
