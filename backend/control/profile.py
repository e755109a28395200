"""The trapezoid speed profile x*(t) of Algorithm 1 (paper section 5.2, eq. 1).

Accelerate at w, cruise at v, decelerate at w, so that x*(T) = distance exactly and
|x*''| <= w, |x*'| <= v. Short distances never reach v: a triangle profile. An optional start
speed v0 (the robot already moving along the line) is capped at what can still be braked within
the distance, so the profile is always feasible.
"""

from __future__ import annotations

import math
from dataclasses import dataclass


@dataclass(frozen=True, slots=True)
class ProfilePoint:
    pos: float  # m from A along the line
    vel: float  # m/s
    acc: float  # m/s^2


@dataclass(frozen=True, slots=True)
class Trapezoid:
    """x*(t) from 0 to ``distance`` (m) with speed limit ``v`` (m/s) and acceleration ``w``."""

    distance: float
    v: float
    w: float
    v0: float = 0.0

    @property
    def start_speed(self) -> float:
        d = max(0.0, self.distance)
        return min(max(0.0, self.v0), self.v, math.sqrt(2.0 * self.w * d))

    @property
    def peak_speed(self) -> float:
        d = max(0.0, self.distance)
        v0 = self.start_speed
        return min(self.v, math.sqrt(self.w * d + 0.5 * v0 * v0))

    @property
    def t_w(self) -> float:
        """End of the acceleration segment (s)."""
        return (self.peak_speed - self.start_speed) / self.w

    @property
    def t_v(self) -> float:
        """End of the constant-speed segment (s); equals t_w for a triangle."""
        vp = self.peak_speed
        if vp <= 0.0:
            return 0.0
        v0 = self.start_speed
        d_acc = (vp * vp - v0 * v0) / (2.0 * self.w)
        d_dec = vp * vp / (2.0 * self.w)
        cruise = max(0.0, max(0.0, self.distance) - d_acc - d_dec)
        return self.t_w + cruise / vp

    @property
    def duration(self) -> float:
        """T: the reference is at ``distance`` with zero speed from here on."""
        return self.t_v + self.peak_speed / self.w

    @property
    def is_triangle(self) -> bool:
        return self.peak_speed < self.v

    def sample(self, t: float) -> ProfilePoint:
        return trapezoid(t, self.distance, self.v, self.w, self.v0)


def trapezoid(t: float, distance: float, v: float, w: float, v0: float = 0.0) -> ProfilePoint:
    """Pure function: the reference position, speed and acceleration at time ``t`` (s)."""
    if v <= 0.0 or w <= 0.0:
        raise ValueError("v and w must be positive")
    d = max(0.0, distance)
    s0 = min(max(0.0, v0), v, math.sqrt(2.0 * w * d))
    vp = min(v, math.sqrt(w * d + 0.5 * s0 * s0))
    t_w = (vp - s0) / w
    d_acc = (vp * vp - s0 * s0) / (2.0 * w)
    d_dec = vp * vp / (2.0 * w)
    cruise = max(0.0, d - d_acc - d_dec)
    t_v = t_w + (cruise / vp if vp > 0.0 else 0.0)
    t_end = t_v + vp / w
    if t <= 0.0:
        return ProfilePoint(0.0, s0, w if t_w > 0.0 else 0.0)
    if t < t_w:
        return ProfilePoint(s0 * t + 0.5 * w * t * t, s0 + w * t, w)
    if t < t_v:
        return ProfilePoint(d_acc + vp * (t - t_w), vp, 0.0)
    if t < t_end:
        r = t_end - t  # time left: distance left = w r^2 / 2, exact at the end
        return ProfilePoint(d - 0.5 * w * r * r, w * r, -w)
    return ProfilePoint(d, 0.0, 0.0)
