"""Geometry library cost (not a test): microseconds per call for N = 22 (every robot on a
division-A field) and N = 1000 points.

Usage: .venv/bin/python bench/geometry_bench.py
"""

from __future__ import annotations

import sys
import timeit
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from domain.field import DIVISION_A

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from backend import geometry as g


def cases(n: int) -> dict[str, Callable[[], Any]]:
    rng = np.random.default_rng(0)
    a, b, p = (rng.uniform(-4500, 4500, size=(n, 2)) for _ in range(3))
    r = rng.uniform(90, 500, size=n)
    obstacles, radii = rng.uniform(-4500, 4500, size=(16, 2)), np.full(16, 180.0)
    th = rng.uniform(-10, 10, size=n)
    track = np.cumsum(rng.normal(size=(n, 2)), axis=0)
    return {
        "distance": lambda: g.distance(a, b),
        "normalise": lambda: g.normalise(a),
        "signed_angle": lambda: g.signed_angle(a, b),
        "wrap_angle": lambda: g.wrap_angle(th),
        "rotate": lambda: g.rotate(a, th),
        "point_segment_distance": lambda: g.point_segment_distance(p, a, b),
        "line_intersection": lambda: g.line_intersection(a, b, p, a[::-1]),
        "segment_intersection": lambda: g.segment_intersection(a, b, p, a[::-1]),
        "line_circle_intersection": lambda: g.line_circle_intersection(a, b, p, r),
        "circle_circle_intersection": lambda: g.circle_circle_intersection(a, r, b, r),
        "tangent_points": lambda: g.tangent_points(a, p, r),
        "segment_hits_circles (16 obstacles)": lambda: g.segment_hits_circles(
            a, b, obstacles, radii),
        "in_rectangle": lambda: g.in_rectangle(p, [0, 0], [1000, 500], 0.3),
        "in_defense_area": lambda: g.in_defense_area(p, DIVISION_A),
        "fit_line_tls (one track of N)": lambda: g.fit_line_tls(track),
        "goalkeeper_target": lambda: g.goalkeeper_target(a, b, -4500.0, 1000.0, 90.0),
    }


def main() -> None:
    small, big = cases(22), cases(1000)
    print(f"{'function':<38} {'N=22 us':>10} {'N=1000 us':>10}")
    for name in small:
        res = []
        for fn in (small[name], big[name]):
            number = 2000
            best = min(timeit.repeat(fn, number=number, repeat=3)) / number
            res.append(best * 1e6)
        print(f"{name:<38} {res[0]:10.1f} {res[1]:10.1f}")


if __name__ == "__main__":
    main()
