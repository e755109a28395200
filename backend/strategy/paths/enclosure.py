"""When there is no way through: the test that the goal sits in a pocket the start cannot
reach (the search back from the goal runs dry at once, so the search over the whole field is
not run), and the answer then: the straight line towards the goal as far as it is free.
"""

from __future__ import annotations

import math

import numpy as np

from .astar import EXPAND_BATCH, _astar, _OverBudget
from .collision import _Inflated, first_blocking
from .graph import NODE_PAD_MM, _Graph
from .obstacles import Array, Obstacles

#: node expansions of the search back from the goal before the unbounded search (see
#: ``_enclosed``)
POCKET_BUDGET = 2 * EXPAND_BATCH


def _enclosed(inf: _Inflated, s: Array, g: Array, graph: _Graph) -> bool:
    """The goal sits in a small pocket the start cannot reach (e.g. a goal moved to the nearest
    free point between two robots and a defence area): the search back from the goal runs
    out of nodes within ``POCKET_BUDGET`` expansions without meeting the start. The graph's
    edges are the same both ways, so then there is no path at all, and the unbounded search
    from the start, which would visit every node on the field twice (pruned, then not), is
    not needed."""
    try:
        return _astar(inf, g, s, graph, math.inf, False, POCKET_BUDGET) is None
    except _OverBudget:
        return False


def _free_prefix(a: Array, b: Array, obstacles: Obstacles, clearance: float) -> Array:
    """The farthest point of [a, b] reachable from a before the first obstacle, backed off
    by ``NODE_PAD_MM`` (a itself when the first obstacle is right there)."""
    hit = first_blocking(a, b, obstacles, clearance)
    if hit is None:
        return b
    length = float(np.hypot(*(b - a)))
    t = max(hit.t - NODE_PAD_MM / length, 0.0) if length > 0.0 else 0.0
    return np.asarray(a + t * (b - a), dtype=np.float64)
