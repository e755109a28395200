"""A proportional go-to controller with speed and acceleration limits: the baseline the
paper's Algorithms 1 and 2 (control/motion.py) are compared with, selectable per robot as
"proportional"."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import NamedTuple

from domain.angles import wrap_angle


@dataclass(frozen=True, slots=True)
class Target:
    x: float  # mm
    y: float  # mm
    orientation: float | None  # rad, None: keep the current heading


class LocalVelocity(NamedTuple):
    """A command in the robot's frame (a tuple: built in one call, not a frozen dataclass's
    three ``object.__setattr__``; one per robot step). Read by name."""

    forward_mps: float
    left_mps: float
    angular_radps: float

    @staticmethod
    def zero() -> LocalVelocity:
        return LocalVelocity(0.0, 0.0, 0.0)


@dataclass
class GoToConfig:
    kp_per_s: float = 2.5  # m/s of speed per m of error
    max_speed_mps: float = 2.0
    max_accel_mps2: float = 3.0
    kp_angle_per_s: float = 4.0
    max_angular_radps: float = 4.0
    position_tolerance_mm: float = 15.0
    angle_tolerance_rad: float = 0.03


def global_to_local(vx: float, vy: float, heading: float) -> tuple[float, float]:
    """Rotate a field-frame velocity into the robot frame (forward, left)."""
    c, s = math.cos(heading), math.sin(heading)
    return vx * c + vy * s, -vx * s + vy * c


class GoToController:
    """Per-robot state: the last commanded global velocity (for the acceleration limit)."""

    def __init__(self, config: GoToConfig | None = None) -> None:
        self.config = config or GoToConfig()
        self._last_v = (0.0, 0.0)

    def reset(self) -> None:
        self._last_v = (0.0, 0.0)

    def step(self, x_mm: float, y_mm: float, heading: float, target: Target,
             dt_s: float) -> LocalVelocity:
        cfg = self.config
        ex = (target.x - x_mm) / 1000.0
        ey = (target.y - y_mm) / 1000.0
        dist = math.hypot(ex, ey)
        if dist * 1000.0 <= cfg.position_tolerance_mm:
            vx = vy = 0.0
        else:
            # speed from the error, capped, and also capped by what can still be braked away
            speed = min(cfg.kp_per_s * dist, cfg.max_speed_mps,
                        math.sqrt(2.0 * cfg.max_accel_mps2 * dist))
            vx, vy = ex / dist * speed, ey / dist * speed
        # acceleration limit on the change of the commanded velocity
        lvx, lvy = self._last_v
        dvx, dvy = vx - lvx, vy - lvy
        dv = math.hypot(dvx, dvy)
        max_dv = cfg.max_accel_mps2 * max(dt_s, 1e-3)
        if dv > max_dv:
            vx, vy = lvx + dvx / dv * max_dv, lvy + dvy / dv * max_dv
        self._last_v = (vx, vy)
        omega = 0.0
        if target.orientation is not None:
            err = wrap_angle(target.orientation - heading)
            if abs(err) > cfg.angle_tolerance_rad:
                omega = max(-cfg.max_angular_radps,
                            min(cfg.max_angular_radps, cfg.kp_angle_per_s * err))
        fwd, left = global_to_local(vx, vy, heading)
        return LocalVelocity(fwd, left, omega)


def set_last_velocity(ctrl: GoToController, vx_mps: float, vy_mps: float) -> None:
    """Seed the acceleration limit of ``ctrl`` with a field-frame velocity that was really
    commanded last (used when another controller hands a robot over to this one)."""
    ctrl._last_v = (vx_mps, vy_mps)
