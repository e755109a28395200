from backend.bus import DataBus, Reader, Topic


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


def test_bus_sizes_come_from_configuration() -> None:
    bus = DataBus({"vision-detections": 30, "robot-commands": 20}, default_size=7)
    assert bus.topic("vision-detections").capacity == 30
    assert bus.topic("robot-commands").capacity == 20
    assert bus.topic("other").capacity == 7
    assert bus.topic("vision-detections") is bus.topic("vision-detections")


def test_resize_keeps_newest() -> None:
    t: Topic[int] = Topic("t", 5)
    for i in range(5):
        t.write(i)
    t.resize(2)
    assert [r.value for r in t.records_after(0)] == [3, 4]
    assert t.capacity == 2
