"""Ball motion: ballistic flight with damped bounces, rolling friction, walls.

A chipped ball (``vz > 0``) flies on an exact parabola under ``gravity`` (no air drag, no
rolling while in the air); on landing within a step the landing instant is found and the ball
bounces with ``chip_bounce_restitution`` times its vertical speed for the rest of the step,
until a bounce would be slower than ``MIN_BOUNCE_MPS``: then it rolls. On the ground it
decelerates at ``ball_rolling_decel``. The outer walls reflect it (``ball_wall_restitution``);
the goals' thin walls stop it with a swept test (``goal_wall_restitution``) unless it flies
above ``goal_height``.
"""

from __future__ import annotations

import math

from fieldsim.bodies import Ball
from fieldsim.config import SimConfig
from fieldsim.shapes import EPS, Rect, clamp, push_out_of_rect, sweep_circle_rect

MIN_BOUNCE_MPS = 0.3  # a bounce slower than this ends the flight: the ball rolls


def flight_time(vz: float, gravity: float) -> float:
    """Seconds from leaving the ground at ``vz`` (m/s) to landing again."""
    return 2.0 * vz / gravity if vz > 0 else 0.0


def apex(vz: float, gravity: float) -> float:
    """Height (m) of the flight of a ball leaving the ground at ``vz``."""
    return vz * vz / (2.0 * gravity) if vz > 0 else 0.0


class BallPhysics:
    """Moves one ball by a step; counts nothing itself (the World keeps the statistics)."""

    def __init__(self, config: SimConfig, wall_x: float, wall_y: float,
                 goal_walls: list[Rect], half_length: float, goal_height: float) -> None:
        self.config = config
        self._wall_x, self._wall_y = wall_x, wall_y
        self._goal_walls = goal_walls
        self._hl = half_length
        self._goal_height = goal_height

    def fly(self, ball: Ball, h: float) -> int:
        """The vertical motion over ``h`` seconds; the number of bounces (landings) in it."""
        if ball.z <= 0.0 and ball.vz <= 0.0:
            ball.z, ball.vz = 0.0, 0.0
            return 0
        g = self.config.gravity
        e = self.config.chip_bounce_restitution
        left, landings = h, 0
        while left > 0.0:
            # z(t) = z + vz t - g t^2 / 2 reaches 0 at the larger root
            t_land = (ball.vz + math.sqrt(ball.vz * ball.vz + 2.0 * g * ball.z)) / g
            if t_land > left:
                ball.z += ball.vz * left - g * left * left / 2.0
                ball.vz -= g * left
                return landings
            landings += 1
            left -= t_land
            v_up = (g * t_land - ball.vz) * e  # the landing speed, damped, upwards
            ball.z = 0.0
            if v_up < MIN_BOUNCE_MPS:
                ball.vz = 0.0
                return landings
            ball.vz = v_up
        return landings

    def roll(self, ball: Ball, h: float) -> None:
        """Rolling friction while on the ground."""
        speed = math.hypot(ball.vx, ball.vy)
        if ball.z == 0.0 and speed > 0.0:
            dec = self.config.ball_rolling_decel * h
            if speed <= dec:
                ball.vx = ball.vy = 0.0
            else:
                k = (speed - dec) / speed
                ball.vx *= k
                ball.vy *= k

    def outer_walls(self, ball: Ball) -> int:
        """Reflect the ball off the outer walls; the number of bounces."""
        r = self.config.ball_radius_m
        e = self.config.ball_wall_restitution
        lim_x, lim_y = self._wall_x - r, self._wall_y - r
        n = 0
        if ball.x > lim_x:
            ball.x, ball.vx = 2 * lim_x - ball.x, -abs(ball.vx) * e
            n += 1
        elif ball.x < -lim_x:
            ball.x, ball.vx = -2 * lim_x - ball.x, abs(ball.vx) * e
            n += 1
        if ball.y > lim_y:
            ball.y, ball.vy = 2 * lim_y - ball.y, -abs(ball.vy) * e
            n += 1
        elif ball.y < -lim_y:
            ball.y, ball.vy = -2 * lim_y - ball.y, abs(ball.vy) * e
            n += 1
        ball.x = clamp(ball.x, -lim_x, lim_x)
        ball.y = clamp(ball.y, -lim_y, lim_y)
        return n

    def goal_walls(self, ball: Ball, x0: float, y0: float) -> int:
        """The ball moved from (x0, y0) to its position: stop it at the first goal wall hit;
        the number of bounces."""
        r = self.config.ball_radius_m
        if ball.z >= self._goal_height:
            return 0  # above the goal
        near = self._hl - r  # |x| is convex along the path: both ends short of it, no wall
        if abs(x0) < near and abs(ball.x) < near:
            return 0
        e = self.config.goal_wall_restitution
        n = 0
        best: tuple[float, float, float] | None = None  # t, nx, ny
        for wall in self._goal_walls:
            if push_out_of_rect(x0, y0, wall, r, tol=1e-7) is not None:
                # started inside (teleport, landed from a chip): push out where it is now
                push = push_out_of_rect(ball.x, ball.y, wall, r)
                if push is not None:
                    ball.x, ball.y, nx, ny = push
                    n += reflect(ball, nx, ny, e)
                continue
            hit = sweep_circle_rect(x0, y0, ball.x, ball.y, wall, r)
            if hit is not None and (best is None or hit[0] < best[0]):
                best = hit
        if best is not None:
            t, nx, ny = best
            ball.x = x0 + t * (ball.x - x0) + nx * EPS
            ball.y = y0 + t * (ball.y - y0) + ny * EPS
            n += reflect(ball, nx, ny, e)
        return n


def reflect(ball: Ball, nx: float, ny: float, e: float) -> int:
    """Reflect the ball's ground velocity off a wall with normal (nx, ny): 1 if it bounced."""
    vn = ball.vx * nx + ball.vy * ny
    if vn < 0.0:
        ball.vx -= (1.0 + e) * vn * nx
        ball.vy -= (1.0 + e) * vn * ny
        return 1
    return 0
