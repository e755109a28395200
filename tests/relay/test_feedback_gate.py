"""The relay's feedback forwarding rule (larcmacs_relay/feedback.py), without sockets."""

from __future__ import annotations

from larcmacs_relay.feedback import FeedbackGate, HeldAnswer
from sslpb import touchline_pb2

SIM, BLUE = touchline_pb2.FEEDBACK_SIM_RESPONSE, touchline_pb2.TEAM_BLUE
ADDR = ("127.0.0.1", 10301)


def offer(g: FeedbackGate, data: bytes, now: float) -> str:
    """What the relay does with one answer: "forward", "flush+forward" (the held one first)
    or "hold"."""
    if g.arrive(data, now):
        flushed = g.held is not None and g.held.data != data
        g.forwarded(data, now)
        return "flush+forward" if flushed else "forward"
    g.hold(HeldAnswer(data, ADDR, 0, g.answers, {}))
    return "hold"


def test_repeats_held_a_change_at_once_the_held_ones_first() -> None:
    g = FeedbackGate(SIM, BLUE, 0.02)
    assert offer(g, b"a", 0.0) == "forward"  # the first one
    assert offer(g, b"a", 0.005) == "hold"
    assert offer(g, b"a", 0.010) == "hold"
    assert g.held is not None and g.held.sequence == 3  # only the latest is kept
    assert g.flush_at == 0.04  # by itself: two intervals after the last forward
    # contact changed: at once, after the held "a" (which stands for answers 2 and 3)
    assert offer(g, b"b", 0.011) == "flush+forward"
    assert g.answers == 4 and g.held is None and g.last_forward == 0.011
    assert offer(g, b"b", 0.012) == "hold"
    # the same bytes once the interval has passed: forwarded, the held one superseded (its
    # count is in the newer one's sequence)
    assert offer(g, b"b", 0.031) == "forward"
    assert g.held is None and g.answers == 6


def test_interval_zero_forwards_every_answer() -> None:
    g = FeedbackGate(touchline_pb2.FEEDBACK_GRSIM_STATUS, BLUE, 0.0)
    assert [offer(g, b"s", t) for t in (0.0, 0.0, 0.001)] == ["forward"] * 3
    assert g.answers == 3
