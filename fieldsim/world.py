"""Pure physics core: robots and ball on the field, advanced by ``World.step(dt)``.

No I/O and no wall clock: ``World.t`` is simulated seconds since start. Units inside are SI
(m, m/s, rad); geometry sizes (mm) are converted once. Robots are discs driven by a commanded
LOCAL velocity (forward = along the heading towards the kicker, left, angular ccw) scaled by a
per-robot gain C, with acceleration and speed limits, like grSim they brake to a stop once no
command arrived for ``command_timeout_s``. The ball rolls with constant friction, bounces off the
outer walls and robots, and is kicked by an armed kicker that it touches.
"""

from __future__ import annotations

import enum
import math
import random
from dataclasses import dataclass
from typing import Any

from fieldsim.config import SimConfig
from fieldsim.geometry import FieldGeometry, division_geometry

MAX_ROBOT_ID = 15
ROBOT_HEIGHT_M = 0.15


class Team(enum.IntEnum):
    """Same numbers as ssl_gc_common.Team."""

    YELLOW = 1
    BLUE = 2

    @property
    def label(self) -> str:
        return "yellow" if self is Team.YELLOW else "blue"


@dataclass
class Command:
    """The latest command of one robot (local frame, before the gain C)."""

    forward: float = 0.0  # m/s
    left: float = 0.0  # m/s
    angular: float = 0.0  # rad/s ccw
    kick_speed: float = 0.0  # m/s, 3D speed; 0 = kicker not armed
    kick_angle: float = 0.0  # rad above ground, 0 = straight kick
    dribbler_rpm: float = 0.0
    received_at: float = 0.0  # World.t when it arrived


@dataclass
class Robot:
    team: Team
    id: int
    x: float  # m
    y: float  # m
    theta: float  # rad, ccw from +x
    gain: float = 1.0  # C: actual velocity setpoint = C * commanded
    vx: float = 0.0  # m/s, field frame
    vy: float = 0.0
    omega: float = 0.0  # rad/s
    command: Command | None = None
    ball_contact: bool = False
    kicks: int = 0


@dataclass
class Ball:
    x: float = 0.0  # m
    y: float = 0.0
    z: float = 0.0
    vx: float = 0.0  # m/s
    vy: float = 0.0
    vz: float = 0.0


def wrap_angle(a: float) -> float:
    """Angle in [-pi, pi)."""
    return (a + math.pi) % (2.0 * math.pi) - math.pi


# Formation in fractions of (half length, half width) on the negative-x half, 11 slots.
_FORMATION: tuple[tuple[float, float], ...] = (
    (-0.9, 0.0),
    (-0.65, -0.35),
    (-0.65, 0.35),
    (-0.4, -0.7),
    (-0.4, 0.7),
    (-0.25, 0.0),
    (-0.45, 0.0),
    (-0.2, -0.4),
    (-0.2, 0.4),
    (-0.8, -0.65),
    (-0.8, 0.65),
)


def formation(n: int, side: int, geometry: FieldGeometry) -> list[tuple[float, float, float]]:
    """``n`` start poses (x m, y m, theta rad) on the half with sign ``side`` (-1 or +1)."""
    hl = geometry.half_length / 1000.0
    hw = geometry.half_width / 1000.0
    poses = []
    for fx, fy in _FORMATION[:n]:
        if side < 0:
            poses.append((fx * hl, fy * hw, 0.0))
        else:
            poses.append((-fx * hl, -fy * hw, math.pi))
    return poses


@dataclass
class WorldStats:
    kicks: int = 0
    ball_wall_bounces: int = 0
    steps: int = 0


class World:
    """The true state of the field. Deterministic: same config and calls give the same state."""

    def __init__(self, config: SimConfig | None = None, geometry: FieldGeometry | None = None):
        self.config = config if config is not None else SimConfig()
        self.config.validate()
        self.geometry = geometry if geometry is not None else division_geometry(
            self.config.division
        )
        self.t = 0.0
        self.dt = 1.0 / self.config.physics_hz
        self.ball = Ball()
        self.robots: dict[tuple[Team, int], Robot] = {}
        self.stats = WorldStats()
        self._gains = self._draw_gains()
        self._wall_x = self.geometry.wall_x / 1000.0
        self._wall_y = self.geometry.wall_y / 1000.0
        blue_side = 1 if self.config.blue_on_positive_half else -1
        for team, n, side in (
            (Team.BLUE, self.config.blue, blue_side),
            (Team.YELLOW, self.config.yellow, -blue_side),
        ):
            for rid, (x, y, th) in enumerate(formation(n, side, self.geometry)):
                self.add_robot(team, rid, x, y, th)

    # -- setup -------------------------------------------------------------------------------

    def _draw_gains(self) -> dict[tuple[Team, int], float]:
        cfg = self.config
        slots = [(team, rid) for team in (Team.BLUE, Team.YELLOW) for rid in range(16)]
        if cfg.generation == 2:
            return {slot: 1.0 for slot in slots}
        if cfg.gains:
            return {slot: cfg.gains[i % len(cfg.gains)] for i, slot in enumerate(slots)}
        rng = random.Random(f"fieldsim-gains-{cfg.seed}")
        return {slot: rng.uniform(cfg.gain_min, cfg.gain_max) for slot in slots}

    def gain_of(self, team: Team, rid: int) -> float:
        return self._gains[(team, rid)]

    # -- commands and teleports --------------------------------------------------------------

    def robot(self, team: Team, rid: int) -> Robot | None:
        return self.robots.get((team, rid))

    def add_robot(self, team: Team, rid: int, x: float, y: float, theta: float) -> Robot:
        """Put a robot on the field (replaces one with the same id). Raises for bad ids."""
        if not 0 <= rid <= MAX_ROBOT_ID:
            raise ValueError(f"robot id {rid} out of 0..{MAX_ROBOT_ID}")
        robot = Robot(team, rid, x, y, wrap_angle(theta), gain=self._gains[(team, rid)])
        self.robots[(team, rid)] = robot
        return robot

    def remove_robot(self, team: Team, rid: int) -> bool:
        return self.robots.pop((team, rid), None) is not None

    def set_command(
        self,
        team: Team,
        rid: int,
        forward: float,
        left: float,
        angular: float,
        kick_speed: float = 0.0,
        kick_angle: float = 0.0,
        dribbler_rpm: float = 0.0,
    ) -> bool:
        """Store the latest command of a robot; False if it is not on the field.

        Non-finite values are the caller's error: the robot is stopped and ValueError raised.
        """
        robot = self.robots.get((team, rid))
        if robot is None:
            return False
        values = (forward, left, angular, kick_speed, kick_angle, dribbler_rpm)
        if not all(math.isfinite(v) for v in values):
            robot.command = Command(received_at=self.t)
            raise ValueError("non-finite value in robot command")
        robot.command = Command(
            forward, left, angular, max(0.0, kick_speed), kick_angle, dribbler_rpm, self.t
        )
        return True

    def stop_robot(self, team: Team, rid: int) -> None:
        robot = self.robots.get((team, rid))
        if robot is not None:
            robot.command = Command(received_at=self.t)

    def teleport_ball(
        self, x: float, y: float, vx: float = 0.0, vy: float = 0.0, z: float = 0.0, vz: float = 0.0
    ) -> None:
        values = (x, y, vx, vy, z, vz)
        if not all(math.isfinite(v) for v in values):
            raise ValueError("non-finite ball teleport")
        r = self.config.ball_radius_m
        self.ball = Ball(
            _clamp(x, -self._wall_x + r, self._wall_x - r),
            _clamp(y, -self._wall_y + r, self._wall_y - r),
            max(0.0, z),
            vx,
            vy,
            vz,
        )

    def teleport_robot(
        self,
        team: Team,
        rid: int,
        x: float | None = None,
        y: float | None = None,
        theta: float | None = None,
        vx: float = 0.0,
        vy: float = 0.0,
        omega: float = 0.0,
        add: bool = True,
    ) -> bool:
        """Move (or, with ``add``, create) a robot; missing x/y/theta keep the current value."""
        for v in (x, y, theta, vx, vy, omega):
            if v is not None and not math.isfinite(v):
                raise ValueError("non-finite robot teleport")
        robot = self.robots.get((team, rid))
        if robot is None:
            if not add:
                return False
            robot = self.add_robot(team, rid, 0.0, 0.0, 0.0)
        R = self.config.robot_radius_m
        if x is not None:
            robot.x = _clamp(x, -self._wall_x + R, self._wall_x - R)
        if y is not None:
            robot.y = _clamp(y, -self._wall_y + R, self._wall_y - R)
        if theta is not None:
            robot.theta = wrap_angle(theta)
        robot.vx, robot.vy, robot.omega = vx, vy, omega
        robot.command = None
        return True

    # -- physics -----------------------------------------------------------------------------

    def step(self, dt: float | None = None) -> None:
        """Advance the world by ``dt`` seconds (default: one physics tick)."""
        h = self.dt if dt is None else dt
        self._step_robots(h)
        self._collide_robots()
        self._step_ball(h)
        self.t += h
        self.stats.steps += 1

    def _step_robots(self, h: float) -> None:
        cfg = self.config
        R = cfg.robot_radius_m
        max_dv = cfg.robot_max_accel * h
        max_dw = cfg.robot_max_angular_accel * h
        for robot in self.robots.values():
            cmd = robot.command
            if cmd is not None and self.t - cmd.received_at <= cfg.command_timeout_s:
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
            w = _clamp(w, -cfg.robot_max_angular_speed, cfg.robot_max_angular_speed)
            dvx, dvy = sx - robot.vx, sy - robot.vy
            dv = math.hypot(dvx, dvy)
            if dv > max_dv:
                dvx *= max_dv / dv
                dvy *= max_dv / dv
            robot.vx += dvx
            robot.vy += dvy
            robot.omega += _clamp(w - robot.omega, -max_dw, max_dw)
            robot.x += robot.vx * h
            robot.y += robot.vy * h
            robot.theta = wrap_angle(robot.theta + robot.omega * h)
            # outer walls
            lim_x, lim_y = self._wall_x - R, self._wall_y - R
            if robot.x > lim_x or robot.x < -lim_x:
                robot.x = _clamp(robot.x, -lim_x, lim_x)
                robot.vx = 0.0
            if robot.y > lim_y or robot.y < -lim_y:
                robot.y = _clamp(robot.y, -lim_y, lim_y)
                robot.vy = 0.0

    def _collide_robots(self) -> None:
        R2 = 2.0 * self.config.robot_radius_m
        robots = list(self.robots.values())
        lim_x = self._wall_x - self.config.robot_radius_m
        lim_y = self._wall_y - self.config.robot_radius_m
        for _ in range(3):  # a few relaxation passes resolve chains of contacts
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
                        r.x = _clamp(r.x, -lim_x, lim_x)
                        r.y = _clamp(r.y, -lim_y, lim_y)
                    moved = True
            if not moved:
                break

    def _step_ball(self, h: float) -> None:
        cfg = self.config
        ball = self.ball
        # vertical (chip): gravity and damped bounces
        if ball.z > 0.0 or ball.vz != 0.0:
            ball.vz -= cfg.gravity * h
            ball.z += ball.vz * h
            if ball.z <= 0.0:
                ball.z = 0.0
                ball.vz = -ball.vz * cfg.chip_bounce_restitution
                if ball.vz < 0.3:
                    ball.vz = 0.0
        # rolling friction on the ground
        speed = math.hypot(ball.vx, ball.vy)
        if ball.z == 0.0 and speed > 0.0:
            dec = cfg.ball_rolling_decel * h
            if speed <= dec:
                ball.vx = ball.vy = 0.0
            else:
                k = (speed - dec) / speed
                ball.vx *= k
                ball.vy *= k
        ball.x += ball.vx * h
        ball.y += ball.vy * h
        # outer walls
        r = cfg.ball_radius_m
        e = cfg.ball_wall_restitution
        lim_x, lim_y = self._wall_x - r, self._wall_y - r
        if ball.x > lim_x:
            ball.x, ball.vx = 2 * lim_x - ball.x, -abs(ball.vx) * e
            self.stats.ball_wall_bounces += 1
        elif ball.x < -lim_x:
            ball.x, ball.vx = -2 * lim_x - ball.x, abs(ball.vx) * e
            self.stats.ball_wall_bounces += 1
        if ball.y > lim_y:
            ball.y, ball.vy = 2 * lim_y - ball.y, -abs(ball.vy) * e
            self.stats.ball_wall_bounces += 1
        elif ball.y < -lim_y:
            ball.y, ball.vy = -2 * lim_y - ball.y, abs(ball.vy) * e
            self.stats.ball_wall_bounces += 1
        ball.x = _clamp(ball.x, -lim_x, lim_x)
        ball.y = _clamp(ball.y, -lim_y, lim_y)
        self._ball_vs_robots()

    def _ball_vs_robots(self) -> None:
        cfg = self.config
        ball = self.ball
        R, r = cfg.robot_radius_m, cfg.ball_radius_m
        contact_d = R + r
        reach = R + r + cfg.kicker_reach_m
        for robot in self.robots.values():
            dx, dy = ball.x - robot.x, ball.y - robot.y
            if abs(dx) > reach or abs(dy) > reach:
                robot.ball_contact = False
                continue
            d = math.hypot(dx, dy)
            if d < 1e-9:
                dx, dy, d = math.cos(robot.theta), math.sin(robot.theta), 1.0
            nx, ny = dx / d, dy / d
            on_ground = ball.z < ROBOT_HEIGHT_M
            if on_ground and d < contact_d:
                # push the ball out of the robot and reflect the approaching relative velocity
                ball.x = robot.x + nx * contact_d
                ball.y = robot.y + ny * contact_d
                vn = (ball.vx - robot.vx) * nx + (ball.vy - robot.vy) * ny
                if vn < 0.0:
                    k = (1.0 + cfg.ball_robot_restitution) * vn
                    ball.vx -= k * nx
                    ball.vy -= k * ny
                d = contact_d
            bearing = wrap_angle(math.atan2(ny, nx) - robot.theta)
            in_front = abs(bearing) <= cfg.kicker_half_angle_rad
            robot.ball_contact = on_ground and in_front and d <= reach
            cmd = robot.command
            if (
                robot.ball_contact
                and cmd is not None
                and cmd.kick_speed > 0.0
                and self.t - cmd.received_at <= cfg.command_timeout_s
            ):
                speed = min(cmd.kick_speed, cfg.ball_max_speed)
                ground = speed * math.cos(cmd.kick_angle)
                ball.vx = ground * math.cos(robot.theta)
                ball.vy = ground * math.sin(robot.theta)
                ball.vz = max(0.0, speed * math.sin(cmd.kick_angle))
                if ball.vz > 0.0:
                    ball.z = max(ball.z, 1e-6)
                cmd.kick_speed = 0.0  # one kick per command
                robot.kicks += 1
                self.stats.kicks += 1

    # -- truth -------------------------------------------------------------------------------

    def truth(self) -> dict[str, Any]:
        """The true state as plain data: mm, mm/s, rad (for the ZeroMQ truth publisher)."""
        b = self.ball
        return {
            "t": self.t,
            "ball": {
                "x": b.x * 1000.0,
                "y": b.y * 1000.0,
                "z": b.z * 1000.0,
                "vx": b.vx * 1000.0,
                "vy": b.vy * 1000.0,
            },
            "robots": [
                {
                    "team": r.team.label,
                    "id": r.id,
                    "x": r.x * 1000.0,
                    "y": r.y * 1000.0,
                    "orientation": r.theta,
                    "vx": r.vx * 1000.0,
                    "vy": r.vy * 1000.0,
                    "omega": r.omega,
                    "C": r.gain,
                }
                for r in self.robots.values()
            ],
        }


def _clamp(v: float, lo: float, hi: float) -> float:
    return lo if v < lo else hi if v > hi else v


__all__ = ["Ball", "Command", "Robot", "Team", "World", "formation", "wrap_angle"]
