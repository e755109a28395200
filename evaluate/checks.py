"""The checks: small functions that score a recorded run (``evaluate.record.Run``).

A check is a plain function ``name(run, **params) -> Result``: ``passed``, a ``score`` in
[0, 1] (partial credit: a keeper that was 0.1 s late is better than one that never moved), the
measured ``value`` with its ``unit`` (time to reach, path length, ...) and a sentence saying
what happened. A scenario names its checks in ``[[check]]`` tables with their parameters
(``name = "reach"``, ``robot = 0``, ...), checked against the function's signature when the
file is loaded. Everything is in our frame, SI units (m, s, rad; ``_deg`` params in degrees).

A suite's own checks go in a ``checks.py`` beside its scenarios: public functions with the same
shape (``def my_check(run: Run, robot: int, limit_m: float = 1.0) -> Result``), found by
name; they may use everything here (``from evaluate.checks import Result, ...``).
"""

from __future__ import annotations

import importlib.util
import inspect
import math
import sys
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from pathlib import Path
from types import ModuleType
from typing import Any

import numpy as np

from .record import BVX, BVY, BX, BY, RHEADING, RX, RY, Event, Run
from .scenario import CheckSignature, check_signature_from_ast

Point = tuple[float, float]


@dataclass(frozen=True)
class Result:
    passed: bool
    score: float  # 0..1
    detail: str
    value: float | None = None
    unit: str = ""

    def as_dict(self) -> dict[str, Any]:
        v = self.value
        return {"passed": self.passed, "score": round(self.score, 4), "detail": self.detail,
                "value": None if v is None or not math.isfinite(v) else round(v, 4),
                "unit": self.unit}


def _ok(passed: bool, detail: str, value: float | None = None, unit: str = "",
        score: float | None = None) -> Result:
    s = (1.0 if passed else 0.0) if score is None else min(1.0, max(0.0, score))
    return Result(passed, s, detail, value, unit)


def _dist(run: Run, robot: np.ndarray, target: Point) -> np.ndarray:
    return np.hypot(robot[:, RX] - target[0], robot[:, RY] - target[1])


def _angle_diff(a: np.ndarray | float, b: np.ndarray | float) -> Any:
    return np.abs((np.asarray(a) - np.asarray(b) + math.pi) % (2 * math.pi) - math.pi)


# -- goals ------------------------------------------------------------------------------------


def ball_in_goal(run: Run, goal: str = "theirs", before_s: float | None = None) -> Result:
    """A goal into ``goal``'s goal ("theirs": we scored; "ours": we conceded) before
    ``before_s`` s (default: any time in the run). Value: when."""
    goals = [e for e in run.of("goal") if e.detail == goal
             and (before_s is None or e.t <= before_s)]
    if goals:
        return _ok(True, f"goal into {goal} goal at {goals[0].t:.2f} s", goals[0].t, "s")
    late = [e for e in run.of("goal") if e.detail == goal]
    why = f" (at {late[0].t:.2f} s, after {before_s:g} s)" if late else ""
    return _ok(False, f"no goal into {goal} goal{why}", None, "s")


def keeper_saved(run: Run, after_s: float = 0.0) -> Result:
    """No goal into our goal after ``after_s`` s: the keeper (and the defence) saved."""
    goals = [e for e in run.of("goal") if e.detail == "ours" and e.t >= after_s]
    if goals:
        return _ok(False, f"conceded at {goals[0].t:.2f} s", goals[0].t, "s")
    return _ok(True, "no goal conceded")


# -- the ball ---------------------------------------------------------------------------------


def ball_placed(run: Run, target: Point | None = None, tolerance_m: float = 0.15,
                before_s: float | None = None, still_mps: float = 0.1) -> Result:
    """The ball at rest (slower than ``still_mps``) within ``tolerance_m`` of ``target``
    (default: the referee's placement target) at some time before ``before_s``. Value: when;
    the score falls with the distance left at the end when it never got there."""
    tgt = target if target is not None else run.designated
    if tgt is None:
        return _ok(False, "no target: give target = [x, y] or a BALL_PLACEMENT step")
    d = np.hypot(run.ball[:, BX] - tgt[0], run.ball[:, BY] - tgt[1])
    speed = np.hypot(run.ball[:, BVX], run.ball[:, BVY])
    ok = (d <= tolerance_m) & (speed <= still_mps)
    if before_s is not None:
        ok &= run.t <= before_s
    hit = np.flatnonzero(ok)
    if hit.size:
        t = float(run.t[hit[0]])
        return _ok(True, f"placed within {tolerance_m:g} m at {t:.2f} s "
                         f"({d[hit[0]]:.3f} m off)", t, "s")
    last = float(d[-1]) if len(d) and math.isfinite(d[-1]) else math.inf
    score = max(0.0, 1.0 - (last - tolerance_m) / 1.0) * 0.5 if math.isfinite(last) else 0.0
    return _ok(False, f"not placed: {last:.3f} m from the target at the end", None, "s",
               score)


def touched_ball(run: Run, robot: int | None = None, team: str = "ours",
                 before_s: float | None = None) -> Result:
    """``robot`` (any of ``team``'s when not given) touched the ball before ``before_s``:
    an intercepted ball, a receiver that got it. Value: the first touch's time."""
    touches = [e for e in run.of("touch") if e.team == team
               and (robot is None or e.robot == robot)
               and (before_s is None or e.t <= before_s)]
    who = f"{team} robot {robot}" if robot is not None else f"a {team} robot"
    if touches:
        return _ok(True, f"{who} touched the ball at {touches[0].t:.2f} s", touches[0].t, "s")
    return _ok(False, f"{who} never touched the ball" +
               (f" before {before_s:g} s" if before_s is not None else ""), None, "s")


def pass_completed(run: Run, passer: int, receiver: int, min_distance_m: float = 1.0,
                   before_s: float | None = None) -> Result:
    """Our ``passer`` kicked the ball and our ``receiver`` touched it next, at least
    ``min_distance_m`` away (nobody else touched it between). Value: passes completed."""
    done = 0
    first: float | None = None
    kick: Event | None = None
    for e in run.events:
        if before_s is not None and e.t > before_s:
            break
        if e.kind == "kick":
            kick = e if (e.team == "ours" and e.robot == passer) else None
            continue
        if e.kind != "touch" or kick is None:
            continue
        if e.team == "ours" and e.robot == passer:
            continue  # the kicker's own touch (the kick itself)
        if e.team == "ours" and e.robot == receiver:
            i, j = run.index_at(kick.t), run.index_at(e.t)
            moved = math.hypot(run.ball[j, BX] - run.ball[i, BX], run.ball[j, BY] - run.ball[i, BY])
            if moved >= min_distance_m:
                done += 1
                first = e.t if first is None else first
        kick = None
    if done:
        return _ok(True, f"{done} pass(es) from {passer} to {receiver}, the first received at "
                         f"{first:.2f} s", float(done), "passes")
    return _ok(False, f"no pass from {passer} to {receiver} received", 0.0, "passes")


# -- robots -----------------------------------------------------------------------------------


def reach(run: Run, robot: int, target: Point, tolerance_m: float = 0.1,
          within_s: float | None = None, hold_s: float = 0.0,
          heading_deg: float | None = None, heading_tolerance_deg: float = 10.0) -> Result:
    """Our ``robot`` within ``tolerance_m`` of ``target`` (and, with ``heading_deg``, facing
    that way within ``heading_tolerance_deg``) before ``within_s``, staying there ``hold_s``.
    Value: the time it got there (time to reach)."""
    r = run.robot("ours", robot)
    ok = _dist(run, r, target) <= tolerance_m
    if heading_deg is not None:
        ok &= _angle_diff(r[:, RHEADING], math.radians(heading_deg)) <= math.radians(
            heading_tolerance_deg)
    t_reach = _first_held(run.t, ok, hold_s)
    if t_reach is not None and (within_s is None or t_reach <= within_s):
        return _ok(True, f"robot {robot} reached ({target[0]:g}, {target[1]:g}) at "
                         f"{t_reach:.2f} s", t_reach, "s")
    d_end = float(_dist(run, r, target)[-1]) if len(r) else math.inf
    late = f" at {t_reach:.2f} s, after {within_s:g} s" if t_reach is not None else ""
    return _ok(False, f"robot {robot} did not reach ({target[0]:g}, {target[1]:g}){late}; "
                      f"{d_end:.2f} m away at the end", t_reach, "s")


def _first_held(t: np.ndarray, ok: np.ndarray, hold_s: float) -> float | None:
    """The first time ``ok`` holds and keeps holding for ``hold_s`` (to the run's end at
    least, when the run ends sooner)."""
    idx = np.flatnonzero(ok)
    if idx.size == 0:
        return None
    if hold_s <= 0:
        return float(t[idx[0]])
    start = None
    for i in range(len(t)):
        if ok[i]:
            if start is None:
                start = i
            if t[i] - t[start] >= hold_s or i == len(t) - 1:
                return float(t[start])
        else:
            start = None
    return None


def time_to_reach(run: Run, robot: int, target: Point, good_s: float, bad_s: float,
                  tolerance_m: float = 0.1) -> Result:
    """Time for our ``robot`` to get within ``tolerance_m`` of ``target``: score 1 at
    ``good_s`` or sooner, falling to 0 at ``bad_s``; passes up to ``bad_s``."""
    r = run.robot("ours", robot)
    t_reach = _first_held(run.t, _dist(run, r, target) <= tolerance_m, 0.0)
    if t_reach is None:
        return _ok(False, f"robot {robot} never got within {tolerance_m:g} m", None, "s")
    span = max(1e-9, bad_s - good_s)
    score = 1.0 - (t_reach - good_s) / span
    return _ok(t_reach <= bad_s, f"robot {robot} reached it in {t_reach:.2f} s "
                                 f"(good {good_s:g} s, bad {bad_s:g} s)", t_reach, "s", score)


def path_length(run: Run, robot: int, max_m: float | None = None,
                max_ratio: float | None = None, target: Point | None = None) -> Result:
    """The length of our ``robot``'s path over the run: at most ``max_m``, and/or at most
    ``max_ratio`` times the straight line from its start to ``target`` (default: to where it
    ended). Value: the length (m)."""
    r = run.robot("ours", robot)
    xy = r[:, [RX, RY]]
    xy = xy[np.isfinite(xy).all(axis=1)]
    if len(xy) < 2:
        return _ok(False, f"robot {robot} was not on the field", None, "m")
    length = float(np.hypot(*np.diff(xy, axis=0).T).sum())
    end = target if target is not None else (float(xy[-1, 0]), float(xy[-1, 1]))
    straight = math.hypot(end[0] - xy[0, 0], end[1] - xy[0, 1])
    ratio = length / straight if straight > 1e-6 else math.inf
    ok = (max_m is None or length <= max_m) and (max_ratio is None or ratio <= max_ratio)
    score = 1.0 if ok else max(0.0, min(
        1.0, (max_ratio / ratio) if max_ratio and math.isfinite(ratio) else
        (max_m / length if max_m else 0.0)))
    return _ok(ok, f"robot {robot} drove {length:.2f} m ({ratio:.2f}x the straight "
                   f"{straight:.2f} m)", length, "m", score)


def face_ball(run: Run, robot: int, tolerance_deg: float = 10.0,
              from_s: float | None = None) -> Result:
    """Our ``robot`` faces the ball (heading within ``tolerance_deg`` of the direction to it)
    from ``from_s`` (default: the last second) to the end. Value: the worst error (deg); the
    score is the share of that time it faced it."""
    r = run.robot("ours", robot)
    start = (run.duration_s - 1.0) if from_s is None else from_s
    sel = run.t >= start
    if not sel.any():
        return _ok(False, f"no samples after {start:g} s", None, "deg")
    bearing = np.arctan2(run.ball[sel, BY] - r[sel, RY], run.ball[sel, BX] - r[sel, RX])
    err = np.degrees(_angle_diff(r[sel, RHEADING], bearing))
    err = err[np.isfinite(err)]
    if err.size == 0:
        return _ok(False, "robot or ball not seen", None, "deg")
    share = float(np.mean(err <= tolerance_deg))
    worst = float(err.max())
    return _ok(worst <= tolerance_deg, f"robot {robot}: worst heading error to the ball "
                                       f"{worst:.1f} deg ({100 * share:.0f} % within "
                                       f"{tolerance_deg:g} deg)", worst, "deg", share)


# -- rules ------------------------------------------------------------------------------------


def no_collision(run: Run, team: str = "ours", min_speed_mps: float = 0.0) -> Result:
    """No robot of ``team`` touched another robot faster than ``min_speed_mps`` (relative
    speed; the rules count 1.5 m/s). Value: the number of collisions."""
    hits = [e for e in run.of("collision") if team in (e.team, e.data.get("other_team"))
            and float(e.data.get("relative_speed_mps", 0.0)) > min_speed_mps]
    if not hits:
        return _ok(True, "no collision", 0.0, "collisions")
    e = hits[0]
    return _ok(False, f"{len(hits)} collision(s); the first at {e.t:.2f} s ({e.team} "
                      f"{e.robot} and {e.data.get('other_team')} {e.data.get('other')}, "
                      f"{float(e.data.get('relative_speed_mps', 0.0)):.2f} m/s)",
               float(len(hits)), "collisions")


def no_violation(run: Run, team: str = "ours", kinds: tuple[str, ...] | None = None) -> Result:
    """No rule violation by ``team`` as the match judge counts them (``kinds``: only these:
    halt_moving, stop_speed, stop_distance, set_piece_distance, placement_distance,
    defense_area, kickoff_position, penalty_position, collision). Value: how many."""
    found = [e for e in run.of("violation") if e.team == team
             and (kinds is None or e.detail in kinds)]
    if not found:
        return _ok(True, "no violation" + (f" ({', '.join(kinds)})" if kinds else ""), 0.0,
                   "violations")
    e = found[0]
    return _ok(False, f"{len(found)} violation(s); the first at {e.t:.2f} s: "
                      f"{e.data.get('text', e.detail)}", float(len(found)), "violations")


# -- the registry -----------------------------------------------------------------------------

BUILTIN: dict[str, Callable[..., Result]] = {f.__name__: f for f in (
    ball_in_goal, keeper_saved, ball_placed, touched_ball, pass_completed, reach,
    time_to_reach, path_length, face_ball, no_collision, no_violation)}


def _signature_of(fn: Callable[..., Any]) -> CheckSignature:
    import ast
    import textwrap

    tree = ast.parse(textwrap.dedent(inspect.getsource(fn)))
    node = tree.body[0]
    assert isinstance(node, ast.FunctionDef)
    return check_signature_from_ast(node)


_SIGS: dict[str, CheckSignature] | None = None


def builtin_signatures() -> Mapping[str, CheckSignature]:
    global _SIGS
    if _SIGS is None:
        _SIGS = {name: _signature_of(fn) for name, fn in BUILTIN.items()}
    return _SIGS


def load_custom(checks_py: str | Path) -> dict[str, Callable[..., Result]]:
    """A suite's checks.py imported (in the worker that runs the scenario, never in the
    station's process), its public functions by name."""
    path = Path(checks_py)
    name = f"evaluate_suite_checks_{abs(hash(str(path.resolve())))}"
    mod = sys.modules.get(name)
    if mod is None:
        spec = importlib.util.spec_from_file_location(name, path)
        if spec is None or spec.loader is None:
            raise ImportError(f"cannot import {path}")
        mod = importlib.util.module_from_spec(spec)
        sys.modules[name] = mod
        try:
            spec.loader.exec_module(mod)
        except BaseException:
            del sys.modules[name]
            raise
    assert isinstance(mod, ModuleType)
    return {k: v for k, v in vars(mod).items()
            if inspect.isfunction(v) and not k.startswith("_") and v.__module__ == name}


def run_check(fn: Callable[..., Any], run: Run, params: Mapping[str, Any]) -> Result:
    """Calls a check; an exception or a result of the wrong type is a failed check that says
    so (a team's own check must not take the whole report down)."""
    try:
        res = fn(run, **params)
    except Exception as exc:
        return Result(False, 0.0, f"the check failed: {type(exc).__name__}: {exc}")
    if not isinstance(res, Result):
        return Result(False, 0.0, f"the check returned {type(res).__name__}, not a Result")
    if not math.isfinite(res.score):
        return Result(False, 0.0, f"the check's score is {res.score}")
    return res
