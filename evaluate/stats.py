"""Confidence intervals for the report: Wilson's score interval for a rate, Newcombe's
hybrid score interval for the difference of two independent rates (both 95 % by default),
and a t interval for a mean. Plain math (no scipy): a report is made where the runs were
collected, which may be a small process."""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

Z95 = 1.959963984540054
#: two-sided 97.5 % quantiles of Student's t for 1..30 degrees of freedom (then ~z)
_T975 = (12.706, 4.303, 3.182, 2.776, 2.571, 2.447, 2.365, 2.306, 2.262, 2.228, 2.201, 2.179,
         2.160, 2.145, 2.131, 2.120, 2.110, 2.101, 2.093, 2.086, 2.080, 2.074, 2.069, 2.064,
         2.060, 2.056, 2.052, 2.048, 2.045, 2.042)


def wilson(k: int, n: int, z: float = Z95) -> tuple[float, float, float]:
    """(rate, low, high) of ``k`` successes in ``n`` trials; (nan, 0, 1) for n = 0."""
    if n <= 0:
        return (math.nan, 0.0, 1.0)
    if not 0 <= k <= n:
        raise ValueError(f"{k} successes in {n} trials")
    p = k / n
    z2 = z * z
    den = 1.0 + z2 / n
    centre = (p + z2 / (2 * n)) / den
    half = z * math.sqrt(p * (1 - p) / n + z2 / (4 * n * n)) / den
    return (p, max(0.0, centre - half), min(1.0, centre + half))


def newcombe(k1: int, n1: int, k2: int, n2: int,
             z: float = Z95) -> tuple[float, float, float]:
    """(p1 - p2, low, high): Newcombe's hybrid score interval (method 10 of his 1998 paper)
    for the difference of two independent rates, from each rate's Wilson interval."""
    p1, l1, u1 = wilson(k1, n1, z)
    p2, l2, u2 = wilson(k2, n2, z)
    d = p1 - p2
    lo = d - math.sqrt((p1 - l1) ** 2 + (u2 - p2) ** 2)
    hi = d + math.sqrt((u1 - p1) ** 2 + (p2 - l2) ** 2)
    return (d, max(-1.0, lo), min(1.0, hi))


def mean_interval(values: Sequence[float]) -> tuple[float, float, float]:
    """(mean, low, high) with Student's t (95 %); the interval is the mean alone for n < 2."""
    n = len(values)
    if n == 0:
        return (math.nan, math.nan, math.nan)
    m = sum(values) / n
    if n < 2:
        return (m, m, m)
    sd = math.sqrt(sum((v - m) ** 2 for v in values) / (n - 1))
    t = _T975[n - 2] if n - 1 <= len(_T975) else Z95
    half = t * sd / math.sqrt(n)
    return (m, m - half, m + half)


def rate(k: int, n: int) -> dict[str, Any]:
    """A rate for the report: k, n, rate and its Wilson interval."""
    p, lo, hi = wilson(k, n)
    return {"k": k, "n": n, "rate": None if math.isnan(p) else round(p, 4),
            "low": round(lo, 4), "high": round(hi, 4)}


def difference(k1: int, n1: int, k2: int, n2: int) -> dict[str, Any]:
    """The difference of two independent rates with Newcombe's interval, and whether it is
    significant (the interval does not contain 0) in words."""
    d, lo, hi = newcombe(k1, n1, k2, n2)
    sig = lo > 0.0 or hi < 0.0
    return {"difference": round(d, 4), "low": round(lo, 4), "high": round(hi, 4),
            "significant": sig, "verdict": verdict(d, lo, hi)}


def verdict(d: float, lo: float, hi: float, what: str = "the difference") -> str:
    if lo > 0.0:
        return f"{what} is significant (95 % interval {lo:+.2f} to {hi:+.2f}, above 0)"
    if hi < 0.0:
        return f"{what} is significant (95 % interval {lo:+.2f} to {hi:+.2f}, below 0)"
    return (f"not significant: {what} {d:+.2f} has a 95 % interval {lo:+.2f} to {hi:+.2f}, "
            f"which contains 0")
