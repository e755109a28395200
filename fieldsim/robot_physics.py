"""Robot motion: commanded local velocity with gain, limits and timeout; contacts; goal walls.

Robots are discs driven by a commanded LOCAL velocity (forward = along the heading towards the
kicker, left, angular ccw) scaled by a per-robot gain C, with acceleration and speed limits;
like grSim they brake to a stop once no command arrived for ``command_timeout_s``. Overlapping
robots are pushed apart (a few relaxation passes) and a pair coming into contact is reported
once (``Contact``) with the closing speed, so the World can raise a ``collision`` event.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from domain.angles import wrap_angle
from fieldsim.bodies import Robot, RobotKey
from fieldsim.config import SimConfig
from fieldsim.shapes import Rect, clamp, push_out_of_rect

CONTACT_HYSTERESIS_M = 0.005  # a robot pair stays "in contact" until this far apart


@dataclass(frozen=True)
class Contact:
    """Two robots that just came into contact: velocities before resolution, contact normal."""

    a: Robot
    b: Robot
    va: tuple[float, float]
    vb: tuple[float, float]
    nx: float
    ny: float


class RobotPhysics:
    """Steps the robots of a World; remembers which pairs are in contact."""

    def __init__(self, config: SimConfig, wall_x: float, wall_y: float,
                 goal_walls: list[Rect], half_length: float) -> None:
        self.config = config
        self._wall_x, self._wall_y = wall_x, wall_y
        self._goal_walls = goal_walls
        self._hl = half_length
        self._contacts: set[tuple[RobotKey, RobotKey]] = set()

    def step(self, robots: dict[RobotKey, Robot], t: float, h: float) -> list[Contact]:
        """Move every robot by ``h`` seconds at simulated time ``t``; the new contacts."""
        self._drive(robots, t, h)
        contacts = self._collide(robots)
        self._vs_goals(robots)
        return contacts

    def _drive(self, robots: dict[RobotKey, Robot], t: float, h: float) -> None:
        cfg = self.config
        R = cfg.robot_radius_m
        max_dv = cfg.robot_max_accel * h
        max_dw = cfg.robot_max_angular_accel * h
        for robot in robots.values():
            cmd = robot.command
            if cmd is not None and t - cmd.received_at <= cfg.command_timeout_s:
                c = robot.gain
                fwd, lft, w = c * cmd.forward, c * cmd.left, c * cmd.angular
            else:
                fwd = lft = w = 0.0
            cos_t, sin_t = math.cos(robot.theta), math.sin(robot.theta)
            sx = fwd * cos_t - lft * sin_t
            sy = fwd * sin_t + lft * cos_t
            speed = math.hypot(sx, sy)
            if speed > cfg.robot_max_speed:
                sx *= cfg.robot_max_speed / speed
                sy *= cfg.robot_max_speed / speed
            w = clamp(w, -cfg.robot_max_angular_speed, cfg.robot_max_angular_speed)
            dvx, dvy = sx - robot.vx, sy - robot.vy
            dv = math.hypot(dvx, dvy)
            if dv > max_dv:
                dvx *= max_dv / dv
                dvy *= max_dv / dv
            robot.vx += dvx
            robot.vy += dvy
            robot.omega += clamp(w - robot.omega, -max_dw, max_dw)
            robot.x += robot.vx * h
            robot.y += robot.vy * h
            robot.theta = wrap_angle(robot.theta + robot.omega * h)
            # outer walls
            lim_x, lim_y = self._wall_x - R, self._wall_y - R
            if robot.x > lim_x or robot.x < -lim_x:
                robot.x = clamp(robot.x, -lim_x, lim_x)
                robot.vx = 0.0
            if robot.y > lim_y or robot.y < -lim_y:
                robot.y = clamp(robot.y, -lim_y, lim_y)
                robot.vy = 0.0

    def _collide(self, robot_map: dict[RobotKey, Robot]) -> list[Contact]:
        R2 = 2.0 * self.config.robot_radius_m
        robots = list(robot_map.values())
        lim_x = self._wall_x - self.config.robot_radius_m
        lim_y = self._wall_y - self.config.robot_radius_m
        # contacts: pairs overlapping before resolution, and pairs that touched on the previous
        # step and are still within the hysteresis distance; a Contact for new ones
        reach = R2 + CONTACT_HYSTERESIS_M
        contacts: set[tuple[RobotKey, RobotKey]] = set()
        new: list[Contact] = []
        for key in self._contacts:
            a_, b_ = robot_map.get(key[0]), robot_map.get(key[1])
            if a_ is not None and b_ is not None and math.hypot(b_.x - a_.x, b_.y - a_.y) < reach:
                contacts.add(key)
        velocities = [(r.vx, r.vy) for r in robots]  # before resolution, for the events
        for sweep in range(3):  # a few relaxation passes resolve chains of contacts
            moved = False
            for i in range(len(robots)):
                a = robots[i]
                for j in range(i + 1, len(robots)):
                    b = robots[j]
                    dx, dy = b.x - a.x, b.y - a.y
                    if abs(dx) >= R2 or abs(dy) >= R2:
                        continue
                    d = math.hypot(dx, dy)
                    if d >= R2:
                        continue
                    if d < 1e-9:
                        nx, ny, d = 1.0, 0.0, 0.0
                    else:
                        nx, ny = dx / d, dy / d
                    if sweep == 0:
                        ka, kb = (a.team, a.id), (b.team, b.id)
                        key = (ka, kb) if ka < kb else (kb, ka)
                        if key not in contacts:
                            contacts.add(key)
                            new.append(Contact(a, b, velocities[i], velocities[j], nx, ny))
                    push = (R2 - d) / 2.0 + 1e-6
                    a.x -= nx * push
                    a.y -= ny * push
                    b.x += nx * push
                    b.y += ny * push
                    # remove the approaching part of the relative velocity
                    vn = (b.vx - a.vx) * nx + (b.vy - a.vy) * ny
                    if vn < 0.0:
                        a.vx += nx * vn / 2.0
                        a.vy += ny * vn / 2.0
                        b.vx -= nx * vn / 2.0
                        b.vy -= ny * vn / 2.0
                    for r in (a, b):
                        r.x = clamp(r.x, -lim_x, lim_x)
                        r.y = clamp(r.y, -lim_y, lim_y)
                    moved = True
            if not moved:
                break
        self._contacts = contacts
        return new

    def _vs_goals(self, robots: dict[RobotKey, Robot]) -> None:
        """Robots stop at the goals' back and side walls; the goal's inside is open to them
        (a real robot can drive in; a keeper on its goal line stands half in the goal)."""
        R = self.config.robot_radius_m
        reach_x = self._hl - R
        for robot in robots.values():
            if abs(robot.x) <= reach_x:
                continue
            for box in self._goal_walls:
                push = push_out_of_rect(robot.x, robot.y, box, R)
                if push is None:
                    continue
                robot.x, robot.y, nx, ny = push
                vn = robot.vx * nx + robot.vy * ny
                if vn < 0.0:  # stop the part of the motion into the goal
                    robot.vx -= vn * nx
                    robot.vy -= vn * ny
