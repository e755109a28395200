import pytest

from backend.referee.internal import InternalReferee, RefereeCommandError
from sslpb.ssl_gc_referee_message_pb2 import Referee


def test_message_is_a_complete_referee_packet() -> None:
    ref = InternalReferee()
    m = Referee.FromString(ref.encode(now_us=123))
    assert m.IsInitialized()
    assert m.command == Referee.HALT and m.packet_timestamp == 123
    assert m.source_identifier == ref.source_identifier


def test_stage_time_left_runs_like_the_game_controllers() -> None:
    """Sent in every message (the league's ssl-log-stats dereferences it): 0 before the game,
    then the half's 5 minutes counting down from the stage's start."""
    ref = InternalReferee()
    m = Referee.FromString(ref.encode(now_us=1_000_000))
    assert m.HasField("stage_time_left") and m.stage_time_left == 0
    ref.give("FORCE_START", now_us=2_000_000)
    assert Referee.FromString(ref.encode(now_us=2_000_000)).stage_time_left == 300_000_000
    assert Referee.FromString(ref.encode(now_us=12_000_000)).stage_time_left == 290_000_000


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


def test_cards_lower_the_robots_allowed_until_a_yellow_expires() -> None:
    from backend.referee.internal import YELLOW_CARD_US
    from backend.world.referee import decode_referee

    ref = InternalReferee()
    t0 = 1_000_000_000
    # before any card, max_allowed_bots is not sent (like an older game controller)
    assert not Referee.FromString(ref.encode(t0)).blue.HasField("max_allowed_bots")
    ref.card("blue", "yellow", now_us=t0)
    ref.card("blue", "red", now_us=t0 + 1_000_000)
    ref.card("blue", "yellow", now_us=t0 + 2_000_000)
    st = decode_referee(Referee.FromString(ref.encode(t0 + 10_000_000)))
    assert st.max_allowed_bots("blue") == 3 and st.max_allowed_bots("yellow") is None
    assert st.blue["yellow_cards"] == 2 and st.blue["red_cards"] == 1
    assert st.blue["yellow_card_times_s"] == [110.0, 112.0]
    # the first yellow ends: one robot back; the red stays for the game
    st = decode_referee(Referee.FromString(ref.encode(t0 + YELLOW_CARD_US + 500_000)))
    assert st.max_allowed_bots("blue") == 4
    st = decode_referee(Referee.FromString(ref.encode(t0 + 3 * YELLOW_CARD_US)))
    assert st.max_allowed_bots("blue") == 5 and st.blue["yellow_card_times_s"] == []
    assert st.blue["yellow_cards"] == 2  # cards given, as the game controller counts them
    ref.card("blue", "clear", now_us=t0 + 3 * YELLOW_CARD_US)
    st = decode_referee(Referee.FromString(ref.encode(t0 + 3 * YELLOW_CARD_US)))
    assert st.max_allowed_bots("blue") == 6 and st.blue["red_cards"] == 0


@pytest.mark.parametrize("team,card", [("green", "yellow"), ("blue", "blue")])
def test_bad_cards_are_refused(team: str, card: str) -> None:
    ref = InternalReferee()
    with pytest.raises(RefereeCommandError):
        ref.card(team, card)
    assert ref.blue.red_cards == ref.blue.yellow_cards == 0
