"""The search: A* (``astar.py``) within a growing corridor around start and goal, first on
the tangent-pruned graph, then on the full one, so a path is found whenever the graph has
one.

- the search first runs inside an ellipse around start and goal that only allows short
  detours, then wider ones (``CORRIDOR_FIRST``, ``CORRIDOR_GROWTH``), then unbounded (unless
  the goal is enclosed: ``enclosure.py``);
- it first tests only edges that touch the end node's polygon from outside (collinear
  within rounding, or from inside that polygon's circumcircle, or at a node next to a
  dropped one, also count), and searches the full graph only when that finds nothing.

Gaps between obstacles narrower than about the node padding may be missed (conservative,
never unsafe).
"""

from __future__ import annotations

import math

import numpy as np

from .astar import _astar
from .collision import _Inflated
from .enclosure import _enclosed
from .graph import CIRCLE_SIDES, NODE_PAD_MM, _graph_nodes
from .obstacles import Array

#: corridor schedule of ``_shortest``: first extra length over the straight distance, in
#: units of the largest inflated circle's circumference, and the growth factor
CORRIDOR_FIRST = 1.0
CORRIDOR_GROWTH = 2.5


def _shortest(inf: _Inflated, s: Array, g: Array, prune: bool = True) -> list[Array] | None:
    """``_astar`` within a growing corridor: most detours are short (around one or two
    robots), and a narrow ellipse keeps the search small: only the obstacles that can have
    nodes in it get any. Each stage is exact for its bound and the last has none. With
    ``prune`` the tangent-pruned graph is searched first and the full graph only when that
    finds nothing, so a path is found whenever the full graph has one."""
    direct = float(np.hypot(g[0] - s[0], g[1] - s[1]))
    # every node of an obstacle lies within `reach` of its centre c, so it is in the
    # ellipse of a bound L only if |s c| + |c g| - 2 reach <= L
    rv = (inf.cr + NODE_PAD_MM) / math.cos(math.pi / CIRCLE_SIDES)
    mid = (inf.rects[:, :2] + inf.rects[:, 2:]) * 0.5
    half = np.hypot(inf.rects[:, 2] - inf.rects[:, 0], inf.rects[:, 3] - inf.rects[:, 1]) * 0.5
    centre = np.vstack([inf.cxy, mid])
    reach = np.concatenate([rv, half + NODE_PAD_MM * math.sqrt(2.0)])
    via = (np.hypot(centre[:, 0] - s[0], centre[:, 1] - s[1])
           + np.hypot(centre[:, 0] - g[0], centre[:, 1] - g[1]))
    lo, hi = via - 2.0 * reach, via + 2.0 * reach
    far = float(hi.max()) if len(hi) else 0.0  # past it the bound no longer prunes
    k = len(inf.cr)
    extra = CORRIDOR_FIRST * 2.0 * math.pi * max(float(rv.max()) if k else 0.0, 100.0)
    graph, used = None, None
    while True:
        limit = direct + extra if direct + extra < far else math.inf
        take = lo <= limit
        if used is None or (take != used).any():
            used = take
            graph = _graph_nodes(inf, s, g, np.nonzero(take[:k])[0], np.nonzero(take[k:])[0])
        assert graph is not None
        if math.isinf(limit) and _enclosed(inf, s, g, graph):
            return None
        chain = _astar(inf, s, g, graph, limit, prune)
        if chain is not None or math.isinf(limit):
            break
        extra *= CORRIDOR_GROWTH
    if chain is None and prune:
        chain = _astar(inf, s, g, graph, math.inf, False)
    return chain
