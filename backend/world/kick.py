"""Kick detection: a ball whose speed jumps next to a robot's front starts a :class:`KickedBall`.

Pure: fed the ball's merged measurements (capture time, mm) and the robots at each world
update, no clock, no I/O.

* Speed: the slope of a least-squares line through the measurements of the last
  ``speed_window_s``.
* Start: the speed rose by more than ``jump_mps`` compared with its lowest value in the last
  ``jump_window_s``, and at least ``min_samples`` measurements left the ball's previous line
  (fitted on 0.1 s; noise allowance ``off_line_mm``, or four times the measurements' scatter
  around that line if larger; the newest twice that far), and the line fitted through them
  (with the rolling-friction model) is faster by ``jump_mps``. The start time is where the
  kick's line meets the previous one (clamped between the last measurement on it, less the
  allowance's worth of travel, and the first off it), the start position the previous line
  at that time. The kicker is the nearest robot whose front (``front_half_angle_deg`` either
  side of its heading) holds the start position within ``robot_radius_mm + reach_mm``; no
  robot there: no kick.
* Prediction: constant deceleration ``decel_mps2`` (fieldsim's rolling friction by default):
  a ball at p with speed v along v_hat stops at p + v_hat v^2 / (2a), after v / a. The kick's
  initial velocity is fitted on its first ``start_fit_s`` (then frozen), the stop point on its
  last ``fit_window_s`` of measurements (corrected for the deceleration), so it follows a real
  ball that slows differently from the model.
* End: the ball (its slope over ``turn_window_s`` of the kick's measurements) is slower than
  ``stop_mps``, or faster than ``turn_min_mps`` and turned by more than ``max_turn_deg`` (a
  touch, a bounce: running back is a 180 degree turn), is lost or gone; a new jump starts a
  new kick.
"""

from __future__ import annotations

import math
from collections import deque
from collections.abc import Iterable, Sequence
from dataclasses import dataclass

from domain.angles import wrap_angle
from domain.rules import ROBOT_RADIUS_MM

from ..filters.core import line_sums
from .state import BallState, KickedBall, RobotState, Team

__all__ = ["KickConfig", "KickDetector", "KickedBall", "fit_rolling", "stop_of"]


@dataclass
class KickConfig:
    decel_mps2: float = 0.4  # fieldsim's ball_rolling_decel
    jump_mps: float = 1.0  # a speed rise larger than this ...
    jump_window_s: float = 0.05  # ... within this long
    speed_window_s: float = 0.04  # speed: slope over this long of measurements
    min_samples: int = 2  # measurements off the previous line before a kick starts
    off_line_mm: float = 15.0  # noise allowance of "off the previous line"
    robot_radius_mm: float = ROBOT_RADIUS_MM
    reach_mm: float = 100.0  # kick start this far beyond the robot's radius at most
    front_half_angle_deg: float = 60.0  # the front: this far either side of the heading
    stop_mps: float = 0.1  # slower than this: the kick is over
    max_turn_deg: float = 30.0  # the ball turned more than this: touched or bounced
    turn_min_mps: float = 0.3  # the turn is judged only above this speed
    turn_window_s: float = 0.1  # speed and direction while following: over this long
    start_fit_s: float = 0.1  # initial velocity fitted on this long after the start
    fit_window_s: float = 0.15  # stop prediction fitted on this long of the newest measurements


Sample = tuple[float, float, float]  # t, x, y


def _fit(pts: Sequence[Sample]) -> tuple[float, float, float, float, float] | None:
    """The means of t, x, y and the least-squares slopes: (tm, xm, ym, vx, vy), or None (the
    kick detector fits a line for every ball measurement: the sums of ``line_sums``)."""
    n = len(pts)
    if n < 2:
        return None
    tm, xm, ym, stt, sx, sy = line_sums(pts, n)
    if stt < 1e-10:
        return None
    return tm, xm, ym, sx / stt, sy / stt


def _slope(pts: Sequence[Sample]) -> tuple[float, float] | None:
    f = _fit(pts)
    return None if f is None else (f[3], f[4])


def _line(pts: Sequence[Sample]) -> tuple[Sample, tuple[float, float], float] | None:
    """Least-squares line through the points: ((t_last, x, y) on it, velocity, rms residual)."""
    f = _fit(pts)
    if f is None:
        return None
    tm, xm, ym, vx, vy = f
    n = len(pts)
    ss = 0.0
    for t, x, y in pts:
        d = t - tm
        ss += (x - xm - vx * d) ** 2 + (y - ym - vy * d) ** 2
    # residual per point, both axes; n - 2 degrees of freedom per axis
    rms = math.sqrt(ss / max(1, 2 * (n - 2))) if n > 2 else 0.0
    t = pts[-1][0]
    return (t, xm + vx * (t - tm), ym + vy * (t - tm)), (vx, vy), rms


def _rolling_points(pts: Sequence[Sample], decel: float, u: tuple[float, float] | None
                    ) -> tuple[float, list[Sample]] | None:
    """The points with the deceleration along ``u`` taken out, on a time axis from the first
    point's (t0, the points): a straight line for a ball rolling as the model says."""
    if len(pts) < 2:
        return None
    if u is None:
        s = _slope(pts)
        if s is None:
            return None
        n = math.hypot(*s)
        if n < 1e-9:
            return None
        u = (s[0] / n, s[1] / n)
    t0 = pts[0][0]
    return t0, [(p[0] - t0, p[1] + u[0] * decel * (p[0] - t0) ** 2 / 2,
                 p[2] + u[1] * decel * (p[0] - t0) ** 2 / 2) for p in pts]


def fit_rolling(pts: Sequence[Sample], decel: float,
                u: tuple[float, float] | None = None) -> tuple[Sample, tuple[float, float]] | None:
    """Fit p(tau) = p0 + w tau - u decel tau^2 / 2 (tau from the first point's time; u the unit
    direction, the plain slope's if not given): ((t0, x0, y0), w), or None."""
    c = _rolling_points(pts, decel, u)
    if c is None:
        return None
    t0, corr = c
    f = _fit(corr)
    if f is None:
        return None
    tm, xm, ym, wx, wy = f
    return (t0, xm - wx * tm, ym - wy * tm), (wx, wy)


def stop_of(x: float, y: float, vx: float, vy: float, t: float,
            decel: float) -> tuple[float, float, float]:
    """Where and when a ball rolling at (vx, vy) from (x, y) at t stops: (x, y, t)."""
    v = math.hypot(vx, vy)
    if v <= 1e-9 or decel <= 0:
        return x, y, t
    d = v * v / (2 * decel)
    return x + vx / v * d, y + vy / v * d, t + v / decel


@dataclass
class _Kick:
    robot: tuple[Team, int] | None
    t_before: float  # last measurement on the previous line
    p_before: tuple[float, float]
    v_before: tuple[float, float]
    t_first: float  # first measurement off it
    samples: list[Sample]
    u: tuple[float, float] = (1.0, 0.0)
    start: Sample = (0.0, 0.0, 0.0)
    v0: tuple[float, float] = (0.0, 0.0)
    frozen: bool = False
    stop: Sample = (0.0, 0.0, 0.0)  # t, x, y
    allow: float = 0.0  # mm, the noise allowance the start was found with
    speed0: float = 0.0  # mm/s, the fitted initial speed


class KickDetector:
    def __init__(self, config: KickConfig | None = None) -> None:
        self.config = config or KickConfig()
        self._pts: deque[Sample] = deque(maxlen=256)
        self._speeds: deque[tuple[float, float, float, float]] = deque(maxlen=256)  # t v vx vy
        self._kick: _Kick | None = None
        self._last_start = -math.inf
        self.kicks = 0  # kicks started (counter for tests and health)
        self.ended = ""  # why the last kick ended

    @property
    def kick(self) -> KickedBall | None:
        k = self._kick
        if k is None:
            return None
        return KickedBall(k.robot, k.start[1], k.start[2], k.start[0], k.v0[0], k.v0[1],
                          k.stop[1], k.stop[2], k.stop[0])

    def reset(self) -> None:
        self._pts.clear()
        self._speeds.clear()
        self._kick = None

    def _end(self, why: str) -> None:
        self._kick = None
        self.ended = why

    def update(self, samples: Iterable[Sample], ball: BallState | None,
               robots: Sequence[RobotState]) -> KickedBall | None:
        """New ball measurements (time order, newer than the ones before), the ball as the
        world model has it now (None: gone) and the robots: the kick in progress, or None."""
        for s in samples:
            if self._pts and s[0] <= self._pts[-1][0]:
                continue
            self._add(s, robots)
        if self._kick is not None and (ball is None or ball.lost or not ball.visible):
            self._end("lost")
        return self.kick

    # -- per measurement -------------------------------------------------------------------

    def _add(self, s: Sample, robots: Sequence[RobotState]) -> None:
        cfg = self.config
        t = s[0]
        self._pts.append(s)
        keep = cfg.jump_window_s + cfg.speed_window_s + 0.2
        while t - self._pts[0][0] > keep:
            self._pts.popleft()
        win: list[Sample] = []
        for p in reversed(self._pts):
            if t - p[0] > cfg.speed_window_s:
                break
            win.append(p)
        v = _slope(win) if len(win) >= 2 else None
        if v is None:
            return
        speed = math.hypot(*v)
        self._speeds.append((t, speed, v[0], v[1]))
        while t - self._speeds[0][0] > cfg.jump_window_s + 0.05:
            self._speeds.popleft()
        k = self._kick
        if k is not None:
            k.samples.append(s)
            self._follow(k, t)
        self._detect(t, speed, robots)

    def _follow(self, k: _Kick, t: float) -> None:
        cfg = self.config
        if not k.frozen:
            self._fit_start(k)
            if t - k.start[0] >= cfg.start_fit_s:
                k.frozen = True
        else:  # only the newest measurements are fitted from now on
            keep = max(cfg.fit_window_s, cfg.turn_window_s)
            while k.samples and t - k.samples[0][0] > keep:
                k.samples.pop(0)
        v = _slope([p for p in k.samples if t - p[0] <= cfg.turn_window_s])
        if v is not None:
            speed = math.hypot(*v)
            if speed < cfg.stop_mps * 1000.0:
                self._end("stopped")
                return
            if speed >= cfg.turn_min_mps * 1000.0:
                turn = abs(wrap_angle(math.atan2(v[1], v[0]) - math.atan2(k.u[1], k.u[0])))
                if turn > math.radians(cfg.max_turn_deg):
                    self._end("turned")
                    return
        self._predict(k)

    def _predict(self, k: _Kick) -> None:
        cfg = self.config
        a = cfg.decel_mps2 * 1000.0
        t_last = k.samples[-1][0]
        pts = [p for p in k.samples if t_last - p[0] <= cfg.fit_window_s]
        fit = fit_rolling(pts, a, k.u)
        if fit is None:
            return
        (t0, x0, y0), w = fit
        tau = t_last - t0
        v = max(0.0, math.hypot(*w) - a * tau)
        x = x0 + w[0] * tau - k.u[0] * a * tau * tau / 2
        y = y0 + w[1] * tau - k.u[1] * a * tau * tau / 2
        sx, sy, st = stop_of(x, y, k.u[0] * v, k.u[1] * v, t_last, a)
        k.stop = (st, sx, sy)

    def _fit_start(self, k: _Kick) -> bool:
        """Direction, start time and position, initial velocity from the first measurements."""
        cfg = self.config
        a = cfg.decel_mps2 * 1000.0
        pts = [p for p in k.samples if p[0] - k.t_first <= cfg.start_fit_s]
        fit = fit_rolling(pts, a)
        if fit is None:
            return False
        (tf, xf, yf), w = fit
        wn = math.hypot(*w)
        if wn < 1e-6:
            return False
        u = (w[0] / wn, w[1] / wn)
        # where the kick's line meets the previous one, along u
        vb = k.v_before[0] * u[0] + k.v_before[1] * u[1]
        pb = k.p_before[0] * u[0] + k.p_before[1] * u[1]
        pf = xf * u[0] + yf * u[1]
        # pb + vb (t - t_before) = pf + wn (t - tf)   (deceleration ignored over a few ms)
        den = wn - vb
        t0 = k.t_first if den <= 1e-6 else (pb - vb * k.t_before - pf + wn * tf) / den
        t0 = min(max(t0, k.t_before - k.allow / wn), k.t_first)
        sx = k.p_before[0] + k.v_before[0] * (t0 - k.t_before)
        sy = k.p_before[1] + k.v_before[1] * (t0 - k.t_before)
        v0 = wn + a * (tf - t0)
        k.u, k.start, k.v0, k.speed0 = u, (t0, sx, sy), (u[0] * v0, u[1] * v0), v0
        return True

    def _detect(self, t: float, speed: float, robots: Sequence[RobotState]) -> None:
        cfg = self.config
        ref = [e for e in self._speeds if t - cfg.jump_window_s <= e[0] < t]
        if not ref:
            return
        low = min(ref, key=lambda e: e[1])
        if speed - low[1] <= cfg.jump_mps * 1000.0:
            return
        # the previous line: fitted through the measurements of the 0.1 s up to the low
        # speed's time; their scatter around it widens the noise allowance
        t_ref = low[0]
        before = [p for p in self._pts if t_ref - 0.1 <= p[0] <= t_ref]
        if not before:
            return
        fit = _line(before)
        if fit is None:
            t_b, p_b, vbx, vby = before[-1][0], (before[-1][1], before[-1][2]), low[2], low[3]
            allow = cfg.off_line_mm
        else:
            (t_b, pbx, pby), (vbx, vby), rms = fit
            p_b = (pbx, pby)
            allow = max(cfg.off_line_mm, 4.0 * rms)
        line_t, line_p = t_b, p_b
        off: list[Sample] = []
        for p in self._pts:
            if p[0] <= t_ref:
                continue
            ex = line_p[0] + vbx * (p[0] - line_t)
            ey = line_p[1] + vby * (p[0] - line_t)
            if off or math.hypot(p[1] - ex, p[2] - ey) > allow:
                off.append(p)
            else:
                t_b, p_b = p[0], (ex, ey)
        if len(off) < cfg.min_samples:
            return
        last = off[-1]
        if math.hypot(last[1] - line_p[0] - vbx * (last[0] - line_t),
                      last[2] - line_p[1] - vby * (last[0] - line_t)) <= 2 * allow:
            return  # not clearly away from the line yet
        k = _Kick(None, t_b, p_b, (vbx, vby), off[0][0], list(off), allow=allow)
        if not self._fit_start(k) or k.start[0] <= self._last_start + cfg.jump_window_s:
            return
        if k.speed0 - math.hypot(vbx, vby) <= cfg.jump_mps * 1000.0:
            return  # the measurements off the line are not a kick's line
        if self._kick is not None and k.start[0] <= self._kick.start[0] + cfg.jump_window_s:
            return  # the jump of the kick in progress
        robot = self._kicker(k.start[1], k.start[2], robots)
        if robot is None:
            return
        k.robot = robot
        k.frozen = t - k.start[0] >= cfg.start_fit_s
        self._kick = k
        self._last_start = k.start[0]
        self.kicks += 1
        self._predict(k)

    def _kicker(self, x: float, y: float,
                robots: Sequence[RobotState]) -> tuple[Team, int] | None:
        cfg = self.config
        reach = cfg.robot_radius_mm + cfg.reach_mm
        half = math.radians(cfg.front_half_angle_deg)
        best: tuple[Team, int] | None = None
        best_d = math.inf
        for r in robots:
            if r.lost:
                continue
            d = math.hypot(x - r.x, y - r.y)
            if d > reach or d >= best_d:
                continue
            if abs(wrap_angle(math.atan2(y - r.y, x - r.x) - r.orientation)) > half:
                continue
            best, best_d = (r.team, r.id), d
        return best
