"""The internal referee's processor on a bus: the robots allowed follow the field's division
before any card, and the reason it stepped aside names the game controller heard last (found
by hand against grSim and the ssl-game-controller: 6 robots shown on a 12 m field, and the
reason kept the first GC's id after a second one came)."""

from __future__ import annotations

from backend import topics
from backend.bus import DataBus
from backend.processors.internal_referee import InternalRefereeProcessor
from backend.referee.internal import InternalReferee
from backend.world.referee import RefereeState


def _gc(source: str) -> RefereeState:
    return RefereeState(command="STOP", stage="NORMAL_FIRST_HALF", command_counter=1,
                        stage_time_left_s=None, blue={}, yellow={}, designated_position=None,
                        blue_team_on_positive_half=None, packet_timestamp_us=0,
                        source_identifier=source)


async def test_the_robots_allowed_follow_the_field() -> None:
    bus = DataBus({})
    ref = InternalReferee()
    p = InternalRefereeProcessor(bus, ref)
    await p.tick()
    assert ref.max_allowed_bots("blue") == 6  # no geometry yet: division B
    bus.of(topics.GEOMETRY).write({"field_length": 12000.0, "field_width": 9000.0})
    await p.tick()
    assert ref.max_allowed_bots("blue") == ref.max_allowed_bots("yellow") == 11
    bus.of(topics.GEOMETRY).write({"field_length": 9000.0, "field_width": 6000.0})
    await p.tick()
    assert ref.max_allowed_bots("yellow") == 6


async def test_the_reason_names_the_game_controller_heard_last() -> None:
    bus = DataBus({})
    p = InternalRefereeProcessor(bus, InternalReferee())
    p.enable(True)
    bus.of(topics.REFEREE).write(_gc("gc-1"))
    await p.tick()
    assert not p.enabled and p.disabled_reason.endswith("(gc-1)")
    bus.of(topics.REFEREE).write(_gc("gc-2"))
    await p.tick()
    assert p.disabled_reason == "switched off: a game controller is active (gc-2)"
    # an operator's own reason is not overwritten
    p.disabled_reason = "switched off by the operator"
    bus.of(topics.REFEREE).write(_gc("gc-3"))
    await p.tick()
    assert p.disabled_reason == "switched off by the operator"
