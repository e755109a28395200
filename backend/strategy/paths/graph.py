"""The visibility graph the search runs on: its nodes around each obstacle and which of
their edges the search tests first.

- around each inflated circle, a polygon circumscribed about the circle grown by
  ``NODE_PAD_MM`` (so its edges stay outside the circle), touching it where the tangents
  from start and goal touch it, with corners at most 2 pi / ``CIRCLE_SIDES`` apart: a path
  around one circle is tangent, polygon, tangent, within 2.4 % (+ the pad) of the exact
  tangent-arc-tangent length;
- the corners of each inflated rectangle, pushed diagonally outward by ``NODE_PAD_MM``;
- start and goal (added by the search);

dropping nodes inside another obstacle or outside the bounds (so overlapping obstacles are
passed around their union). Edges are not stored: the search tests them lazily.
``_tangent_ok`` is the pruning: the edges that touch the end node's polygon from outside
(the edges a taut path can use).
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numpy.typing import NDArray

from .collision import _Inflated
from .obstacles import Array

#: sides of the polygon placed around each circular obstacle
CIRCLE_SIDES = 12
#: graph nodes lie this far (mm) outside the inflated obstacles
NODE_PAD_MM = 1.0


class _Graph(NamedTuple):
    """Candidate waypoints (free ones only) with what the tangent pruning needs."""

    xy: Array  #: (V, 2) node positions
    to_prev: Array  #: (V, 2) unit vector along the polygon edge to the previous corner
    to_next: Array  #: (V, 2) unit vector along the polygon edge to the next corner
    owner: Array  #: (V, 3) centre and squared radius of a circle holding that polygon
    always: NDArray[np.bool_]  #: (V,) never pruned (near another obstacle)

    @classmethod
    def concat(cls, parts: list[_Graph]) -> _Graph:
        return cls(*(np.concatenate([pt[i] for pt in parts]) for i in range(5)))


def _circle_nodes(inf: _Inflated, s: Array, g: Array, sel: NDArray[np.int64]) -> _Graph:
    """Around each selected inflated circle a polygon circumscribed about the circle grown
    by the pad, touching it where the tangents from start and goal touch it (on the radius
    through an end point closer than that) and with corners at most 2 pi / ``CIRCLE_SIDES``
    apart in between: every edge between neighbouring nodes lies on a tangent of that
    circle, so it stays outside, and start -> touch point is a tangent too. The free nodes,
    with the directions of the polygon's edges at each (for the tangent pruning); all edges
    of a circle that comes near another obstacle are kept."""
    n, k = CIRCLE_SIDES, len(sel)
    two_pi = 2.0 * math.pi
    cxy, cx, cy = inf.cxy[sel], inf.cx[sel], inf.cy[sel]
    rt = inf.cr[sel] + NODE_PAD_MM  # (k,) the circle the polygon touches
    v = np.stack([s, g])[:, None, :] - cxy  # (2, k, 2)
    d = np.hypot(v[..., 0], v[..., 1])
    theta = np.arctan2(v[..., 1], v[..., 0])
    half = np.arccos(np.minimum(rt / np.maximum(d, 1e-12), 1.0))  # 0 from inside rt
    a = np.sort(np.concatenate([theta - half, theta + half]).T % two_pi, axis=1)  # (k, 4)
    arc = a[:, [1, 2, 3, 0]] - a  # arc j: from touch point j to touch point j + 1
    arc[:, 3] += two_pi  # the wrap-around (2 pi when all four coincide)
    a, arc = a.ravel(), arc.ravel()
    cnt = np.where(arc > 1e-9, np.ceil(arc / (two_pi / n) - 1e-9), 0.0).astype(np.int64)
    half_step = arc / (2.0 * np.maximum(cnt, 1))
    owner = np.repeat(np.arange(k), 4)
    # corners, arc after arc: arc j's corner i at angle a_j + (2 i + 1) half_step_j, where
    # the tangents at a_j + 2 i half_step_j and a_j + (2 i + 2) half_step_j cross
    j = np.repeat(np.arange(4 * k), cnt)
    i = np.arange(len(j)) - (np.cumsum(cnt) - cnt)[j]
    hs = half_step[j]
    ang = np.concatenate([a[j] + (2 * i + 1) * hs, a])  # corners, then touch points
    hs = np.concatenate([hs, np.zeros(4 * k)])  # a touch point sits on a straight edge
    who = np.concatenate([owner[j], owner])
    rad = rt[who] / np.cos(hs)
    cs, sn = np.cos(ang), np.sin(ang)
    xy = cxy[who] + rad[:, None] * np.column_stack([cs, sn])
    # circles whose polygon may reach another obstacle or a bound: only their nodes can be
    # inside one (the others are free by construction), and theirs may sit in a notch
    # between obstacles, so their edges are never pruned
    rv = rt / math.cos(math.pi / n)  # no node is farther from its centre
    gap = np.hypot(cx[:, None] - inf.cx, cy[:, None] - inf.cy)  # (k, K)
    gap[np.arange(k), sel] = np.inf
    crowded: NDArray[np.bool_] = np.asarray((gap < rv[:, None] + inf.cr).any(axis=1))
    if len(inf.rects):
        r = inf.rects
        ox = np.maximum(np.maximum(r[:, 0] - cx[:, None], 0.0), cx[:, None] - r[:, 2])
        oy = np.maximum(np.maximum(r[:, 1] - cy[:, None], 0.0), cy[:, None] - r[:, 3])
        crowded |= (np.hypot(ox, oy) < rv[:, None]).any(axis=1)
    b = inf.bounds
    if b is not None:
        crowded |= (cx - rv < b[0]) | (cx + rv > b[2]) | (cy - rv < b[1]) | (cy + rv > b[3])
    near = crowded[who]
    keep = np.ones(len(xy), dtype=bool)
    keep[near] = inf.points_free(xy[near])
    keep[len(j):] &= arc > 1e-9  # a zero-length arc: its touch point is the next one's
    # edge directions at a node: along the tangents at ang - hs (back) and ang + hs (on)
    ch, sh = np.cos(hs), np.sin(hs)
    cc, ss, cs_, sc = cs * ch, sn * sh, cs * sh, sn * ch
    dirs = np.column_stack([sc - cs_, -(cc + ss), -(sc + cs_), cc - ss])[keep]
    own = np.column_stack([cxy, rv * rv])[who]
    return _Graph(xy[keep], dirs[:, :2], dirs[:, 2:], own[keep], near[keep])


def _rect_nodes(inf: _Inflated, sel: NDArray[np.int64]) -> _Graph:
    """The corners of each selected inflated rectangle pushed diagonally out by the pad
    (the free ones); few, so never pruned."""
    r, e = inf.rects[sel], NODE_PAD_MM
    quad = np.stack([r[:, [0, 2, 2, 0]] + np.array([-e, e, e, -e]),
                     r[:, [1, 1, 3, 3]] + np.array([-e, -e, e, e])], axis=-1).reshape(-1, 2)
    quad = quad[inf.points_free(quad)]
    z = np.zeros_like(quad)
    return _Graph(quad, z, z, np.zeros((len(quad), 3)), np.ones(len(quad), dtype=bool))


def _graph_nodes(inf: _Inflated, s: Array, g: Array, circles: NDArray[np.int64],
                 rects: NDArray[np.int64]) -> _Graph:
    """Waypoints around the given obstacles (see the module docstring), the free ones."""
    parts = []
    if len(circles):
        parts.append(_circle_nodes(inf, s, g, circles))
    if len(rects):
        parts.append(_rect_nodes(inf, rects))
    if not parts:
        z = np.zeros((0, 2))
        return _Graph(z, z, z, np.zeros((0, 3)), np.zeros(0, dtype=bool))
    return _Graph.concat(parts)


def _tangent_ok(ux: Array, uy: Array, vx: Array, vy: Array, graph: _Graph,
                vi: NDArray[np.int64]) -> NDArray[np.bool_]:
    """Edges u -> v worth testing when pruning: v's polygon lies on one side of the line uv
    near v (the line touches the polygon at v, as the edges of a taut path around it do),
    or u is within the polygon's circumcircle, or v's obstacle is near another one."""
    dx, dy = vx - ux, vy - uy
    p, q = graph.to_prev[vi], graph.to_next[vi]
    s1 = dx * p[:, 1] - dy * p[:, 0]
    s2 = dx * q[:, 1] - dy * q[:, 0]
    # same side, or collinear within rounding: sin products above -1e-9
    scale = dx * dx + dy * dy
    o = graph.owner[vi]
    inside = (ux - o[:, 0]) ** 2 + (uy - o[:, 1]) ** 2 < o[:, 2]
    return np.asarray((s1 * s2 >= -1e-9 * scale) | inside | graph.always[vi])
