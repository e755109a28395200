"""A* on the visibility graph (``graph.py``): exact on the graph, inside a bound on the
path length (the ellipse around start and goal), with the edges of several nodes tested
together in one numpy call.
"""

from __future__ import annotations

import heapq
import math

import numpy as np

from .collision import _Inflated
from .graph import _Graph, _tangent_ok
from .obstacles import Array

#: nodes expanded together in one vectorised step of the search
EXPAND_BATCH = 8


class _OverBudget(Exception):
    """``_astar`` expanded more nodes than its budget allows."""


def _astar(inf: _Inflated, s: Array, g: Array, graph: _Graph, limit: float,
           prune: bool, budget: int | None = None) -> list[Array] | None:
    """Shortest path s -> g (excluding s) of length <= ``limit`` through the graph's nodes,
    in the lazily built visibility graph; None when there is none that short.

    Only nodes with |s v| + |v g| <= limit can be on such a path (the ellipse with foci s
    and g), so the others are dropped before anything is tested. The search is best-first on
    f = g + |v goal| (a consistent heuristic), but pops up to ``EXPAND_BATCH`` nodes at a
    time and tests all their edges in one numpy call (numpy's per-call cost dominates at
    these sizes); a node whose cost improves after its expansion is expanded again, and the
    search stops when the smallest f left is no better than the goal's cost, so the result
    is the exact shortest path in the graph. An edge is tested only when it improves its end
    node and could still lead to a path under the bound; with ``prune`` also only when it
    passes ``_tangent_ok``. With a ``budget`` it raises ``_OverBudget`` after that many
    expansions."""
    cx, cy = graph.xy[:, 0], graph.xy[:, 1]
    near = np.hypot(cx - s[0], cy - s[1]) + np.hypot(cx - g[0], cy - g[1]) <= limit
    ends = _Graph(np.vstack([s, g]), np.zeros((2, 2)), np.zeros((2, 2)),
                  np.array([[0.0, 0.0, np.inf]] * 2), np.ones(2, dtype=bool))  # never pruned
    sub = _Graph.concat([ends, _Graph(*(a[near] for a in graph))])
    x, y = sub.xy[:, 0].copy(), sub.xy[:, 1].copy()
    v = len(x)
    h = np.hypot(x - g[0], y - g[1])
    best = np.full(v, np.inf)
    best[0] = 0.0
    expanded_at = [math.inf] * v  # cost of each node when it was last expanded
    hl = h.tolist()
    parent = np.full(v, -1, dtype=np.int64)
    heap: list[tuple[float, int]] = [(float(h[0]), 0)]
    while heap:
        batch: list[int] = []
        goal_cost = float(best[1])
        while heap and len(batch) < EXPAND_BATCH:
            f, u = heapq.heappop(heap)
            if f >= goal_cost:  # nothing left can beat the path to the goal
                heap.clear()
                break
            bu = float(best[u])
            if bu < expanded_at[u] and f <= bu + hl[u]:  # else a stale entry
                batch.append(u)
                expanded_at[u] = bu
        if not batch:
            break
        if budget is not None:
            budget -= len(batch)
            if budget < 0:
                raise _OverBudget
        ub = np.asarray(batch, dtype=np.int64)
        ux, uy = x[ub][:, None], y[ub][:, None]
        new = best[ub][:, None] + np.hypot(x - ux, y - uy)  # (B, V)
        f_new = new + h
        bi, vi = np.nonzero((new < best) & (f_new < min(goal_cost, limit + 1e-9)))
        if prune and len(bi):
            ok = _tangent_ok(x[ub[bi]], y[ub[bi]], x[vi], y[vi], sub, vi)
            bi, vi = bi[ok], vi[ok]
        if not len(bi):
            continue
        ok = ~inf.segments_blocked(x[ub[bi]], y[ub[bi]], x[vi], y[vi])
        bi, vi = bi[ok], vi[ok]
        if not len(bi):
            continue
        nv = new[bi, vi]
        order = np.lexsort((nv, vi))  # per end node, its cheapest new edge first
        vs = vi[order]
        first = np.ones(len(vs), dtype=bool)
        first[1:] = vs[1:] != vs[:-1]
        sel = order[first]
        vsel, csel = vi[sel], nv[sel]
        best[vsel] = csel
        parent[vsel] = ub[bi[sel]]
        for w, fw in zip(vsel.tolist(), (csel + h[vsel]).tolist(), strict=True):
            heapq.heappush(heap, (fw, w))
    if not np.isfinite(best[1]):
        return None
    chain: list[Array] = []
    w = 1
    while w != 0:
        chain.append(sub.xy[w])
        w = int(parent[w])
    chain.reverse()
    return chain
