"""Distributing targets between robots: which robot takes which role or position (slot).

The URoboRus paper lists "distributing targets between robots" among the strategy's jobs:
the play decides *where* the team needs robots (a goalkeeper spot, two defenders on the
ball-goal line, an attacker behind the ball, ...) and something must decide *which* robot
goes to each of those points. That is an assignment problem: robots are rows, target slots
are columns, the cost of a pair is how far (mm) the robot has to drive, plus any extra
penalty the play wants to add. This module solves it in three layers:

- ``min_cost_assignment``: the assignment with the least total cost (scipy's
  ``linear_sum_assignment``), rectangular matrices allowed; ``+inf`` marks a forbidden pair.
- ``bottleneck_assignment``: the assignment whose *largest* cost is least (the slowest robot
  arrives as early as possible), ties broken by least total cost.
- ``StableAssigner``: the per-tick helper the strategy calls. It keeps the previous
  robot -> slot pairs unless changing is clearly better (hysteresis), so that noise in the
  vision data, or a robot appearing or disappearing, does not make robots swap roles back
  and forth every tick; it also honours fixed pairs (the goalkeeper the referee names) and
  the slots' priority order.

The solver is scipy's ``linear_sum_assignment`` (also for the bottleneck's matching test); this
module adds the conventions a team needs (forbidden pairs, rows left out, bottleneck first).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.optimize import linear_sum_assignment

__all__ = ["StableAssigner", "bottleneck_assignment", "min_cost_assignment"]

IntArray = NDArray[np.int64]
FloatArray = NDArray[np.float64]


def _check_cost(cost: ArrayLike) -> FloatArray:
    c = np.asarray(cost, dtype=np.float64)
    if c.ndim != 2:
        raise ValueError(f"cost must be a 2-D matrix (robots x slots), got shape {c.shape}")
    if np.isnan(c).any():
        raise ValueError("cost contains NaN; costs must be finite numbers or +inf (forbidden)")
    if np.isneginf(c).any():
        raise ValueError("cost contains -inf; costs must be finite numbers or +inf (forbidden)")
    return c


def min_cost_assignment(cost: ArrayLike) -> IntArray:
    """Least-total-cost assignment of rows (robots) to distinct columns (slots).

    ``cost`` is an (N, M) matrix of finite numbers or ``+inf`` (that pair is forbidden);
    NaN and -inf raise ValueError. Returns an int array of length N: the column of each row,
    or -1 for a row left without a column (N > M: the N - M rows whose absence costs least;
    or a row that could only take forbidden columns). Among assignments the result first
    uses as many allowed pairs as possible, then has the least total cost of those pairs.
    """
    c = _check_cost(cost)
    n, m = c.shape
    if n == 0 or m == 0:
        return np.full(n, -1, dtype=np.int64)
    allowed = np.isfinite(c)
    if allowed.any():
        finite = c[allowed]
        lo, hi = float(finite.min()), float(finite.max())
    else:
        lo = hi = 0.0
    # A forbidden pair costs more than any change in the finite part of a full assignment,
    # so the optimum uses the fewest forbidden pairs first, then the least finite total.
    k = min(n, m)
    big = hi + (k + 1) * (hi - lo + 1.0)
    work = np.where(allowed, c, big)
    rows, cols = linear_sum_assignment(work)
    res = np.full(n, -1, dtype=np.int64)
    res[rows] = cols
    assigned = res >= 0
    idx = np.nonzero(assigned)[0]
    bad = idx[~allowed[idx, res[idx]]]
    res[bad] = -1
    return res


def _matching_size(mask: NDArray[np.bool_]) -> int:
    """Size of a maximum bipartite matching on the allowed pairs of ``mask`` (rows x cols):
    a full assignment that uses as few disallowed pairs as possible uses that many allowed
    ones (on these small matrices scipy's dense solver beats building a sparse graph)."""
    bad = (~mask).astype(np.float64)
    rows, cols = linear_sum_assignment(bad)
    return int(len(rows) - bad[rows, cols].sum())


def _bottleneck_value(c: FloatArray) -> float | None:
    """Least threshold t such that the pairs with cost <= t still admit a matching as large
    as the one on all allowed (finite) pairs; None when no pair is allowed."""
    n, m = c.shape
    allowed = np.isfinite(c)
    if n == 0 or m == 0 or not allowed.any():
        return None
    target = _matching_size(allowed)
    values = np.unique(c[allowed])
    lo, hi = 0, len(values) - 1  # values[hi] always admits the target size
    while lo < hi:
        mid = (lo + hi) // 2
        if _matching_size(c <= values[mid]) >= target:
            hi = mid
        else:
            lo = mid + 1
    return float(values[lo])


def bottleneck_assignment(cost: ArrayLike, *, slack: float = 0.0) -> IntArray:
    """Assignment minimising the largest cost of the assigned pairs, ties broken by the least
    total cost.

    Same conventions as ``min_cost_assignment`` (``+inf`` forbidden, NaN raises, -1 for a row
    without a column); as there, the number of allowed pairs used is maximised first. The
    bottleneck value t* is found by binary search over the sorted distinct costs with a
    maximum-matching test; then the least-total-cost assignment among the pairs costing at
    most ``t* + slack`` is returned (``slack`` > 0 trades a slightly later slowest robot for
    a lower total; ``StableAssigner`` uses it for hysteresis).
    """
    c = _check_cost(cost)
    if slack < 0.0 or not np.isfinite(slack):
        raise ValueError(f"slack must be a finite number >= 0, got {slack}")
    t = _bottleneck_value(c)
    if t is None:
        return np.full(c.shape[0], -1, dtype=np.int64)
    return min_cost_assignment(np.where(c <= t + slack, c, np.inf))


class StableAssigner:
    """Robot -> slot assignment that stays put from tick to tick.

    ``mode="sum"`` minimises the total distance, ``mode="bottleneck"`` the largest one (then
    the total). Every previous (robot id, slot name) pair still on offer gets a bonus of
    ``-hysteresis_mm`` on its cost, so a robot keeps its slot unless the change saves more
    than ``hysteresis_mm`` per robot that changes. Consequences:

    - sum mode: the assignment never changes while every robot-slot distance stays within
      ``hysteresis_mm / 2`` of its value when the assignment was made (vision noise, small
      movements);
    - bottleneck mode: the bottleneck is computed on the bonus-adjusted costs and pairs up to
      ``hysteresis_mm / 2`` above it stay admissible for the total-cost tie-break, otherwise
      two nearly equal longest distances could swap robots on noise; it is stable while the
      distances stay within ``hysteresis_mm / 4`` (the first assignment, or the first after
      ``reset()``, is the exact ``bottleneck_assignment``);
    - a robot that appears or disappears only moves the robots the bonuses cannot keep
      (with fewer robots than slots, the lowest-priority slot may fall out of the set, and
      its robot has to move; the others move only if that saves more than the hysteresis).
    """

    def __init__(self, mode: Literal["sum", "bottleneck"] = "sum",
                 hysteresis_mm: float = 300.0) -> None:
        if mode not in ("sum", "bottleneck"):
            raise ValueError(f"mode must be 'sum' or 'bottleneck', got {mode!r}")
        if not (np.isfinite(hysteresis_mm) and hysteresis_mm >= 0.0):
            raise ValueError(f"hysteresis_mm must be a finite number >= 0, got {hysteresis_mm}")
        self.mode: Literal["sum", "bottleneck"] = mode
        self.hysteresis_mm = float(hysteresis_mm)
        self._previous: dict[int, str] = {}

    @property
    def previous(self) -> dict[int, str]:
        """The last assignment returned (a copy); empty after ``reset()``."""
        return dict(self._previous)

    def reset(self) -> None:
        """Forget the history: the next call assigns from scratch."""
        self._previous = {}

    def assign(self, robot_ids: Sequence[int], robot_xy: ArrayLike, slot_names: Sequence[str],
               slot_xy: ArrayLike, extra_cost: ArrayLike | None = None,
               fixed: Mapping[int, str] | None = None) -> dict[int, str]:
        """Assign robots to slots; returns {robot id: slot name} in ``robot_ids`` order.

        ``robot_xy`` (N, 2) and ``slot_xy`` (M, 2) in mm; ``slot_names`` in priority order.
        ``extra_cost`` (N, M) is added to the distances (``+inf`` forbids a pair).
        ``fixed`` maps a robot id to the slot it must take (e.g. the goalkeeper); entries for
        robots not in ``robot_ids`` are ignored. The other robots share the remaining slots:
        with fewer robots than slots only the first ones (in priority order) are filled, with
        more robots than slots the surplus robots are absent from the result. A robot whose
        every remaining slot is forbidden is also absent.
        """
        ids = [int(r) for r in robot_ids]
        names = [str(s) for s in slot_names]
        n, m = len(ids), len(names)
        if len(set(ids)) != n:
            raise ValueError(f"robot ids must be distinct, got {ids}")
        if len(set(names)) != m:
            raise ValueError(f"slot names must be distinct, got {names}")
        rxy = np.asarray(robot_xy, dtype=np.float64).reshape(-1, 2) if n else np.zeros((0, 2))
        sxy = np.asarray(slot_xy, dtype=np.float64).reshape(-1, 2) if m else np.zeros((0, 2))
        if rxy.shape != (n, 2) or sxy.shape != (m, 2):
            raise ValueError(f"expected robot_xy ({n}, 2) and slot_xy ({m}, 2), "
                             f"got {rxy.shape} and {sxy.shape}")
        if not (np.isfinite(rxy).all() and np.isfinite(sxy).all()):
            raise ValueError("robot and slot positions must be finite")
        extra = None
        if extra_cost is not None:
            extra = np.asarray(extra_cost, dtype=np.float64)
            if extra.shape != (n, m):
                raise ValueError(f"extra_cost must have shape ({n}, {m}), got {extra.shape}")

        result: dict[int, str] = {}
        taken: set[str] = set()
        present = set(ids)
        for rid, slot in (fixed or {}).items():
            if rid not in present:
                continue
            if slot not in names:
                raise ValueError(f"fixed slot {slot!r} for robot {rid} is not among {names}")
            if slot in taken:
                raise ValueError(f"slot {slot!r} is fixed for more than one robot")
            result[rid] = slot
            taken.add(slot)

        free_r = [i for i, rid in enumerate(ids) if rid not in result]
        free_s = [j for j, name in enumerate(names) if name not in taken][:len(free_r)]
        if free_r and free_s:
            d = rxy[free_r][:, None, :] - sxy[free_s][None, :, :]
            cost = np.hypot(d[..., 0], d[..., 1])
            if extra is not None:
                cost = cost + extra[np.ix_(free_r, free_s)]
            col_of = {names[j]: b for b, j in enumerate(free_s)}
            bonus = False
            for a, i in enumerate(free_r):
                b = col_of.get(self._previous.get(ids[i], ""), -1)
                if b >= 0:
                    cost[a, b] -= self.hysteresis_mm
                    bonus = True
            if self.mode == "sum":
                cols = min_cost_assignment(cost)
            else:
                slack = self.hysteresis_mm / 2.0 if bonus else 0.0
                cols = bottleneck_assignment(cost, slack=slack)
            for a, b in enumerate(cols.tolist()):
                if b >= 0:
                    result[ids[free_r[a]]] = names[free_s[b]]

        ordered = {rid: result[rid] for rid in ids if rid in result}
        self._previous = dict(ordered)
        return ordered
