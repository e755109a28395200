"""Where the world model's time goes per camera frame, hot, at full scale (figures, not a test):
issue 29's "robots as arrays" pays only where the per-detection work is, so this splits it.

Input: fieldsim 11 v 11, division A, 8 cameras x 75 Hz, every robot driving (curves at
0.3-1.5 m/s, turning), false detections, the cameras ``spread`` (each its own phase) or
``together`` (one burst of eight frames an instant, as grSim). The frames go through one
``WorldModel`` in arrival order, a snapshot after each pass (``--per-pass`` frames; default
2 spread, 8 together), the camera positions known (the station's case).

The split (CPU time per frame, best of ``--reps``):

- the adaptive filters, replayed alone: every ``update``/``revise`` call the run made,
  recorded and replayed on fresh filters in the same order (exactly the filters' own cost,
  no profiler in it): robots' positions (2-D), robots' orientations (1-D), the ball;
- ``update`` (the world model's per-frame merge) minus the filters: ``_measure``'s own work,
  the per-frame bookkeeping, the ball's association;
- ``snapshot``, of which ``_seen_state``.

Also counts robot detections a frame and a pass, and how many are a new instant (``update``)
or another camera at the same instant (``revise``).

    PYTHONPATH=. .venv/bin/python bench/world_split.py [--phases spread|together]
        [--seconds 6] [--per-pass N] [--reps 5]
"""

from __future__ import annotations

import argparse
import math
import sys
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from backend.filters.adaptive import AdaptiveIMM, AdaptiveIMM1D
from backend.world.decode import decode_detection
from backend.world.model import WorldModel
from backend.world.state import CameraFrame

T0 = 1_700_000_000.0


def fieldsim_frames(phases: str, seconds: float, seed: int = 3) -> tuple[
        list[CameraFrame], dict[int, tuple[float, float, float]]]:
    """The frames in arrival order (a burst's in camera order) and the cameras' poses."""
    from fieldsim.config import SimConfig
    from fieldsim.vision import Vision, WorldClockFrames
    from fieldsim.world import Team, World

    cfg = SimConfig(blue=11, yellow=11, seed=seed, cameras=8, division="A", camera_hz=75.0,
                    false_prob=0.05, camera_phases=phases)
    w = World(cfg)
    v = Vision(cfg, w.geometry)
    frames = WorldClockFrames(v, w, T0)
    out: list[tuple[float, int, CameraFrame]] = []
    while w.t < seconds:
        for team in (Team.BLUE, Team.YELLOW):
            for rid in range(11):
                # every robot driving a curve of its own, turning back and forth
                s = 0.3 + 0.1 * rid
                w.set_command(team, rid, s, 0.2 * math.sin(w.t + rid),
                              1.0 if (w.t + 0.3 * rid) % 2 < 1 else -1.0)
        w.step()
        for k, tc, packet in frames.due():
            recv = int((T0 + tc + 0.002) * 1e9) + 30_000 * k
            out.append((recv, k, decode_detection(packet.detection, recv)))
    out.sort(key=lambda p: (p[0], p[1]))
    poses = {c.camera_id: (c.cx, c.cy, c.height) for c in v.cameras}
    return [f for _, _, f in out], poses


def passes(frames: list[CameraFrame], per_pass: int) -> list[list[CameraFrame]]:
    return [frames[i:i + per_pass] for i in range(0, len(frames), per_pass)]


class Recorder:
    """Records every adaptive filter call (the filter, the method, its arguments)."""

    def __init__(self) -> None:
        self.calls: list[tuple[Any, str, tuple[float, ...]]] = []
        self.saved: list[tuple[type, str, Callable[..., Any]]] = []
        self.depth = [0]  # (shared: update calls revise through the class, wrapped too)

    def __enter__(self) -> Recorder:
        for cls in (AdaptiveIMM, AdaptiveIMM1D):
            for name in ("update", "revise"):
                orig = cls.__dict__[name]
                self.saved.append((cls, name, orig))
                setattr(cls, name, self._wrap(orig, name))
        return self

    def _wrap(self, orig: Callable[..., Any], name: str) -> Callable[..., Any]:
        calls, depth = self.calls, self.depth

        def f(flt: Any, *args: Any) -> Any:
            # only the outermost call (update calls revise, revise may redo an update)
            if depth[0] == 0:
                calls.append((flt, name, args[:3] if name == "update" else args[:2]))
            depth[0] += 1
            try:
                return orig(flt, *args)
            finally:
                depth[0] -= 1
        return f

    def __exit__(self, *exc: object) -> None:
        for cls, name, orig in self.saved:
            setattr(cls, name, orig)


def run_model(ps: list[list[CameraFrame]], poses: dict[int, tuple[float, float, float]],
              seen_timer: bool = False) -> tuple[WorldModel, float, float, float]:
    """CPU seconds in update, in snapshot, and (``seen_timer``) in _seen_state."""
    m = WorldModel()
    m.set_cameras(poses)
    seen_total = [0.0]
    if seen_timer:
        orig = m._seen_state
        clock = time.perf_counter

        def timed(key: Any, tr: Any) -> Any:
            c0 = clock()
            s = orig(key, tr)
            seen_total[0] += clock() - c0
            return s
        m._seen_state = timed  # type: ignore[method-assign]
    upd = snap = 0.0
    clock = time.perf_counter
    for p in ps:
        c0 = clock()
        for f in p:
            m.update(f)
        c1 = clock()
        m.snapshot()
        upd += c1 - c0
        snap += clock() - c1
    return m, upd, snap, seen_total[0]


def replay(calls: list[tuple[Any, str, tuple[float, ...]]], kinds: dict[int, str]) -> dict[
        str, float]:
    """The recorded calls on fresh filters, timed per kind of filter (robot 2-D, robot 1-D,
    ball) and method."""
    fresh: dict[int, Any] = {}
    plan: list[tuple[Callable[..., Any], tuple[float, ...], str]] = []
    for flt, name, args in calls:
        k = id(flt)
        if k not in fresh:
            fresh[k] = type(flt)()
        plan.append((getattr(fresh[k], name), args, f"{kinds.get(k, '?')} {name}"))
    totals: dict[str, float] = {}
    clock = time.perf_counter
    for f, args, label in plan:
        c0 = clock()
        f(*args)
        totals[label] = totals.get(label, 0.0) + clock() - c0
    # the timer's own cost, per call, taken off
    c0 = clock()
    for _ in range(20000):
        c1 = clock()
        c1 = clock() - c1
    per = (clock() - c0) / 20000 / 2
    counts: dict[str, int] = {}
    for _, _, label in plan:
        counts[label] = counts.get(label, 0) + 1
    return {k: v - per * counts[k] for k, v in totals.items()} | {
        f"n {k}": float(c) for k, c in counts.items()}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--phases", choices=["spread", "together"], default="spread")
    ap.add_argument("--seconds", type=float, default=6.0)
    ap.add_argument("--per-pass", type=int, default=None)
    ap.add_argument("--reps", type=int, default=5)
    a = ap.parse_args()
    per_pass = a.per_pass or (2 if a.phases == "spread" else 8)
    frames, poses = fieldsim_frames(a.phases, a.seconds)
    ps = passes(frames, per_pass)
    nf = len(frames)
    dets = [len(f.robots) for f in frames]
    per_pass_dets = [sum(len(f.robots) for f in p) for p in ps]
    # which filter is whose, and the calls the run makes
    with Recorder() as rec:
        m, _, _, _ = run_model(ps, poses)
    kinds: dict[int, str] = {}
    seen_ids: set[int] = set()
    for flt, _, _ in rec.calls:
        seen_ids.add(id(flt))
    # the robots' filters at the end, plus any dropped (then "ball" is what is left 2-D)
    for tr in m._robots.values():
        kinds[id(tr.pos)] = "robot-xy"
        assert tr.ang is not None
        kinds[id(tr.ang.inner)] = "robot-angle"
    for flt, _, _ in rec.calls:
        if id(flt) not in kinds:
            kinds[id(flt)] = "robot-angle" if isinstance(flt, AdaptiveIMM1D) else "ball/other"
    best: dict[str, float] | None = None
    best_tot = math.inf
    for _ in range(a.reps):
        cpu0 = time.process_time()
        _, upd, snap, _ = run_model(ps, poses)
        cpu = time.process_time() - cpu0
        _, _, _, seen = run_model(ps, poses, seen_timer=True)
        rp = replay(rec.calls, kinds)
        r = {"update": upd, "snapshot": snap, "seen_state": seen, "cpu": cpu} | rp
        if upd + snap < best_tot:
            best, best_tot = r, upd + snap
    assert best is not None
    us = 1e6 / nf
    filt = {k: v for k, v in best.items() if not k.startswith("n ") and " " in k}
    ftot = sum(filt.values())
    print(f"fieldsim {a.phases}, {nf} frames, {per_pass} a pass ({len(ps)} passes): "
          f"robot detections {sum(dets) / nf:.2f} a frame, {sum(per_pass_dets) / len(ps):.1f} "
          f"a pass (min {min(per_pass_dets)}, max {max(per_pass_dets)})")
    print(f"  world model, us a frame (CPU {best['cpu'] * us:.1f}):")
    print(f"    update (merge)        {best['update'] * us:7.1f}")
    for k in sorted(filt):
        n = best[f"n {k}"]
        print(f"      filter {k:22s} {filt[k] * us:6.1f}  ({n / nf:.2f} calls a frame, "
              f"{filt[k] / n * 1e6:.2f} us a call)")
    print(f"      the rest of update  {(best['update'] - ftot) * us:6.1f}  (_measure's own, "
          "bookkeeping, the ball's association)")
    print(f"    snapshot              {best['snapshot'] * us:7.1f}")
    print(f"      _seen_state         {best['seen_state'] * us:6.1f}  (timed in a run of its "
          "own)")


if __name__ == "__main__":
    main()
