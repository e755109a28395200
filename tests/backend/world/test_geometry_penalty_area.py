"""The defence area and the penalty mark of a geometry packet that does not say them: grSim
sends the field lines only (its 12 x 9 m field came out with division B's 1 x 2 m defence
area and 6 m penalty mark, found by hand against grSim)."""

from __future__ import annotations

import pytest

from backend.world.decode import geometry_to_dict
from domain.field import DIVISION_A, DIVISION_B, Field
from fieldsim.geometry import division_geometry, field_size_message
from sslpb.ssl_vision_geometry_pb2 import SSL_GeometryData


def _without_sizes(name: str) -> SSL_GeometryData:
    """fieldsim's packet of the division, its lines as ssl-vision draws them, the defence
    area's sizes and the penalty mark left out."""
    geo = SSL_GeometryData()
    geo.field.CopyFrom(field_size_message(division_geometry(name)))
    for f in ("penalty_area_depth", "penalty_area_width", "goal_center_to_penalty_mark"):
        geo.field.ClearField(f)  # type: ignore[arg-type]
    return geo


def _grsim_like() -> SSL_GeometryData:
    """Division A's field as grSim sends it: sizes without the defence area or the penalty
    mark, each line's centre half its thickness outside the area (LeftPenaltyStretch at
    x = -4195 from y = -1800 to 1800)."""
    geo = SSL_GeometryData()
    f = geo.field
    f.field_length, f.field_width, f.goal_width, f.goal_depth, f.boundary_width = (
        12000, 9000, 1800, 180, 300)
    for name, x1, y1, x2, y2 in (
            ("TopTouchLine", -6000, 4495, 6000, 4495),
            ("LeftPenaltyStretch", -4195, -1800, -4195, 1800),
            ("RightPenaltyStretch", 4195, -1800, 4195, 1800),
            ("LeftFieldLeftPenaltyStretch", -6000, -1805, -4195, -1805)):
        ln = f.field_lines.add()
        ln.name, ln.thickness = name, 10
        ln.p1.x, ln.p1.y, ln.p2.x, ln.p2.y = x1, y1, x2, y2
    return geo


@pytest.mark.parametrize("name, field", [("A", DIVISION_A), ("B", DIVISION_B)])
def test_the_defence_area_is_read_off_the_lines_of_ssl_vision(name: str, field: Field) -> None:
    g = geometry_to_dict(_without_sizes(name))
    assert (g["penalty_area_depth"], g["penalty_area_width"]) == (
        field.penalty_area_depth, field.penalty_area_width)
    assert g["goal_center_to_penalty_mark"] == 0
    assert Field.from_geometry(g) == field  # the penalty mark: the division's, by the size


def test_grsim_geometry_gives_division_a_sizes() -> None:
    g = geometry_to_dict(_grsim_like())
    assert (g["penalty_area_depth"], g["penalty_area_width"]) == (1800, 3600)
    f = Field.from_geometry(g)
    assert (f.penalty_area_depth, f.penalty_area_width) == (1800, 3600)
    assert f.penalty_mark_distance == 8000
    assert f.defense_rect(-1) == (-6000, -4200, -1800, 1800)
    assert f.penalty_mark(-1) == (2000, 0)


def test_sizes_sent_win_over_the_lines_and_the_division() -> None:
    geo = _grsim_like()
    geo.field.penalty_area_depth, geo.field.penalty_area_width = 1500, 3000
    geo.field.goal_center_to_penalty_mark = 7000
    g = geometry_to_dict(geo)
    assert (g["penalty_area_depth"], g["penalty_area_width"]) == (1500, 3000)
    f = Field.from_geometry(g)
    assert (f.penalty_area_depth, f.penalty_area_width, f.penalty_mark_distance) == (
        1500, 3000, 7000)


def test_no_lines_and_no_sizes_leave_the_division_default() -> None:
    geo = SSL_GeometryData()
    geo.field.field_length, geo.field.field_width = 12000, 9000
    geo.field.goal_width, geo.field.goal_depth, geo.field.boundary_width = 1800, 180, 300
    g = geometry_to_dict(geo)
    assert (g["penalty_area_depth"], g["penalty_area_width"]) == (0, 0)
    f = Field.from_geometry(g)
    assert (f.penalty_area_depth, f.penalty_area_width, f.penalty_mark_distance) == (
        1800, 3600, 8000)
    # a line that does not fit the field is not believed
    ln = geo.field.field_lines.add()
    ln.name, ln.thickness = "LeftPenaltyStretch", 10
    ln.p1.x, ln.p1.y, ln.p2.x, ln.p2.y = -9000, -1000, -9000, 1000
    assert geometry_to_dict(geo)["penalty_area_depth"] == 0
