"""Decoding of SSL-Vision wrapper packets into plain data (no I/O)."""

from __future__ import annotations

import math
from typing import Any

from domain.rules import BALL_RADIUS_MM, ROBOT_RADIUS_MM
from sslpb.ssl_vision_detection_pb2 import SSL_DetectionFrame
from sslpb.ssl_vision_geometry_pb2 import SSL_GeometryData

from .referee import wire_str
from .state import CameraFrame, RawBall, RawRobot, Team

_tuple_new = tuple.__new__


def _finite(*vals: float) -> bool:
    return all(math.isfinite(v) for v in vals)


def decode_detection(frame: SSL_DetectionFrame, receive_time_ns: int) -> CameraFrame:
    """Plain copy of a detection frame. Robots without an id and non-finite values are dropped.

    Each protobuf field is read once (an attribute read of a message is a call into the
    protobuf runtime: 600 frames a second at 8 cameras x 75 Hz); a detection is a tuple
    built in one call (``RawRobot``, ``RawBall``: NamedTuples, without their ``__new__``'s
    Python frame). ``v - v`` is 0.0 for a finite ``v`` and NaN (true) for an infinite or NaN
    one: ``math.isfinite`` without a call."""
    robots: list[RawRobot] = []
    new = _tuple_new
    team: Team
    for team, dets in (("yellow", frame.robots_yellow), ("blue", frame.robots_blue)):
        for d in dets:
            rid = d.robot_id  # 0 when not sent (proto2): only a 0 asks whether it was
            if not rid and not d.HasField("robot_id"):
                continue
            x, y = d.x, d.y
            if rid > 15 or x - x or y - y:
                continue
            ori = d.orientation  # 0.0 when not sent (proto2, no default)
            if ori - ori:
                ori = 0.0
            robots.append(new(RawRobot, (team, rid, x, y, ori, d.confidence)))
    balls: list[RawBall] = []
    for b in frame.balls:
        x, y = b.x, b.y
        if not (x - x or y - y):
            balls.append(new(RawBall, (x, y, b.confidence)))
    return CameraFrame(frame.camera_id, frame.frame_number, frame.t_capture, frame.t_sent,
                       receive_time_ns, tuple(balls), tuple(robots))


def geometry_to_dict(geo: SSL_GeometryData, bad: list[str] | None = None) -> dict[str, Any]:
    """The field part of a geometry packet as the JSON the browser draws from (mm, rad).

    Cleaned at the edge: names are valid UTF-8 (decoded with replacement, and named in
    ``bad``), a line or arc with a non-finite number is left out, a non-finite or non-positive
    radius takes its default; so nothing that cannot be JSON reaches the page or the API."""
    f = geo.field
    lines = [
        {
            "name": wire_str(ln.name, bad, "field line name"),
            "p1": {"x": ln.p1.x, "y": ln.p1.y},
            "p2": {"x": ln.p2.x, "y": ln.p2.y},
            "thickness": ln.thickness,
        }
        for ln in f.field_lines
        if _finite(ln.p1.x, ln.p1.y, ln.p2.x, ln.p2.y, ln.thickness)
    ]
    arcs = [
        {
            "name": wire_str(a.name, bad, "field arc name"),
            "center": {"x": a.center.x, "y": a.center.y},
            "radius": a.radius,
            "a1": a.a1,
            "a2": a.a2,
            "thickness": a.thickness,
        }
        for a in f.field_arcs
        if _finite(a.center.x, a.center.y, a.radius, a.a1, a.a2, a.thickness)
    ]

    def positive(has: bool, value: float, default: float) -> float:
        return value if has and math.isfinite(value) and value > 0 else default

    depth, width = _penalty_area(f, lines)
    return {
        "field_length": f.field_length,
        "field_width": f.field_width,
        "goal_width": f.goal_width,
        "goal_depth": f.goal_depth,
        "boundary_width": f.boundary_width,
        "penalty_area_depth": depth,
        "penalty_area_width": width,
        "goal_center_to_penalty_mark": (
            f.goal_center_to_penalty_mark if f.HasField("goal_center_to_penalty_mark")
            and f.goal_center_to_penalty_mark > 0 else 0),
        "center_circle_radius": (
            f.center_circle_radius if f.HasField("center_circle_radius") else 500
        ),
        "ball_radius": positive(f.HasField("ball_radius"), f.ball_radius, BALL_RADIUS_MM),
        "max_robot_radius": positive(f.HasField("max_robot_radius"), f.max_robot_radius,
                                     ROBOT_RADIUS_MM),
        "lines": lines,
        "arcs": arcs,
        "cameras": camera_poses(geo),
    }


#: The defence area's sides among ssl-vision's line names: the line parallel to the goal
#: line (its x says the depth) and the ones along the touch lines (their y says the width)
_STRETCH = ("LeftPenaltyStretch", "RightPenaltyStretch")
_STRETCH_SIDES = ("LeftFieldLeftPenaltyStretch", "LeftFieldRightPenaltyStretch",
                  "RightFieldLeftPenaltyStretch", "RightFieldRightPenaltyStretch")


def _penalty_area(f: Any, lines: list[dict[str, Any]]) -> tuple[float, float]:
    """The defence area's depth and width (mm): as sent, else read off the field lines
    (grSim sends the lines only: without this a 12 x 9 m field got division B's 1 x 2 m
    area), else 0 (the consumers' division default). A line's centre lies half its
    thickness inside or outside the area (ssl-vision and grSim differ): a size within that
    of a multiple of 50 mm is that multiple."""
    hl = f.field_length / 2.0
    depth = float(f.penalty_area_depth) if f.HasField("penalty_area_depth") else 0.0
    width = float(f.penalty_area_width) if f.HasField("penalty_area_width") else 0.0
    stretch = [ln for ln in lines if ln["name"] in _STRETCH and ln["p1"]["x"] == ln["p2"]["x"]]
    if depth <= 0 and stretch:
        ln = stretch[0]
        depth = _snap(hl - abs(ln["p1"]["x"]), ln["thickness"] / 2.0)
    if width <= 0:
        if stretch:  # its ends: the area's corners
            ln = stretch[0]
            width = _snap(abs(ln["p2"]["y"] - ln["p1"]["y"]), ln["thickness"])
        else:  # the sides along the touch lines, each half the width from the centre line
            sides = [ln for ln in lines
                     if ln["name"] in _STRETCH_SIDES and ln["p1"]["y"] == ln["p2"]["y"]]
            if sides:
                width = _snap(2.0 * abs(sides[0]["p1"]["y"]), sides[0]["thickness"])
    return (depth if 0 < depth < hl else 0.0,
            width if 0 < width < f.field_width else 0.0)


def _snap(size: float, within: float) -> float:
    near = round(size / 50.0) * 50.0
    return near if abs(size - near) <= within + 1.0 else size


def camera_poses(geo: SSL_GeometryData) -> list[dict[str, Any]]:
    """Each calibration's camera position (``derived_camera_world_t*``, mm), where sent,
    finite and above the field; one per camera id (the first)."""
    out: list[dict[str, Any]] = []
    seen: set[int] = set()
    for c in geo.calib:
        if not (c.HasField("derived_camera_world_tx") and c.HasField("derived_camera_world_ty")
                and c.HasField("derived_camera_world_tz")):
            continue
        x, y, z = c.derived_camera_world_tx, c.derived_camera_world_ty, c.derived_camera_world_tz
        if not _finite(x, y, z) or z <= 0 or c.camera_id in seen or c.camera_id > 63:
            continue
        seen.add(c.camera_id)
        out.append({"id": c.camera_id, "x": x, "y": y, "z": z})
    return out
