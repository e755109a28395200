"""The field (``domain.field``) as an SSL_GeometryFieldSize with lines and arcs.

Lines and arcs are generated the way ssl-vision names them: touch lines, goal lines, halfway
and centre line, penalty stretches and the centre circle. All lengths in mm.
"""

from __future__ import annotations

import math

from domain.field import Field, division
from sslpb import ssl_vision_geometry_pb2 as geom_pb

#: fieldsim's name for the domain's field
FieldGeometry = Field


def division_geometry(name: str) -> Field:
    """The default field of division "A" (12000x9000) or "B" (9000x6000)."""
    return division(name)


_T = geom_pb.SSL_FieldShapeType


def _line(
    fs: geom_pb.SSL_GeometryFieldSize,
    name: str,
    shape: int,
    x1: float,
    y1: float,
    x2: float,
    y2: float,
    thickness: float,
) -> None:
    line = fs.field_lines.add()
    line.name = name
    line.p1.x, line.p1.y = x1, y1
    line.p2.x, line.p2.y = x2, y2
    line.thickness = thickness
    line.type = shape  # type: ignore[assignment]


def field_size_message(g: FieldGeometry) -> geom_pb.SSL_GeometryFieldSize:
    """SSL_GeometryFieldSize with sizes, field_lines and field_arcs like ssl-vision's."""
    fs = geom_pb.SSL_GeometryFieldSize()
    fs.field_length = round(g.field_length)
    fs.field_width = round(g.field_width)
    fs.goal_width = round(g.goal_width)
    fs.goal_depth = round(g.goal_depth)
    fs.boundary_width = round(g.boundary_width)
    fs.penalty_area_depth = round(g.penalty_area_depth)
    fs.penalty_area_width = round(g.penalty_area_width)
    fs.center_circle_radius = round(g.center_circle_radius)
    # the game controller takes its penalty mark from here; without it, it keeps the default
    # of the division it started in (8 m in A: the mark 3.5 m into the wrong half of B)
    fs.goal_center_to_penalty_mark = round(g.penalty_mark_distance)
    fs.line_thickness = round(g.line_thickness)
    fs.goal_height = round(g.goal_height)
    fs.ball_radius = g.ball_radius
    fs.max_robot_radius = g.max_robot_radius

    hl, hw, t = g.half_length, g.half_width, float(g.line_thickness)
    ht = t / 2.0
    pd, phw = float(g.penalty_area_depth), g.penalty_area_width / 2.0
    _line(fs, "TopTouchLine", _T.TopTouchLine, -hl, hw - ht, hl, hw - ht, t)
    _line(fs, "BottomTouchLine", _T.BottomTouchLine, -hl, -hw + ht, hl, -hw + ht, t)
    _line(fs, "LeftGoalLine", _T.LeftGoalLine, -hl + ht, -hw, -hl + ht, hw, t)
    _line(fs, "RightGoalLine", _T.RightGoalLine, hl - ht, -hw, hl - ht, hw, t)
    _line(fs, "HalfwayLine", _T.HalfwayLine, 0.0, -hw, 0.0, hw, t)
    _line(fs, "CenterLine", _T.CenterLine, -hl, 0.0, hl, 0.0, t)
    _line(fs, "LeftPenaltyStretch", _T.LeftPenaltyStretch,
          -hl + pd - ht, -phw, -hl + pd - ht, phw, t)
    _line(fs, "RightPenaltyStretch", _T.RightPenaltyStretch,
          hl - pd + ht, -phw, hl - pd + ht, phw, t)
    _line(fs, "LeftFieldLeftPenaltyStretch", _T.LeftFieldLeftPenaltyStretch,
          -hl, -phw + ht, -hl + pd, -phw + ht, t)
    _line(fs, "LeftFieldRightPenaltyStretch", _T.LeftFieldRightPenaltyStretch,
          -hl, phw - ht, -hl + pd, phw - ht, t)
    _line(fs, "RightFieldLeftPenaltyStretch", _T.RightFieldLeftPenaltyStretch,
          hl, phw - ht, hl - pd, phw - ht, t)
    _line(fs, "RightFieldRightPenaltyStretch", _T.RightFieldRightPenaltyStretch,
          hl, -phw + ht, hl - pd, -phw + ht, t)

    arc = fs.field_arcs.add()
    arc.name = "CenterCircle"
    arc.center.x, arc.center.y = 0.0, 0.0
    arc.radius = g.center_circle_radius - ht
    arc.a1 = 0.0
    arc.a2 = 2.0 * math.pi
    arc.thickness = t
    arc.type = _T.CenterCircle
    return fs
