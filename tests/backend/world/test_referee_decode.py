"""Decoding the game controller's Referee message into RefereeState: the fields a real
ssl-game-controller sends beyond the basics (next command, status message, cards and the
number of robots allowed, game events), and what an older controller leaves out."""

from __future__ import annotations

from backend.world.referee import MAX_GAME_EVENTS, decode_referee
from sslpb.ssl_gc_common_pb2 import Team
from sslpb.ssl_gc_game_event_pb2 import GameEvent
from sslpb.ssl_gc_referee_message_pb2 import MatchType, Referee


def _team(msg: Referee.TeamInfo, name: str) -> None:
    msg.name = name
    msg.score = 0
    msg.red_cards = 0
    msg.yellow_cards = 0
    msg.timeouts = 4
    msg.timeout_time = 300_000_000
    msg.goalkeeper = 0


def _minimal() -> Referee:
    m = Referee(packet_timestamp=1, stage=Referee.NORMAL_FIRST_HALF, command=Referee.STOP,
                command_counter=3, command_timestamp=1)
    _team(m.blue, "B")
    _team(m.yellow, "Y")
    return m


def test_an_old_controller_leaves_the_optional_fields_unknown() -> None:
    st = decode_referee(Referee.FromString(_minimal().SerializeToString()))
    assert st.next_command is None and st.match_type is None
    assert st.status_message == "" and st.game_events == ()
    assert st.current_action_time_remaining_s is None
    assert st.blue["max_allowed_bots"] is None and st.max_allowed_bots("blue") is None
    assert st.yellow["can_place_ball"] is None
    assert st.blue["timeout_time_s"] == 300.0


def test_cards_next_command_status_and_events_are_carried() -> None:
    m = _minimal()
    m.next_command = Referee.DIRECT_FREE_YELLOW
    m.status_message = "Ball placement failed"
    m.match_type = MatchType.GROUP_PHASE
    m.current_action_time_remaining = 12_500_000
    m.blue.yellow_cards = 1
    m.blue.yellow_card_times.append(119_000_000)
    m.blue.max_allowed_bots = 5
    m.blue.can_place_ball = False
    m.blue.bot_substitution_intent = True
    m.yellow.max_allowed_bots = 6
    for k in range(MAX_GAME_EVENTS + 3):
        ev = m.game_events.add(id=f"e{k}", type=GameEvent.BALL_LEFT_FIELD_TOUCH_LINE,
                               created_timestamp=1_000_000 * k)
        ev.ball_left_field_touch_line.by_team = Team.YELLOW if k % 2 else Team.BLUE
        ev.origin.append("TIGERs AutoRef")
    st = decode_referee(Referee.FromString(m.SerializeToString()))
    assert st.next_command == "DIRECT_FREE_YELLOW"
    assert st.status_message == "Ball placement failed"
    assert st.match_type == "GROUP_PHASE"
    assert st.current_action_time_remaining_s == 12.5
    assert st.max_allowed_bots("blue") == 5 and st.max_allowed_bots("yellow") == 6
    assert st.blue["can_place_ball"] is False and st.blue["bot_substitution_intent"] is True
    assert st.blue["yellow_card_times_s"] == [119.0]
    # the newest events first, at most MAX_GAME_EVENTS of them
    assert len(st.game_events) == MAX_GAME_EVENTS
    newest = MAX_GAME_EVENTS + 2
    assert st.game_events[0] == {"id": f"e{newest}", "type": "BALL_LEFT_FIELD_TOUCH_LINE",
                                 "by_team": "BLUE", "origin": ["TIGERs AutoRef"],
                                 "created_s": float(newest)}
    assert st.game_events[1]["by_team"] == "YELLOW"
    d = st.to_dict(0.0)
    assert d["next_command"] == "DIRECT_FREE_YELLOW" and len(d["game_events"]) == MAX_GAME_EVENTS


def test_an_event_type_newer_than_our_proto_is_kept_as_unknown() -> None:
    """proto2 keeps an enum value it does not know as an unknown field: the event is still
    listed (id kept), its type reads UNKNOWN, and decoding goes on."""
    m = _minimal()
    ev = GameEvent(id="x")
    raw = m.SerializeToString()
    # field 16 (game_events), an embedded GameEvent with type (field 40) = 999
    body = ev.SerializeToString() + bytes([0xC0, 0x02]) + bytes([0xE7, 0x07])
    raw += bytes([0x82, 0x01, len(body)]) + body
    st = decode_referee(Referee.FromString(raw))
    assert st.game_events == ({"id": "x", "type": "UNKNOWN", "by_team": None, "origin": [],
                               "created_s": None},)
    assert st.command == "STOP"
