"""The true state of the field, advanced by ``World.step(dt)``: a composition of the parts.

No I/O and no wall clock: ``World.t`` is simulated seconds since start. Units inside are SI
(m, m/s, rad); geometry sizes (mm) are converted once. The parts have their own modules: the
bodies (``bodies``), robot motion and contacts (``robot_physics``), ball flight, rolling and
walls (``ball_physics``), plane geometry (``shapes``); the cameras are ``cameras`` and
``vision``, the protocols ``protocol``. The World keeps what ties them together: the ball
against the robots (touches, kicks, the dribbler), the lines, goals and events.

A kick with ``kick_angle > 0`` is a chip: the ball leaves the ground on a ballistic arc and
bounces (``ball_physics``). Other balls (``World.other_balls``, a second ball left on the field:
``SimConfig.other_balls`` or ``add_ball``) roll, fly and bounce off the walls like the ball, are
seen by the cameras, and are not touched by the robots (they stay where they were left).

What a match needs on top of that:

- **Goals**: behind each goal line a goal of ``goal_width`` x ``goal_depth`` (geometry) with thin
  back and side walls (``goal_wall_thickness_m``). The ball bounces off them (restitution
  ``goal_wall_restitution``, swept test so a fast ball cannot tunnel) unless it flies above
  ``goal_height``; robots stop at the walls and may drive into the goal, as real ones can (a
  keeper touching its goal line stands partly in it: the game controller's penalty check). A
  ball fully over the goal line between the posts (centre beyond the line by its radius,
  ``|y| < goal_width / 2``, below the goal height) is a goal: one ``goal`` event,
  ``ball_in_goal`` is set and the goal mouth closes behind the ball (it rolls to rest against
  the walls) until the ball is teleported.
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

import math
import random
from typing import Any

from domain.angles import wrap_angle
from fieldsim.ball_physics import BallPhysics
from fieldsim.bodies import (
    MAX_ROBOT_ID,
    ROBOT_HEIGHT_M,
    Ball,
    Command,
    Robot,
    RobotKey,
    Team,
    WorldStats,
    formation,
)
from fieldsim.config import SimConfig
from fieldsim.geometry import FieldGeometry, division_geometry
from fieldsim.lines import LineJudge
from fieldsim.robot_physics import CONTACT_HYSTERESIS_M, Contact, RobotPhysics
from fieldsim.shapes import Rect, clamp, push_out_of_rect


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
        # per side (+1, -1): the three walls of the goal, for the ball and the robots
        self._goal_walls: list[Rect] = []
        for side in (1.0, -1.0):
            gy, gy_out = self._goal_hw, self._goal_hw + thick
            xs = (self._hl, self._hl + depth, self._hl + depth + thick)
            a, b, c = (side * x for x in xs)
            self._goal_walls.append((min(b, c), max(b, c), -gy_out, gy_out))  # back
            self._goal_walls.append((min(a, b), max(a, b), gy, gy_out))  # side walls
            self._goal_walls.append((min(a, b), max(a, b), -gy_out, -gy))
        # match state
        self.events: list[dict[str, Any]] = []
        self.last_touch: RobotKey | None = None
        self.lines = LineJudge(self._hl, self._hw, self._goal_hw, self._goal_height,
                               self.config.ball_radius_m)
        self._seq = 0
        self._t_event = 0.0  # simulated time stamped on events of the current step
        self._holder: RobotKey | None = None
        # the robot that just kicked or lost the ball: no re-catch until it left its kicker zone
        self._no_catch: RobotKey | None = None
        self.robot_physics = RobotPhysics(self.config, self._wall_x, self._wall_y,
                                          self._goal_walls, self._hl)
        self.ball_physics = BallPhysics(self.config, self._wall_x, self._wall_y,
                                        self._goal_walls, self._hl, self._goal_height)
        #: balls other than the ball (left on the field): seen by the cameras, not played
        self.other_balls: list[Ball] = []
        for x, y in self.config.other_balls:
            self.add_ball(x, y)
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
            clamp(x, -self._wall_x + r, self._wall_x - r),
            clamp(y, -self._wall_y + r, self._wall_y - r),
            max(0.0, z),
            vx,
            vy,
            vz,
        )
        # a placement: no goal pending, no holder, nobody touched it; no ball_out is raised
        # for a ball placed outside the field until it has been back inside
        self._release()
        self._no_catch = None
        self.last_touch = None
        self.lines.placed(self.ball.x, self.ball.y)

    def add_ball(self, x: float, y: float, vx: float = 0.0, vy: float = 0.0) -> Ball:
        """Leave another ball on the field (m, m/s): cameras see it, robots do not play it."""
        if not all(math.isfinite(v) for v in (x, y, vx, vy)):
            raise ValueError("non-finite ball")
        r = self.config.ball_radius_m
        ball = Ball(clamp(x, -self._wall_x + r, self._wall_x - r),
                    clamp(y, -self._wall_y + r, self._wall_y - r), 0.0, vx, vy, 0.0)
        self.other_balls.append(ball)
        return ball

    def clear_other_balls(self) -> int:
        """Take the other balls off the field; how many there were."""
        n = len(self.other_balls)
        self.other_balls.clear()
        return n

    @property
    def ball_in_goal(self) -> str | None:
        """"positive" / "negative" (the x side) while a scored ball is in the goal, else None."""
        return self.lines.ball_in_goal

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
            robot.x = clamp(x, -self._wall_x + R, self._wall_x - R)
        if y is not None:
            robot.y = clamp(y, -self._wall_y + R, self._wall_y - R)
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
        for contact in self.robot_physics.step(self.robots, self.t, h):
            self._collision_event(contact)
        self._carry(h, holder_v)
        self._step_ball(h)
        for other in self.other_balls:
            self._move_other_ball(other, h)
        self._check_lines(x0, y0)
        self.t += h
        self.stats.steps += 1

    def _collision_event(self, c: Contact) -> None:
        vn = (c.vb[0] - c.va[0]) * c.nx + (c.vb[1] - c.va[1]) * c.ny
        self.stats.collisions += 1
        self._emit(
            "collision",
            a={"team": c.a.team.label, "id": c.a.id, "speed_mps": math.hypot(*c.va)},
            b={"team": c.b.team.label, "id": c.b.id, "speed_mps": math.hypot(*c.vb)},
            relative_speed_mps=abs(vn),
            x=(c.a.x + c.b.x) * 500.0,
            y=(c.a.y + c.b.y) * 500.0,
        )

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
        return all(push_out_of_rect(x, y, w, r) is None for w in self._goal_walls)

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
        ball, phys = self.ball, self.ball_physics
        phys.fly(ball, h)  # vertical (chip): gravity and damped bounces
        phys.roll(ball, h)  # rolling friction on the ground
        x0, y0 = ball.x, ball.y
        ball.x += ball.vx * h
        ball.y += ball.vy * h
        self._ball_vs_goal_walls(x0, y0)
        r = self.config.ball_radius_m
        if self.ball_in_goal is not None:
            # a scored ball stays in the goal: the mouth is closed behind it
            side = 1.0 if self.ball_in_goal == "positive" else -1.0
            mouth = self._hl + r
            if side * ball.x < mouth:
                ball.x = side * (2.0 * mouth - side * ball.x)
                ball.vx = side * abs(ball.vx) * self.config.goal_wall_restitution
                self.stats.goal_wall_bounces += 1
        self.stats.ball_wall_bounces += phys.outer_walls(ball)

    def _move_other_ball(self, ball: Ball, h: float) -> None:
        """Another ball: flies, rolls and bounces off the walls; no robot touches it."""
        phys = self.ball_physics
        phys.fly(ball, h)
        phys.roll(ball, h)
        x0, y0 = ball.x, ball.y
        ball.x += ball.vx * h
        ball.y += ball.vy * h
        phys.goal_walls(ball, x0, y0)
        phys.outer_walls(ball)

    def _ball_vs_goal_walls(self, x0: float, y0: float) -> None:
        """The ball moved from (x0, y0) to its position: stop it at the first goal wall hit."""
        self.stats.goal_wall_bounces += self.ball_physics.goal_walls(self.ball, x0, y0)

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
    # -- lines, goals, events ----------------------------------------------------------------

    def _check_lines(self, x0: float, y0: float) -> None:
        """Goal / ball_out events for a ball that moved from (x0, y0) this step."""
        call = self.lines.check(x0, y0, self.ball)
        if call is None:
            return
        if call.kind == "goal":
            self._release()
            self.stats.goals += 1
        else:
            self.stats.ball_out += 1
        self._emit(call.kind, **call.fields, last_touch=self._touch_dict())

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
            "other_balls": [
                {"x": o.x * 1000.0, "y": o.y * 1000.0, "z": o.z * 1000.0} for o in self.other_balls
            ],
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


__all__ = [
    "CONTACT_HYSTERESIS_M",
    "MAX_ROBOT_ID",
    "ROBOT_HEIGHT_M",
    "Ball",
    "Command",
    "Rect",
    "Robot",
    "RobotKey",
    "Team",
    "World",
    "WorldStats",
    "formation",
    "wrap_angle",
]
