"""The referee commands are one list (domain.rules.RefereeCommand): the proto's enum, the
station's rule sets, the internal referee's buttons and the browser contract all follow it."""

from __future__ import annotations

import json

import pytest
from pydantic import ValidationError

from backend import contract
from backend.referee.internal import OPERATOR_COMMANDS
from domain import rules
from sslpb.ssl_gc_referee_message_pb2 import Referee


def test_the_commands_are_the_protos_enum_in_its_order() -> None:
    wire = [v.name for v in sorted(Referee.Command.DESCRIPTOR.values, key=lambda v: v.number)]
    assert list(rules.COMMANDS) == wire


@pytest.mark.parametrize("subset", ["STOPPED_COMMANDS", "SLOW_COMMANDS"])
def test_every_rule_set_names_commands_that_exist(subset: str) -> None:
    assert set(getattr(rules, subset)) <= set(rules.COMMANDS)


def test_the_operators_commands_exist() -> None:
    assert set(OPERATOR_COMMANDS) <= set(rules.COMMANDS)
    assert len(set(OPERATOR_COMMANDS)) == len(OPERATOR_COMMANDS)


def test_the_contract_takes_only_a_command_that_exists() -> None:
    assert contract.RefereeCommandIn(command="FORCE_START").command == "FORCE_START"
    with pytest.raises(ValidationError) as err:
        contract.RefereeCommandIn(command="DANCE")  # type: ignore[arg-type]
    assert err.value.errors()[0]["loc"] == ("command",)


def test_the_page_gets_the_commands_from_the_generated_contract() -> None:
    from scripts.gen_contract import render_ts

    ts = render_ts()
    line = next(ln for ln in ts.splitlines() if ln.startswith("export type RefereeCommand ="))
    names = json.loads("[" + line.split("=", 1)[1].rstrip(";").replace(" | ", ", ") + "]")
    assert names == list(rules.COMMANDS)


def test_the_team_apis_field_defaults_are_the_domains() -> None:
    # touchline/ imports nothing of the station (a team's tests run without it), so its
    # FieldSize keeps its own defaults: held here to division B and the rules' radii
    from domain.field import DIVISION_B
    from touchline.game import FieldSize

    f = FieldSize()
    assert (f.length, f.width, f.goal_width) == (
        DIVISION_B.field_length, DIVISION_B.field_width, DIVISION_B.goal_width)
    assert (f.goal_depth, f.boundary_width) == (DIVISION_B.goal_depth, DIVISION_B.boundary_width)
    assert (f.penalty_area_depth, f.penalty_area_width) == (
        DIVISION_B.penalty_area_depth, DIVISION_B.penalty_area_width)
    assert f.center_circle_radius == DIVISION_B.center_circle_radius
    assert (f.robot_radius, f.ball_radius) == (rules.ROBOT_RADIUS_MM, rules.BALL_RADIUS_MM)
