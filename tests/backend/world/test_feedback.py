"""The robot feedback decoder and tracker against hand-built bytes (tags from the field
numbers and wire types of ssl_simulation_robot_feedback.proto and grSim's Robots_Status)."""

from __future__ import annotations

import pytest

from backend.world.feedback import (
    NO_ANSWER_S,
    Answer,
    Decoded,
    Decoder,
    FeedbackTracker,
    decode,
)
from sslpb import touchline_pb2 as tl
from tests.wire import key, ld, uv, varint

BLUE, YELLOW = tl.TEAM_BLUE, tl.TEAM_YELLOW


def sim_feedback(rid: int, contact: bool | None) -> bytes:
    """RobotFeedback {1 id uint32 (varint), 2 dribbler_ball_contact bool (varint)}."""
    body = uv(1, rid)
    if contact is not None:
        body += uv(2, int(contact))
    return body


def grsim_status(rid: int, infrared: bool, flat: bool, chip: bool) -> bytes:
    """Robot_Status {1 robot_id int32, 2 infrared, 3 flat_kick, 4 chip_kick}, all varints."""
    return uv(1, rid) + uv(2, int(infrared)) + uv(3, int(flat)) + uv(4, int(chip))


def env(kind: int, team: int, payload: bytes, t_ns: int = 0,
        sent: list[tuple[int, int, int]] | None = None,
        sequence: int = 0) -> tl.RobotFeedbackEnvelope:
    return tl.RobotFeedbackEnvelope(
        kind=kind, team=team, receive_time_ns=t_ns, payload=payload,  # type: ignore[arg-type]
        sequence=sequence,
        sent=[tl.RobotSent(id=i, commands_sent=n, last_sent_time_ns=t) for i, n, t in
              sent or []])


def test_tags_are_the_field_numbers() -> None:
    assert key(1, 0) == b"\x08" and key(2, 0) == b"\x10" and key(2, 2) == b"\x12"
    assert ld(2, sim_feedback(3, True)) == b"\x12\x04\x08\x03\x10\x01"


def test_sim_response_decoded() -> None:
    # RobotControlResponse {1 errors SimulatorError {1 code string}, 2 feedback}
    payload = (ld(1, ld(1, b"E")) + ld(2, sim_feedback(0, True)) + ld(2, sim_feedback(5, False))
               + ld(2, sim_feedback(7, None)))
    dec = decode(env(tl.FEEDBACK_SIM_RESPONSE, BLUE, payload))
    assert dec == Decoded("blue", "sim", (Answer(0, True), Answer(5, False), Answer(7, None)))


def test_grsim_status_decoded() -> None:
    payload = ld(1, grsim_status(2, True, False, False)) + ld(1, grsim_status(4, False, True,
                                                                               False))
    payload += ld(1, grsim_status(6, False, False, True))
    dec = decode(env(tl.FEEDBACK_GRSIM_STATUS, YELLOW, payload))
    assert dec == Decoded("yellow", "grsim", (Answer(2, True, None), Answer(4, False, "flat"),
                                              Answer(6, False, "chip")))


@pytest.mark.parametrize(("kind", "payload", "reason"), [
    (tl.FEEDBACK_SIM_RESPONSE, ld(2, uv(2, 1)), "missing required field"),  # no id
    (tl.FEEDBACK_SIM_RESPONSE, b"\x12\x08\x08", "truncated"),
    (tl.FEEDBACK_SIM_RESPONSE, b"\x07\x01", "not protobuf"),  # wire type 7
    (tl.FEEDBACK_GRSIM_STATUS, ld(1, uv(1, 2) + uv(2, 1)), "missing required field"),
    (tl.FEEDBACK_GRSIM_STATUS, ld(1, uv(1, 2))[:-1], "truncated"),
    (tl.FEEDBACK_UNSPECIFIED, b"", "other"),
])
def test_bad_bytes_refused_by_reason(kind: int, payload: bytes, reason: str) -> None:
    dec = decode(env(kind, BLUE, payload))
    assert isinstance(dec, tuple) and dec[0] == reason


def test_negative_grsim_id_and_unknown_team_refused() -> None:
    neg = ld(1, key(1, 0) + varint((1 << 64) - 1) + uv(2, 0) + uv(3, 0) + uv(4, 0))
    assert decode(env(tl.FEEDBACK_GRSIM_STATUS, BLUE, neg)) == ("other", "robot id -1")
    assert isinstance(decode(env(tl.FEEDBACK_SIM_RESPONSE, 0, b"")), tuple)


def feed(tr: FeedbackTracker, e: tl.RobotFeedbackEnvelope, now: float) -> None:
    dec = decode(e)
    assert not isinstance(dec, tuple)
    tr.update(e, dec, now)


def test_round_trip_losses_and_no_answer() -> None:
    tr = FeedbackTracker()
    payload = ld(2, sim_feedback(0, True))
    t_ns = 1_000_000_000
    # 10 commands answered, each 2 ms after it was sent
    for k in range(10):
        tr.command("blue", 0, k * 0.01)
        sent_ns = t_ns + k * 10_000_000
        feed(tr, env(tl.FEEDBACK_SIM_RESPONSE, BLUE, payload, sent_ns + 2_000_000,
                     [(0, k + 1, sent_ns)]), k * 0.01)
    v = tr.view("blue", 0, 0.1)
    assert v is not None and v.transport == "sim" and v.ball_contact and not v.no_answer
    assert v.round_trip_ms == pytest.approx(2.0)
    assert (v.commands_sent, v.answers, v.loss) == (9, 9, 0.0)
    # 10 more commands, 5 answers: half lost
    for k in range(10, 20, 2):
        feed(tr, env(tl.FEEDBACK_SIM_RESPONSE, BLUE, payload, 0, [(0, k + 2, 0)]), k * 0.01)
    v = tr.view("blue", 0, 0.2)
    assert v is not None and v.loss == pytest.approx(1 - 14 / 19)
    # commanded on, no answer for more than 0.5 s: marked, contact not trusted
    tr.command("blue", 0, 0.9)
    v = tr.view("blue", 0, 0.18 + NO_ANSWER_S + 0.3)
    assert v is not None and v.no_answer and not v.ball_contact
    assert v.age_s == pytest.approx(NO_ANSWER_S + 0.3)
    # not commanded any more: no longer marked
    v = tr.view("blue", 0, 5.0)
    assert v is not None and not v.no_answer
    assert v.battery_v is None and v.kicker_v is None


def test_a_commanded_robot_that_never_answers_is_marked() -> None:
    tr = FeedbackTracker()
    feed(tr, env(tl.FEEDBACK_SIM_RESPONSE, BLUE, ld(2, sim_feedback(0, False)), 1, [(0, 1, 1),
                                                                                 (3, 1, 1)]),
         0.0)
    tr.command("blue", 3, 0.6)
    v = tr.view("blue", 3, 0.7)
    assert v is not None and v.no_answer and v.age_s is None


def test_grsim_kicks_and_contact_no_answer_never_marked() -> None:
    tr = FeedbackTracker()
    feed(tr, env(tl.FEEDBACK_GRSIM_STATUS, YELLOW,
                 ld(1, grsim_status(1, True, False, False))), 1.0)
    feed(tr, env(tl.FEEDBACK_GRSIM_STATUS, YELLOW,
                 ld(1, grsim_status(1, False, False, True))), 2.0)
    tr.command("yellow", 1, 10.0)
    v = tr.view("yellow", 1, 10.0)  # grSim answers only on a change: silence is no loss
    assert v is not None and v.transport == "grsim" and not v.no_answer
    assert not v.ball_contact and v.last_kick == "chip" and v.last_kick_age_s == 8.0
    assert v.round_trip_ms is None and v.loss is None and v.commands_sent is None
    assert tr.view("yellow", 2, 10.0) is None


def test_contact_is_said_only_by_robots_whose_answers_carry_it_and_only_while_fresh() -> None:
    tr = FeedbackTracker()
    payload = ld(2, sim_feedback(1, True)) + ld(2, sim_feedback(2, None))
    e = env(tl.FEEDBACK_SIM_RESPONSE, BLUE, payload)
    tr.update(e, decode(e), 10.0)
    says = tr.view("blue", 1, 10.05)
    silent = tr.view("blue", 2, 10.05)
    assert says is not None and silent is not None
    assert says.contact(0.2) is True
    assert silent.contact(0.2) is None  # its answers never carry contact: not "no ball"
    old = tr.view("blue", 1, 10.5)
    assert old is not None and old.contact(0.2) is None  # no answer lately: not said now


def test_decoder_parses_a_payload_only_when_it_changed() -> None:
    dec = Decoder()
    a, b = ld(2, sim_feedback(0, True)), ld(2, sim_feedback(0, False))
    first = dec(env(tl.FEEDBACK_SIM_RESPONSE, BLUE, a))
    assert first == decode(env(tl.FEEDBACK_SIM_RESPONSE, BLUE, a))
    assert dec(env(tl.FEEDBACK_SIM_RESPONSE, BLUE, a)) is first  # the same bytes: not parsed
    other = dec(env(tl.FEEDBACK_SIM_RESPONSE, YELLOW, a))  # another stream: its own
    assert other is not first and other == Decoded("yellow", "sim", (Answer(0, True),))
    changed = dec(env(tl.FEEDBACK_SIM_RESPONSE, BLUE, b))
    assert changed == Decoded("blue", "sim", (Answer(0, False),))
    bad = b"\x12\x08\x08"
    assert dec(env(tl.FEEDBACK_SIM_RESPONSE, BLUE, bad))[0] == "truncated"  # type: ignore[index]
    assert dec(env(tl.FEEDBACK_SIM_RESPONSE, BLUE, b)) is changed  # a bad one is not kept
    dec.clear()
    assert dec(env(tl.FEEDBACK_SIM_RESPONSE, BLUE, b)) is not changed


def test_coalesced_answers_counted_from_the_sequence() -> None:
    """The relay forwards a run of identical answers as one envelope: the sequence says how
    many answers it stands for, so nothing answered looks lost."""
    tr = FeedbackTracker()
    payload = ld(2, sim_feedback(0, True))
    # 30 commands, each answered; forwarded as envelopes at answers 1, 10, 20, 30
    for k, seq in enumerate((1, 10, 20, 30)):
        feed(tr, env(tl.FEEDBACK_SIM_RESPONSE, BLUE, payload, 0, [(0, seq, 0)], seq), k * 0.1)
    v = tr.view("blue", 0, 0.3)
    assert v is not None and (v.commands_sent, v.answers, v.loss) == (29, 29, 0.0)
    # robot 1 was sent 10 more, but is not in the answers: all lost
    feed(tr, env(tl.FEEDBACK_SIM_RESPONSE, BLUE, payload, 0, [(0, 40, 0), (1, 10, 0)], 40), 0.4)
    feed(tr, env(tl.FEEDBACK_SIM_RESPONSE, BLUE, payload, 0, [(0, 50, 0), (1, 20, 0)], 50), 0.5)
    one = tr.view("blue", 1, 0.5)
    assert one is not None and (one.commands_sent, one.answers, one.loss) == (10, 0, 1.0)
    # a restarted relay counts from 1 again: one answer, not a negative count
    feed(tr, env(tl.FEEDBACK_SIM_RESPONSE, BLUE, payload, 0, [(0, 51, 0)], 1), 0.6)
    v = tr.view("blue", 0, 0.6)
    assert v is not None and v.answers == 50 and v.loss == 0.0
