"""Touchline's 2-D geometry library: the functions of the team's MATLAB geometry scripts,
vectorised with numpy.

Every function accepts single points (shape (2,)) or arrays of points (shape (..., 2)) and
broadcasts; see each module for conventions. Units: the field frame is mm and rad, but all
functions except the defence-area constants are unit-agnostic. Missing results (no
intersection, parallel lines, a point inside a circle for tangents) are NaN coordinates,
never exceptions, so batches can mix hits and misses.

- ``vectors``: dot, cross, norm, distance, normalise, wrap_angle, angle_of, signed_angle,
  rotate, from_polar, perp
- ``lines``: line_param, project_on_line/segment, point_line/segment_distance,
  signed_line_distance, line_intersection, segment_intersection
- ``circles``: line/segment/circle-circle intersection, tangent_points, in_circle,
  segment_hits_circles (first obstacle on a path)
- ``regions``: in_half_plane, in_rectangle (oriented), in_defense_area (division A/B)
- ``fit``: fit_line_tls, fit_motion_lsq, intercept_x, goalkeeper_target
"""

from .circles import (
    SegmentHit,
    circle_circle_intersection,
    in_circle,
    line_circle_intersection,
    segment_circle_intersection,
    segment_hits_circles,
    tangent_points,
)
from .fit import Line, Motion, fit_line_tls, fit_motion_lsq, goalkeeper_target, intercept_x
from .lines import (
    PARALLEL_EPS,
    line_intersection,
    line_param,
    point_line_distance,
    point_segment_distance,
    project_on_line,
    project_on_segment,
    segment_intersection,
    signed_line_distance,
)
from .regions import (
    in_defense_area,
    in_half_plane,
    in_rectangle,
)
from .vectors import (
    angle_of,
    cross,
    distance,
    dot,
    from_polar,
    norm,
    normalise,
    perp,
    rotate,
    signed_angle,
    wrap_angle,
)

__all__ = [
    "PARALLEL_EPS",
    "Line",
    "Motion",
    "SegmentHit",
    "angle_of",
    "circle_circle_intersection",
    "cross",
    "distance",
    "dot",
    "fit_line_tls",
    "fit_motion_lsq",
    "from_polar",
    "goalkeeper_target",
    "in_circle",
    "in_defense_area",
    "in_half_plane",
    "in_rectangle",
    "intercept_x",
    "line_circle_intersection",
    "line_intersection",
    "line_param",
    "norm",
    "normalise",
    "perp",
    "point_line_distance",
    "point_segment_distance",
    "project_on_line",
    "project_on_segment",
    "rotate",
    "segment_circle_intersection",
    "segment_hits_circles",
    "segment_intersection",
    "signed_angle",
    "signed_line_distance",
    "tangent_points",
    "wrap_angle",
]
