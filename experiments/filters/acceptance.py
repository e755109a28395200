"""Issue 13 section 3: does the default (adaptive) filter fit every case without tuning?

Scenarios (60 Hz, one camera): still; constant speed 0.5, 1, 2, 3 m/s; a ball kicked from rest at
5 m/s (then rolling, 0.4 m/s^2); a ball bouncing off a robot (3 m/s, back at 0.9 m/s). Each with
Gaussian noise 2 or 20 mm per coordinate and outliers with probability 0 or 0.2 (a false
detection 200-1000 mm away). Errors after a 0.5 s warm-up.

Filters: raw, median, paper (defaults), Kalman (defaults), "Kalman tuned for that case" (the best
RMSE over a grid of acceleration noise 10 .. 1e5 mm/s^2 x gate none / 150 mm, with the true
measurement noise, chosen on the very data it is scored on: an oracle no station has), and the
adaptive filter (defaults). The criterion: adaptive RMSE <= 1.1 x the best of raw, median, paper
and tuned Kalman.

Pure and seeded (also run by tests/backend/filters/test_adaptive.py with fewer runs).
"""

from __future__ import annotations

import math
import random
from collections.abc import Callable
from typing import Any

from backend.filters import (
    AdaptiveIMM,
    KalmanCV,
    MedianFilter,
    PaperFilter,
    PositionFilter,
    RawFilter,
)

DT = 1 / 60
WARMUP_S = 0.5
NOISES_MM = (2.0, 20.0)
OUTLIER_PS = (0.0, 0.2)
KALMAN_GRID_Q = (10.0, 30.0, 100.0, 300.0, 1000.0, 3000.0, 10000.0, 30000.0, 100000.0)
KALMAN_GRID_GATE = (0.0, 150.0)
TOLERANCE = 1.1

Traj = Callable[[float], tuple[float, float]]
Maker = Callable[[], PositionFilter]
Run = list[tuple[float, float, float, float, float]]  # t, true x, true y, measured x, y


def still(t: float) -> tuple[float, float]:
    return (1000.0, 500.0)


def moving(v_mm_s: float) -> Traj:
    return lambda t: (-1500.0 + v_mm_s * t, 200.0)


def kicked(t: float) -> tuple[float, float]:
    """At rest for 1 s, then kicked at 5 m/s along (0.8, 0.6), rolling at -0.4 m/s^2."""
    if t <= 1.0:
        return (0.0, 0.0)
    s = t - 1.0
    d = 5000.0 * s - 200.0 * s * s
    return (0.8 * d, 0.6 * d)


def bounced(t: float) -> tuple[float, float]:
    """3 m/s along +x, hits a robot at t = 1 s, back at 0.9 m/s; -0.4 m/s^2 throughout."""
    if t <= 1.0:
        return (-3000.0 + 3000.0 * t - 200.0 * t * t, 300.0)
    xb = -3000.0 + 3000.0 - 200.0
    s = t - 1.0
    return (xb - 900.0 * s + 200.0 * s * s, 300.0 + 150.0 * s)


SCENARIOS: list[tuple[str, Traj, float]] = [
    ("still", still, 4.0),
    ("moving 0.5 m/s", moving(500.0), 3.0),
    ("moving 1 m/s", moving(1000.0), 3.0),
    ("moving 2 m/s", moving(2000.0), 3.0),
    ("moving 3 m/s", moving(3000.0), 3.0),
    ("kicked (5 m/s from rest)", kicked, 2.5),
    ("bounced (3 -> 0.9 m/s)", bounced, 2.0),
]

BASELINES: list[tuple[str, Maker]] = [
    ("raw", RawFilter),
    ("median", MedianFilter),
    ("paper", PaperFilter),
    ("kalman", KalmanCV.from_params),
]


def measure(traj: Traj, seconds: float, noise: float, p_out: float, rng: random.Random) -> Run:
    out = []
    for i in range(int(seconds / DT)):
        t = i * DT
        x, y = traj(t)
        zx, zy = x + rng.gauss(0.0, noise), y + rng.gauss(0.0, noise)
        if rng.random() < p_out:  # a false detection, e.g. the ball "on a robot" nearby
            a = rng.uniform(0.0, 2 * math.pi)
            d = rng.uniform(200.0, 1000.0)
            zx, zy = zx + d * math.cos(a), zy + d * math.sin(a)
        out.append((t, x, y, zx, zy))
    return out


def rmse(maker: Maker, runs: list[Run]) -> float:
    s, n = 0.0, 0
    for run in runs:
        f = maker()
        for t, x, y, zx, zy in run:
            ex, ey = f.update(t, zx, zy)
            if t >= WARMUP_S:
                s += (ex - x) ** 2 + (ey - y) ** 2
                n += 1
    return math.sqrt(s / n)


def tuned_kalman(runs: list[Run], noise: float) -> tuple[float, float, float]:
    """(RMSE, acceleration noise, gate) of the best Kalman filter of the grid on these runs."""
    def maker(q: float, g: float) -> Maker:
        return lambda: KalmanCV(q, noise, g)

    return min((rmse(maker(q, g), runs), q, g)
               for q in KALMAN_GRID_Q for g in KALMAN_GRID_GATE)


def table(seed: int, runs: int) -> list[dict[str, Any]]:
    """One row per scenario x noise x outlier rate: every filter's RMSE, the best baseline,
    the adaptive filter's ratio to it."""
    rows = []
    for noise in NOISES_MM:
        for p_out in OUTLIER_PS:
            for k, (name, traj, secs) in enumerate(SCENARIOS):
                rng = random.Random(seed * 1000 + k * 10 + int(noise) + int(10 * p_out))
                data = [measure(traj, secs, noise, p_out, rng) for _ in range(runs)]
                res = {fname: rmse(mk, data) for fname, mk in BASELINES}
                kt, q, g = tuned_kalman(data, noise)
                res["kalman tuned"] = kt
                res["adaptive"] = rmse(AdaptiveIMM, data)
                cands = {f: res[f] for f in ("raw", "median", "paper", "kalman tuned")}
                best = min(cands, key=lambda f: cands[f])
                rows.append({
                    "scenario": name, "noise_mm": noise, "p_out": p_out, "rmse": res,
                    "tuned_q": q, "tuned_gate": g, "best": best,
                    "ratio": res["adaptive"] / res[best],
                })
    return rows


def still_velocity(seed: int, runs: int, noise: float) -> dict[str, dict[str, float]]:
    """Speed read on a still object (the truth is 0), mm/s, after the warm-up."""
    out = {}
    for fname, mk in (("kalman", KalmanCV.from_params), ("adaptive", AdaptiveIMM)):
        rng = random.Random(seed)
        speeds: list[float] = []
        for _ in range(runs):
            f = mk()
            for t, _x, _y, zx, zy in measure(still, 4.0, noise, 0.0, rng):
                f.update(t, zx, zy)
                if t >= WARMUP_S:
                    speeds.append(math.hypot(*f.velocity()))
        speeds.sort()
        out[fname] = {"rms": math.sqrt(sum(v * v for v in speeds) / len(speeds)),
                      "p95": speeds[int(0.95 * (len(speeds) - 1))], "max": speeds[-1]}
    return out


def lag(seed: int, runs: int, noise: float, v_mm_s: float = 2000.0) -> dict[str, float]:
    """Mean error along the motion (true - estimate) at constant speed, after the warm-up."""
    out = {}
    for fname, mk in (("kalman", KalmanCV.from_params), ("adaptive", AdaptiveIMM)):
        rng = random.Random(seed)
        along: list[float] = []
        for _ in range(runs):
            f = mk()
            for t, x, _y, zx, zy in measure(moving(v_mm_s), 3.0, noise, 0.0, rng):
                ex, _ = f.update(t, zx, zy)
                if t >= WARMUP_S:
                    along.append(x - ex)
        out[fname] = sum(along) / len(along)
    return out


def noise_estimate(seed: int, noise: float, p_out: float, scenario: int = 0,
                   runs: int = 5) -> list[float]:
    """The adaptive filter's noise estimate (std, mm) at the end of each run."""
    _name, traj, secs = SCENARIOS[scenario]
    rng = random.Random(seed)
    out = []
    for _ in range(runs):
        f = AdaptiveIMM()
        for t, _x, _y, zx, zy in measure(traj, secs, noise, p_out, rng):
            f.update(t, zx, zy)
        out.append(f.noise())
    return out


def run_all(seed: int, runs: int) -> dict[str, Any]:
    return {
        "table": table(seed, runs),
        "still_velocity": {f"{n:g} mm": still_velocity(seed, runs, n) for n in NOISES_MM},
        "lag_2m_s": {f"{n:g} mm": lag(seed, runs, n) for n in NOISES_MM},
        "noise_estimate": {f"{n:g} mm, p_out={p}": noise_estimate(seed, n, p)
                           for n in NOISES_MM for p in OUTLIER_PS},
    }


def markdown(res: dict[str, Any]) -> list[str]:
    """The scenario x filter table (best baseline in bold, misses flagged) and the figures."""
    cols = ["raw", "median", "paper", "kalman", "kalman tuned", "adaptive"]
    L = ["| scenario | noise (mm) | outliers | " + " | ".join(cols)
         + " | adaptive / best | tuned Kalman (q, gate) |",
         "|---|---|---|" + "---|" * len(cols) + "---|---|"]
    misses = []
    for r in res["table"]:
        cells = []
        for c in cols:
            v = f"{r['rmse'][c]:.2f}"
            cells.append(f"**{v}**" if c == r["best"] else v)
        ok = r["ratio"] <= TOLERANCE
        if not ok:
            misses.append(r)
        L.append(f"| {r['scenario']} | {r['noise_mm']:g} | {r['p_out']:g} | "
                 + " | ".join(cells) + f" | {r['ratio']:.2f}{'' if ok else ' (miss)'} | "
                 f"{r['tuned_q']:g}, {r['tuned_gate']:g} |")
    n = len(res["table"])
    L += ["", f"Cells within {TOLERANCE:g} x the best: {n - len(misses)} of {n}."]
    if misses:
        L.append("Misses: " + "; ".join(
            f"{m['scenario']} / {m['noise_mm']:g} mm / p {m['p_out']:g} ({m['ratio']:.2f})"
            for m in misses) + ".")
    return L
