"""sslnet.streams: the reasons a datagram is refused, and the one stream counter."""

from __future__ import annotations

from hypothesis import given
from hypothesis import strategies as st

from sslnet.streams import NOT_PROTOBUF, TRUNCATED, StreamCounter, wire_problem
from sslpb.ssl_vision_wrapper_pb2 import SSL_WrapperPacket


def _wrapper() -> bytes:
    p = SSL_WrapperPacket()
    d = p.detection
    d.frame_number, d.t_capture, d.t_sent, d.camera_id = 1, 1.5, 1.5, 0
    r = d.robots_blue.add()
    r.confidence, r.robot_id, r.x, r.y, r.pixel_x, r.pixel_y = 1.0, 3, 10.0, 20.0, 0.0, 0.0
    return p.SerializeToString()


@given(st.integers(1, 200))
def test_a_datagram_cut_short_is_truncated(cut: int) -> None:
    data = _wrapper()
    assert wire_problem(data[: min(cut, len(data) - 1)]) == TRUNCATED


def test_garbage_is_not_protobuf() -> None:
    assert wire_problem(b"\x07\x00") == NOT_PROTOBUF  # field 0
    assert wire_problem(b"\x0f\x01") == NOT_PROTOBUF  # wire type 7
    assert wire_problem(b"\xff" * 11) == NOT_PROTOBUF  # a varint longer than 64 bits


def test_the_counter_keeps_every_reason_not_only_the_last() -> None:
    c = StreamCounter("vision")
    c.packet(100)
    c.error(TRUNCATED, "cut at 40 bytes")
    c.error(TRUNCATED)
    c.error("time out of range", "camera 0", n=3)
    d = c.to_dict()
    assert d["errors"] == 5 and d["packets"] == 1
    assert d["errors_by_reason"] == {"time out of range": 3, "truncated": 2}
    assert d["last_error"] == "time out of range: camera 0"


def test_rate_counter_is_exact_when_read_and_keeps_at_most_two_windows() -> None:
    """``add`` trims in bulk (it runs hundreds of times a second per stream); the rate read
    still counts exactly the events of the last window, and memory stays bounded."""
    from sslnet.rate import RateCounter

    rc = RateCounter(window_s=1.0)
    for k in range(3000):  # 1000 events a second for 3 s
        rc.add(k / 1000.0)
        assert len(rc._times) <= 2001
    assert rc.total == 3000
    assert rc.rate_hz(2.9995) == 1000.0  # the events at 2.000 .. 2.999 s
    assert rc.rate_hz(3.5) == 500.0


def test_rate_counter_add_many_is_add_repeated() -> None:
    """``add_many(n, t)`` (a reader's batch counted once) reads the same as ``add(t)`` n times:
    total, rate, the last time and the trimming of old events."""
    from sslnet.rate import RateCounter

    one, many = RateCounter(window_s=1.0), RateCounter(window_s=1.0)
    for k in range(400):
        t = k / 100.0
        n = k % 4  # 0..3 events a batch
        for _ in range(n):
            one.add(t)
        many.add_many(n, t)
        assert (many.total, many.last_time) == (one.total, one.last_time)
        assert len(many._times) == len(one._times)
    assert many.rate_hz(4.2) == one.rate_hz(4.2) > 0
    assert many.age_s(4.5) == one.age_s(4.5)


def test_count_rate_is_computed_when_read_from_the_counts_of_earlier_reads() -> None:
    """``CountRate``: counting is an integer add; the rate read is the count since the
    newest earlier read at least a window old, over that time (the start before any)."""
    from sslnet.rate import CountRate

    cr = CountRate(window_s=1.0, now=0.0)
    assert cr.rate_hz(0.0) == 0.0  # nothing counted, no time passed
    for k in range(1, 3001):  # 1000 events a second for 3 s, read every 0.25 s
        cr.total += 1
        if k % 250 == 0:
            assert cr.rate_hz(k / 1000.0) == 1000.0
    assert len(cr._marks) <= 10  # a few marks a window, not one per read
    cr.add(500)  # 500 more in the next second
    assert cr.rate_hz(4.0) == 500.0  # the marks at 3.0 s: 500 events in 1 s
    assert cr.rate_hz(14.0) == 0.0  # read long after: the mean since the last read
    assert cr.total == 3500
