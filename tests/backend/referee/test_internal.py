import pytest

from backend.referee.internal import InternalReferee, RefereeCommandError
from sslpb.ssl_gc_referee_message_pb2 import Referee


def test_message_is_a_complete_referee_packet() -> None:
    ref = InternalReferee()
    m = Referee.FromString(ref.encode(now_us=123))
    assert m.IsInitialized()
    assert m.command == Referee.HALT and m.packet_timestamp == 123
    assert m.source_identifier == ref.source_identifier


def test_commands_count_and_carry_their_position() -> None:
    ref = InternalReferee()
    ref.give("STOP")
    ref.give("BALL_PLACEMENT_BLUE", (1000.0, -500.0))
    m = Referee.FromString(ref.encode())
    assert m.command == Referee.BALL_PLACEMENT_BLUE and m.command_counter == 2
    assert (m.designated_position.x, m.designated_position.y) == (1000.0, -500.0)
    ref.give("STOP")
    assert not Referee.FromString(ref.encode()).HasField("designated_position")


def test_kickoff_sequence_moves_the_stage() -> None:
    ref = InternalReferee()
    ref.give("PREPARE_KICKOFF_YELLOW")
    ref.give("NORMAL_START")
    assert ref.stage == "NORMAL_FIRST_HALF"


@pytest.mark.parametrize("cmd,pos", [("GO", None), ("BALL_PLACEMENT_YELLOW", None),
                                     ("NORMAL_START", None)])
def test_bad_commands_are_refused_and_change_nothing(cmd: str, pos: None) -> None:
    ref = InternalReferee()
    with pytest.raises(RefereeCommandError):
        ref.give(cmd, pos)
    assert ref.command == "HALT" and ref.command_counter == 0


def test_goal_counts_and_stops() -> None:
    ref = InternalReferee()
    ref.give("FORCE_START")
    ref.goal("yellow")
    m = Referee.FromString(ref.encode())
    assert m.yellow.score == 1 and m.command == Referee.STOP
