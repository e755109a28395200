"""The benchmark's "floor + the paper's algorithms" row claims to run the paper's filter: its
tight plain-Python filter must give what the station's own 'paper' filter gives."""

from __future__ import annotations

import random

import pytest

from backend.filters.core import PaperFilter
from backend.filters.params import PaperParams
from bench.floor.floor import _Track


def test_tight_filter_is_the_paper_filter() -> None:
    rng = random.Random(7)
    # no re-initialisation on jumps or gaps: the tight filter has neither
    ref = PaperFilter(PaperParams(jump_mm=10000.0, gap_s=10.0))
    tight = _Track()
    x, y = 100.0, -250.0
    for k in range(200):
        t = 1000.0 + k / 75.0
        x += 8.0
        y -= 3.0
        mx = x + rng.gauss(0.0, 5.0) + (400.0 if k % 37 == 5 else 0.0)  # noise, an outlier
        my = y + rng.gauss(0.0, 5.0)
        est = ref.update(t, mx, my)
        tight.update(t, mx, my, 0.0)
        assert (tight.fx, tight.fy) == pytest.approx(est, rel=1e-9, abs=1e-6)
