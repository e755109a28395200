"""Every Data Bus topic, declared once: its name, the type of its records, its capacity and
what it carries. Processors and the station get their topics with ``bus.of(topics.X)``;
``DataBus(check_types=True)`` (every test run: ``TOUCHLINE_CHECK_TOPICS=1``) refuses a record
of another type. Capacities: the ones here, unless the ``bus`` parameter group sets one (the
Health tab shows every topic's size and capacity)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Generic, TypeVar

from sslpb import touchline_pb2 as tl

from .messages import CommandSet, OperatorTarget
from .world.referee import RefereeState
from .world.state import CameraFrame, WorldState

T = TypeVar("T")


@dataclass(frozen=True)
class TopicSpec(Generic[T]):
    name: str
    type: type[Any]  # what every record is an instance of (checked with check_types)
    capacity: int
    what: str


VISION_PACKETS = TopicSpec[tl.Envelope]("vision-packets", tl.Envelope, 64,
                                        "raw vision datagrams from the relay")
#: what robots or a simulator answered (RobotControlResponse, grSim Robots_Status), unchanged
FEEDBACK_PACKETS = TopicSpec[tl.RobotFeedbackEnvelope](
    "feedback-packets", tl.RobotFeedbackEnvelope, 64,
    "raw robot / simulator answers from the relay")
#: {(team, id): backend.world.feedback.RobotFeedbackView}, what each robot reports back
ROBOT_FEEDBACK = TopicSpec[dict[Any, Any]]("robot-feedback", dict, 10,
                                           "per robot: ball contact, kicks, answers")
REFEREE_PACKETS = TopicSpec[tl.Envelope]("referee-packets", tl.Envelope, 30,
                                         "raw referee datagrams from the relay")
RELAY_STATS = TopicSpec[dict[str, Any]]("relay-stats", dict, 10,
                                        "the relay's statistics, once a second")
VISION_DETECTIONS = TopicSpec[CameraFrame]("vision-detections", CameraFrame, 64,
                                           "decoded camera frames")
GEOMETRY = TopicSpec[dict[str, Any]]("geometry", dict, 4,
                                     "the field from the geometry packet, on a change")
REFEREE = TopicSpec[RefereeState]("referee", RefereeState, 30, "decoded referee states")
WORLD = TopicSpec[WorldState]("world", WorldState, 30, "the world model's states")
OPERATOR_TARGETS = TopicSpec[OperatorTarget]("operator-targets", OperatorTarget, 30,
                                             "targets set or cleared by an operator")
#: the strategy's targets: {(team, id): TargetEntry}
TARGETS = TopicSpec[dict[Any, Any]]("targets", dict, 10, "the strategy's targets per robot")
ROBOT_COMMANDS = TopicSpec[CommandSet]("robot-commands", CommandSet, 20,
                                       "the control loop's command sets")
SIM_COMMANDS = TopicSpec[bytes]("sim-commands", bytes, 20,
                                "SimulatorCommand bytes (teleports) for the relay")
REFEREE_OUT = TopicSpec[bytes]("referee-out", bytes, 30,
                               "the internal referee's Referee bytes for the relay")
ESTOP = TopicSpec[bool]("estop", bool, 10, "the emergency stop (True: every robot stops)")
PARAMS = TopicSpec[int]("params", int, 4, "the parameter version applied")

ALL: tuple[TopicSpec[Any], ...] = (
    VISION_PACKETS, REFEREE_PACKETS, RELAY_STATS, VISION_DETECTIONS, GEOMETRY, REFEREE, WORLD,
    OPERATOR_TARGETS, TARGETS, ROBOT_COMMANDS, SIM_COMMANDS, REFEREE_OUT, ESTOP, PARAMS,
    FEEDBACK_PACKETS, ROBOT_FEEDBACK,
)
