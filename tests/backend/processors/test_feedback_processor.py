"""The relay's "feedback" topic through the relay ingest and the feedback processor onto the
robot-feedback topic the strategy and the world view read."""

from __future__ import annotations

from backend import topics
from backend.bus import DataBus
from backend.control.goto import LocalVelocity
from backend.messages import Command, CommandSet
from backend.processors import FeedbackProcessor, RelayIngest
from backend.processors.strategy import StrategyProcessor
from sslpb import ssl_simulation_robot_feedback_pb2 as fb_pb
from sslpb import touchline_pb2 as tl


def answer(contact: bool) -> bytes:
    r = fb_pb.RobotControlResponse()
    r.feedback.add(id=4, dribbler_ball_contact=contact)
    return tl.RobotFeedbackEnvelope(
        kind=tl.FEEDBACK_SIM_RESPONSE, team=tl.TEAM_YELLOW, receive_time_ns=2_000_000,
        payload=r.SerializeToString(),
        sent=[tl.RobotSent(id=4, commands_sent=1, last_sent_time_ns=1_000_000)],
    ).SerializeToString()


async def test_feedback_through_ingest_and_processor() -> None:
    bus = DataBus({}, check_types=True)
    ingest = RelayIngest(bus)
    proc = FeedbackProcessor(bus)
    strategy = StrategyProcessor(bus, "yellow")
    bus.of(topics.ROBOT_COMMANDS).write(CommandSet(0, 0, (
        Command("yellow", 4, LocalVelocity(0.0, 0.0, 0.0)),)))
    ingest._handle([b"feedback", answer(True)])
    ingest._handle([b"feedback", b"\xff\xff"])  # not an envelope: counted by the ingest
    ingest._handle([b"feedback", tl.RobotFeedbackEnvelope(
        kind=tl.FEEDBACK_SIM_RESPONSE, team=tl.TEAM_YELLOW, payload=b"\x12\x01").
        SerializeToString()])  # a cut-short answer: counted by the processor
    await proc.tick()
    views = bus.of(topics.ROBOT_FEEDBACK).latest_value()
    assert views is not None
    v = views[("yellow", 4)]
    assert v.ball_contact and v.transport == "sim" and not v.no_answer
    assert v.round_trip_ms == 1.0
    assert strategy.ball_contact("yellow", 4) and not strategy.ball_contact("blue", 4)
    assert ingest.counters["zmq"].errors == 1
    assert proc.counter.by_reason == {"truncated": 1}
    # in replay nothing answers for the station: live answers are not used
    ingest.live = lambda: False
    ingest._handle([b"feedback", answer(False)])
    await proc.tick()
    assert bus.of(topics.ROBOT_FEEDBACK).latest_value()[("yellow", 4)].ball_contact  # type: ignore[index]
