"""A tiny plant for the controller tests: x' = C u (the paper's model, eq. 2), in 2-D."""

from __future__ import annotations

import math
from dataclasses import dataclass

from backend.control.goto import LocalVelocity, Target
from backend.control.motion import MotionController, RobotMotionState


@dataclass
class Plant:
    x_mm: float = 0.0
    y_mm: float = 0.0
    theta: float = 0.0
    gain: float = 1.0  # C
    blocked: bool = False

    def state(self) -> RobotMotionState:
        return RobotMotionState(self.x_mm, self.y_mm, self.theta)

    def apply(self, v: LocalVelocity, dt: float) -> tuple[float, float]:
        """Move by C * command for dt; returns the commanded field-frame velocity."""
        c, s = math.cos(self.theta), math.sin(self.theta)
        vx = v.forward_mps * c - v.left_mps * s
        vy = v.forward_mps * s + v.left_mps * c
        if not self.blocked:
            self.x_mm += self.gain * vx * dt * 1000.0
            self.y_mm += self.gain * vy * dt * 1000.0
        self.theta += self.gain * v.angular_radps * dt
        return vx, vy


def drive(ctrl: MotionController, plant: Plant, target: Target, seconds: float,
          dt: float = 1 / 60) -> list[tuple[float, float]]:
    """Run ``seconds``; returns the commanded field-frame velocities, one per tick."""
    out = []
    for _ in range(round(seconds / dt)):
        v = ctrl.step(plant.state(), target, dt)
        out.append(plant.apply(v, dt))
    return out
