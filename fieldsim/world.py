"""Pure physics core: robots and ball on the field, advanced by ``World.step(dt)``.

No I/O and no wall clock: ``World.t`` is simulated seconds since start. Units inside are SI
(m, m/s, rad); geometry sizes (mm) are converted once. Robots are discs driven by a commanded
LOCAL velocity (forward = along the heading towards the kicker, left, angular ccw) scaled by a
per-robot gain C, with acceleration and speed limits, like grSim they brake to a stop once no
command arrived for ``command_timeout_s``. The ball rolls with constant friction, bounces off the
outer walls and robots, and is kicked by an armed kicker that it touches.

What a match needs on top of that:

- **Goals**: behind each goal line a goal of ``goal_width`` x ``goal_depth`` (geometry) with thin
  back and side walls (``goal_wall_thickness_m``). The ball bounces off them (restitution
  ``goal_wall_restitution``, swept test so a fast ball cannot tunnel) unless it flies above
  ``goal_height``; robots cannot enter the goal box (walls included). A ball fully over the goal
  line between the posts (centre beyond the line by its radius, ``|y| < goal_width / 2``, below
  the goal height) is a goal: one ``goal`` event, ``ball_in_goal`` is set and the goal mouth
  closes behind the ball (it rolls to rest against the walls) until the ball is teleported.
- **Ball out**: a ball fully over a touch line or over a goal line outside the goal (or above
  the goal) gives one ``ball_out`` event; re-armed once the ball centre is back inside the
  field lines (or the ball is teleported). The outer walls still bounce it back.
- **Last touch**: ``last_touch`` = (team, id) of the robot that last touched (overlap), kicked
  or dribbled the ball; None after a ball teleport.
- **Dribbler**: a robot with a fresh command with ``dribbler_rpm > 0`` that has the ball in its
  kicker zone holds it: the ball sits in front at contact distance and moves with the robot
  (translation and rotation) until the dribbler stops, the robot kicks, spins faster than
  ``dribbler_max_omega`` or accelerates harder than ``dribbler_max_accel`` (e.g. a collision),
  or the ball would be pushed into a wall; then it is released with its current velocity.
- **Collisions**: two robots coming into contact (a pair not in contact on the previous step,
  with 5 mm of hysteresis) give one ``collision`` event with the closing speed along the
  contact normal before resolution.
- **Events**: ``World.events`` (at most ``events_kept``) are plain dicts with an increasing
  ``seq``, the simulated time ``t`` and ``kind`` "goal" / "ball_out" / "collision"; ``truth()``
  carries the last ``truth_events`` of them (subscribers dedupe by ``seq``).
"""

from __future__ import annotations

import enum
import math
import random
from dataclasses import dataclass
from typing import Any

from domain.angles import wrap_angle
from fieldsim.config import SimConfig
from fieldsim.geometry import FieldGeometry, division_geometry

MAX_ROBOT_ID = 15
ROBOT_HEIGHT_M = 0.15
CONTACT_HYSTERESIS_M = 0.005  # a robot pair stays "in contact" until this far apart
_EPS = 1e-9

# (x0, x1, y0, y1) of an axis-aligned rectangle, m
Rect = tuple[float, float, float, float]


class Team(enum.IntEnum):
    """Same numbers as ssl_gc_common.Team."""

    YELLOW = 1
    BLUE = 2

    @property
    def label(self) -> str:
        return "yellow" if self is Team.YELLOW else "blue"


RobotKey = tuple[Team, int]


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
    last_kick_chip: bool = False  # the last kick left the ground
    dribbling: bool = False  # holds the ball with its dribbler


@dataclass
class Ball:
    x: float = 0.0  # m
    y: float = 0.0
    z: float = 0.0
    vx: float = 0.0  # m/s
    vy: float = 0.0
    vz: float = 0.0


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
    ball_wall_bounces: int = 0  # outer walls
    goal_wall_bounces: int = 0
    goals: int = 0
    ball_out: int = 0
    collisions: int = 0
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
        g = self.geometry
        self._hl = g.half_length / 1000.0
        self._hw = g.half_width / 1000.0
        self._goal_hw = g.goal_width / 2000.0
        self._goal_height = g.goal_height / 1000.0
        depth, thick = g.goal_depth / 1000.0, self.config.goal_wall_thickness_m
        # per side (+1, -1): the solid goal box robots cannot enter, and the ball's three walls
        self._goal_boxes: list[Rect] = []
        self._goal_walls: list[Rect] = []
        for side in (1.0, -1.0):
            gy, gy_out = self._goal_hw, self._goal_hw + thick
            xs = (self._hl, self._hl + depth, self._hl + depth + thick)
            a, b, c = (side * x for x in xs)
            self._goal_boxes.append((min(a, c), max(a, c), -gy_out, gy_out))
            self._goal_walls.append((min(b, c), max(b, c), -gy_out, gy_out))  # back
            self._goal_walls.append((min(a, b), max(a, b), gy, gy_out))  # side walls
            self._goal_walls.append((min(a, b), max(a, b), -gy_out, -gy))
        # match state
        self.events: list[dict[str, Any]] = []
        self.last_touch: RobotKey | None = None
        self.ball_in_goal: str | None = None  # "positive" / "negative": the x side
        self._seq = 0
        self._t_event = 0.0  # simulated time stamped on events of the current step
        self._out_reported = False  # ball_out / goal raised, not yet back in the field
        self._crossed: tuple[str, float, float] | None = None  # line, x, y where it left
        self._holder: RobotKey | None = None
        # the robot that just kicked or lost the ball: no re-catch until it left its kicker zone
        self._no_catch: RobotKey | None = None
        self._contacts: set[tuple[RobotKey, RobotKey]] = set()
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
        if self._holder == (team, rid):
            self._release()
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

    @property
    def ball_holder(self) -> RobotKey | None:
        """(team, id) of the robot holding the ball with its dribbler, or None."""
        return self._holder

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
        # a placement: no goal pending, no holder, nobody touched it; no ball_out is raised
        # for a ball placed outside the field until it has been back inside
        self._release()
        self._no_catch = None
        self.ball_in_goal = None
        self.last_touch = None
        self._crossed = None
        self._out_reported = not self._in_field(self.ball.x, self.ball.y)

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
        self._t_event = self.t + h
        holder = self.robots.get(self._holder) if self._holder is not None else None
        holder_v = (holder.vx, holder.vy) if holder is not None else (0.0, 0.0)
        x0, y0 = self.ball.x, self.ball.y
        self._step_robots(h)
        self._collide_robots()
        self._robots_vs_goals()
        self._carry(h, holder_v)
        self._step_ball(h)
        self._check_lines(x0, y0)
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
        # contacts: pairs overlapping before resolution, and pairs that touched on the previous
        # step and are still within the hysteresis distance; a collision event for new ones
        reach = R2 + CONTACT_HYSTERESIS_M
        contacts: set[tuple[RobotKey, RobotKey]] = set()
        for key in self._contacts:
            a_, b_ = self.robots.get(key[0]), self.robots.get(key[1])
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
                            self._collision_event(a, b, velocities[i], velocities[j], nx, ny)
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
        self._contacts = contacts

    def _collision_event(
        self,
        a: Robot,
        b: Robot,
        va: tuple[float, float],
        vb: tuple[float, float],
        nx: float,
        ny: float,
    ) -> None:
        vn = (vb[0] - va[0]) * nx + (vb[1] - va[1]) * ny
        self.stats.collisions += 1
        self._emit(
            "collision",
            a={"team": a.team.label, "id": a.id, "speed_mps": math.hypot(*va)},
            b={"team": b.team.label, "id": b.id, "speed_mps": math.hypot(*vb)},
            relative_speed_mps=abs(vn),
            x=(a.x + b.x) * 500.0,
            y=(a.y + b.y) * 500.0,
        )

    def _robots_vs_goals(self) -> None:
        """Robots stay out of the goal boxes (goal interior and walls)."""
        R = self.config.robot_radius_m
        reach_x = self._hl - R
        for robot in self.robots.values():
            if abs(robot.x) <= reach_x:
                continue
            for box in self._goal_boxes:
                push = _push_out_of_rect(robot.x, robot.y, box, R)
                if push is None:
                    continue
                robot.x, robot.y, nx, ny = push
                vn = robot.vx * nx + robot.vy * ny
                if vn < 0.0:  # stop the part of the motion into the goal
                    robot.vx -= vn * nx
                    robot.vy -= vn * ny

    # -- dribbler ----------------------------------------------------------------------------

    def _dribbler_on(self, robot: Robot) -> bool:
        cmd = robot.command
        return (
            cmd is not None
            and cmd.dribbler_rpm > 0.0
            and self.t - cmd.received_at <= self.config.command_timeout_s
        )

    def _release(self, lost: bool = False) -> None:
        """End a hold; ``lost`` (not a dribbler stop): no re-catch while the ball still touches."""
        if self._holder is not None:
            robot = self.robots.get(self._holder)
            if robot is not None:
                robot.dribbling = False
            if lost:
                self._no_catch = self._holder
            self._holder = None

    def _carry(self, h: float, v_before: tuple[float, float]) -> None:
        """Keep a held ball in front of its robot, or release it."""
        if self._holder is None:
            return
        cfg = self.config
        robot = self.robots.get(self._holder)
        if robot is None:
            self._holder = None
            return
        if not self._dribbler_on(robot):
            self._release()
            return
        accel = math.hypot(robot.vx - v_before[0], robot.vy - v_before[1]) / h if h > 0 else 0.0
        if abs(robot.omega) > cfg.dribbler_max_omega or accel > cfg.dribbler_max_accel:
            self._release(lost=True)
            return
        d = cfg.robot_radius_m + cfg.ball_radius_m
        ox, oy = d * math.cos(robot.theta), d * math.sin(robot.theta)
        x, y = robot.x + ox, robot.y + oy
        if not self._ball_spot_free(x, y):
            self._release(lost=True)  # a wall is in the way: the ball stays where it is
            return
        ball = self.ball
        ball.x, ball.y, ball.z, ball.vz = x, y, 0.0, 0.0
        ball.vx = robot.vx - robot.omega * oy
        ball.vy = robot.vy + robot.omega * ox
        self.last_touch = self._holder

    def _ball_spot_free(self, x: float, y: float) -> bool:
        """A ball on the ground at (x, y) overlaps no wall (outer, goal, closed goal mouth)."""
        r = self.config.ball_radius_m
        if abs(x) > self._wall_x - r or abs(y) > self._wall_y - r:
            return False
        if self.ball_in_goal is not None:
            side = 1.0 if self.ball_in_goal == "positive" else -1.0
            if side * x < self._hl + r:
                return False
        if abs(x) < self._hl - r:
            return True
        return all(_push_out_of_rect(x, y, w, r) is None for w in self._goal_walls)

    # -- ball --------------------------------------------------------------------------------

    def _step_ball(self, h: float) -> None:
        ball = self.ball
        if self._holder is None:
            self._move_free_ball(h)
        x1, y1 = ball.x, ball.y
        self._ball_vs_robots()
        if (ball.x, ball.y) != (x1, y1):
            # a robot pushed the ball: it may squeeze it against a goal wall, not through it
            self._ball_vs_goal_walls(x1, y1)

    def _move_free_ball(self, h: float) -> None:
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
        x0, y0 = ball.x, ball.y
        ball.x += ball.vx * h
        ball.y += ball.vy * h
        self._ball_vs_goal_walls(x0, y0)
        r = cfg.ball_radius_m
        if self.ball_in_goal is not None:
            # a scored ball stays in the goal: the mouth is closed behind it
            side = 1.0 if self.ball_in_goal == "positive" else -1.0
            mouth = self._hl + r
            if side * ball.x < mouth:
                ball.x = side * (2.0 * mouth - side * ball.x)
                ball.vx = side * abs(ball.vx) * cfg.goal_wall_restitution
                self.stats.goal_wall_bounces += 1
        # outer walls
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

    def _ball_vs_goal_walls(self, x0: float, y0: float) -> None:
        """The ball moved from (x0, y0) to its position: stop it at the first goal wall hit."""
        ball = self.ball
        r = self.config.ball_radius_m
        if ball.z >= self._goal_height:
            return  # above the goal
        near = self._hl - r  # |x| is convex along the path: both ends short of it, no wall
        if abs(x0) < near and abs(ball.x) < near:
            return
        e = self.config.goal_wall_restitution
        best: tuple[float, float, float] | None = None  # t, nx, ny
        for wall in self._goal_walls:
            if _push_out_of_rect(x0, y0, wall, r, tol=1e-7) is not None:
                # started inside (teleport, landed from a chip): push out where it is now
                push = _push_out_of_rect(ball.x, ball.y, wall, r)
                if push is not None:
                    ball.x, ball.y, nx, ny = push
                    self._reflect_ball(nx, ny, e)
                continue
            hit = _sweep_circle_rect(x0, y0, ball.x, ball.y, wall, r)
            if hit is not None and (best is None or hit[0] < best[0]):
                best = hit
        if best is not None:
            t, nx, ny = best
            ball.x = x0 + t * (ball.x - x0) + nx * _EPS
            ball.y = y0 + t * (ball.y - y0) + ny * _EPS
            self._reflect_ball(nx, ny, e)

    def _reflect_ball(self, nx: float, ny: float, e: float) -> None:
        ball = self.ball
        vn = ball.vx * nx + ball.vy * ny
        if vn < 0.0:
            ball.vx -= (1.0 + e) * vn * nx
            ball.vy -= (1.0 + e) * vn * ny
            self.stats.goal_wall_bounces += 1

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
                if self._no_catch == (robot.team, robot.id):
                    self._no_catch = None
                continue
            d = math.hypot(dx, dy)
            if d < 1e-9:
                dx, dy, d = math.cos(robot.theta), math.sin(robot.theta), 1.0
            nx, ny = dx / d, dy / d
            on_ground = ball.z < ROBOT_HEIGHT_M
            if on_ground and d < contact_d:
                # push the ball out of the robot and reflect the approaching relative velocity
                self.last_touch = (robot.team, robot.id)
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
                robot.last_kick_chip = ball.vz > 0.0
                self.stats.kicks += 1
                self.last_touch = (robot.team, robot.id)
                self._release()  # a kick ends any hold
                self._no_catch = self.last_touch
            elif (
                robot.ball_contact
                and self._holder is None
                and self.ball_in_goal is None
                and self._no_catch != (robot.team, robot.id)
                and self._dribbler_on(robot)
                and abs(robot.omega) <= cfg.dribbler_max_omega
            ):
                self._holder = (robot.team, robot.id)
                robot.dribbling = True
                self.last_touch = self._holder
            if not robot.ball_contact and self._no_catch == (robot.team, robot.id):
                self._no_catch = None

    # -- lines, goals, events ----------------------------------------------------------------

    def _in_field(self, x: float, y: float) -> bool:
        """Ball centre inside the field lines (re-arms ball_out / goal)."""
        return abs(x) <= self._hl and abs(y) <= self._hw

    def _check_lines(self, x0: float, y0: float) -> None:
        """Goal / ball_out events for a ball that moved from (x0, y0) this step."""
        ball = self.ball
        x, y = ball.x, ball.y
        if self._in_field(x, y):
            self._out_reported = False
            self.ball_in_goal = None
            return
        if self._in_field(x0, y0):
            self._crossed = self._exit_point(x0, y0, x, y)
        if self._out_reported:
            return
        r = self.config.ball_radius_m
        over_goal_line = abs(x) > self._hl + r
        over_touch_line = abs(y) > self._hw + r
        if not (over_goal_line or over_touch_line):
            return
        self._out_reported = True
        if over_goal_line and abs(y) < self._goal_hw and ball.z < self._goal_height:
            side = "positive" if x > 0 else "negative"
            self.ball_in_goal = side
            self._release()
            self.stats.goals += 1
            cx, cy = self._crossing("goal", x, y)
            self._emit("goal", side=side, x=cx * 1000.0, y=cy * 1000.0,
                       last_touch=self._touch_dict())
            return
        if over_goal_line and over_touch_line:
            line = self._crossed[0] if self._crossed is not None else "goal"
        else:
            line = "goal" if over_goal_line else "touch"
        cx, cy = self._crossing(line, x, y)
        self.stats.ball_out += 1
        self._emit("ball_out", line=line, x=cx * 1000.0, y=cy * 1000.0,
                   last_touch=self._touch_dict())

    def _exit_point(self, x0: float, y0: float, x1: float, y1: float) -> tuple[str, float, float]:
        """Where the segment from inside the field lines to outside leaves them, and the line."""
        tx = ty = math.inf
        if abs(x1) > self._hl:
            tx = (math.copysign(self._hl, x1) - x0) / (x1 - x0)
        if abs(y1) > self._hw:
            ty = (math.copysign(self._hw, y1) - y0) / (y1 - y0)
        line, t = ("goal", tx) if tx <= ty else ("touch", ty)
        return line, x0 + t * (x1 - x0), y0 + t * (y1 - y0)

    def _crossing(self, line: str, x: float, y: float) -> tuple[float, float]:
        """The point on ``line`` where the ball left the field (projected if unknown)."""
        if self._crossed is not None and self._crossed[0] == line:
            return self._crossed[1], self._crossed[2]
        if line == "goal":
            return math.copysign(self._hl, x), _clamp(y, -self._hw, self._hw)
        return _clamp(x, -self._hl, self._hl), math.copysign(self._hw, y)

    def _touch_dict(self) -> dict[str, Any] | None:
        if self.last_touch is None:
            return None
        return {"team": self.last_touch[0].label, "id": self.last_touch[1]}

    def _emit(self, kind: str, **fields: Any) -> None:
        self._seq += 1
        self.events.append({"seq": self._seq, "t": self._t_event, "kind": kind, **fields})
        excess = len(self.events) - self.config.events_kept
        if excess > 0:
            del self.events[:excess]

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
                    "dribbling": r.dribbling,
                    "kicks": r.kicks,
                }
                for r in self.robots.values()
            ],
            "events": self.events[-self.config.truth_events:],
            "last_touch": self._touch_dict(),
            "ball_in_goal": self.ball_in_goal,
            "stats": {
                "kicks": self.stats.kicks,
                "goals": self.stats.goals,
                "ball_out": self.stats.ball_out,
                "collisions": self.stats.collisions,
            },
        }


def _clamp(v: float, lo: float, hi: float) -> float:
    return lo if v < lo else hi if v > hi else v


def _push_out_of_rect(
    x: float, y: float, rect: Rect, radius: float, tol: float = 0.0
) -> tuple[float, float, float, float] | None:
    """A disc at (x, y) overlapping ``rect`` by more than ``tol``: its pushed-out centre and
    the outward normal (x, y, nx, ny); None if it does not overlap."""
    x0, x1, y0, y1 = rect
    if x < x0 - radius or x > x1 + radius or y < y0 - radius or y > y1 + radius:
        return None
    cx, cy = _clamp(x, x0, x1), _clamp(y, y0, y1)
    dx, dy = x - cx, y - cy
    d = math.hypot(dx, dy)
    if d > _EPS:
        if d >= radius - tol:
            return None
        nx, ny = dx / d, dy / d
        return cx + nx * radius, cy + ny * radius, nx, ny
    # centre inside the rectangle: out through the nearest side
    exits = (
        (x - x0, x0 - radius, y, -1.0, 0.0),
        (x1 - x, x1 + radius, y, 1.0, 0.0),
        (y - y0, x, y0 - radius, 0.0, -1.0),
        (y1 - y, x, y1 + radius, 0.0, 1.0),
    )
    _, px, py, nx, ny = min(exits)
    return px, py, nx, ny


def _sweep_circle_rect(
    x0: float, y0: float, x1: float, y1: float, rect: Rect, radius: float
) -> tuple[float, float, float] | None:
    """First contact of a disc moving (x0, y0) -> (x1, y1) with ``rect`` (a rounded-rectangle
    sweep): (t in [0, 1], nx, ny) or None. The disc must start outside."""
    rx0, rx1, ry0, ry1 = rect
    dx, dy = x1 - x0, y1 - y0
    if (
        max(x0, x1) < rx0 - radius
        or min(x0, x1) > rx1 + radius
        or max(y0, y1) < ry0 - radius
        or min(y0, y1) > ry1 + radius
    ):
        return None
    best: tuple[float, float, float] | None = None
    # the rectangle grown by the radius along x, then along y (flat faces)
    for bx0, bx1, by0, by1 in (
        (rx0 - radius, rx1 + radius, ry0, ry1),
        (rx0, rx1, ry0 - radius, ry1 + radius),
    ):
        hit = _sweep_point_box(x0, y0, dx, dy, bx0, bx1, by0, by1)
        if hit is not None and (best is None or hit[0] < best[0]):
            best = hit
    # the rounded corners
    a = dx * dx + dy * dy
    if a > 0.0:
        for cx, cy in ((rx0, ry0), (rx0, ry1), (rx1, ry0), (rx1, ry1)):
            fx, fy = x0 - cx, y0 - cy
            b = fx * dx + fy * dy
            c = fx * fx + fy * fy - radius * radius
            disc = b * b - a * c
            if b >= 0.0 or disc < 0.0:
                continue  # moving away from the corner or missing it
            t = (-b - math.sqrt(disc)) / a
            if 0.0 <= t <= 1.0 and (best is None or t < best[0]):
                px, py = x0 + t * dx - cx, y0 + t * dy - cy
                best = (t, px / radius, py / radius)
    return best


def _sweep_point_box(
    x0: float, y0: float, dx: float, dy: float, bx0: float, bx1: float, by0: float, by1: float
) -> tuple[float, float, float] | None:
    """Slab test: first entry of the point x0 + t*dx into the box, t in [0, 1], and its face
    normal; None if it does not enter (or starts inside)."""
    t_enter, t_exit = -math.inf, math.inf
    normal = (0.0, 0.0)
    for p, d, lo, hi, axis in ((x0, dx, bx0, bx1, 0), (y0, dy, by0, by1, 1)):
        if abs(d) < 1e-15:
            if p < lo or p > hi:
                return None
            continue
        t_lo, t_hi = (lo - p) / d, (hi - p) / d
        n = -1.0 if d > 0 else 1.0
        if t_lo > t_hi:
            t_lo, t_hi = t_hi, t_lo
        if t_lo > t_enter:
            t_enter = t_lo
            normal = (n, 0.0) if axis == 0 else (0.0, n)
        t_exit = min(t_exit, t_hi)
    if t_enter > t_exit or t_enter < 0.0 or t_enter > 1.0:
        return None
    return t_enter, normal[0], normal[1]


__all__ = ["Ball", "Command", "Robot", "RobotKey", "Team", "World", "formation", "wrap_angle"]
