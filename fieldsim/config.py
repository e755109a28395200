"""Every fieldsim setting in one typed dataclass, with defaults (see README.md for the flags)."""

from __future__ import annotations

from dataclasses import dataclass, field

from domain.rules import ROBOT_RADIUS_MM
from sslnet import defaults

#: fieldsim's camera timing (SimConfig.camera_phases)
CAMERA_PHASES = ("spread", "together")

@dataclass
class SimConfig:
    """Settings of one fieldsim process. Units: mm and rad for vision, m and s for physics."""

    # World
    seed: int = 1
    division: str = "B"  # "A" (12000x9000) or "B" (9000x6000)
    blue: int = 6  # robots per team at start, 0..11
    yellow: int = 6
    blue_on_positive_half: bool = False  # blue starts on the negative-x half by default
    generation: int = 2  # 1: unequal gains C per robot, 2: C = 1 for every robot
    gain_min: float = 0.6  # generation 1: C drawn uniformly in [gain_min, gain_max]
    gain_max: float = 1.4
    gains: list[float] | None = None  # generation 1: fixed C list (robot order: blue, yellow)

    # Physics (SI units)
    physics_hz: float = 200.0
    robot_radius_m: float = ROBOT_RADIUS_MM / 1000.0
    robot_max_speed: float = 3.5  # m/s
    robot_max_accel: float = 3.0  # m/s^2
    robot_max_angular_speed: float = 10.0  # rad/s
    robot_max_angular_accel: float = 20.0  # rad/s^2
    command_timeout_s: float = 0.2  # no command for this long: the robot brakes to a stop
    ball_radius_m: float = 0.0215
    ball_rolling_decel: float = 0.4  # m/s^2
    ball_wall_restitution: float = 0.6
    ball_robot_restitution: float = 0.3
    ball_max_speed: float = 10.0  # m/s, kicks are clamped to this
    kicker_half_angle_rad: float = 0.6981  # 40 degrees either side of the heading
    kicker_reach_m: float = 0.010  # extra reach beyond robot radius + ball radius
    gravity: float = 9.81
    chip_bounce_restitution: float = 0.5
    goal_wall_thickness_m: float = 0.02  # back and side walls of the goals (depth: geometry)
    goal_wall_restitution: float = 0.2  # the ball on the goal walls (and a scored ball's mouth)
    dribbler_max_omega: float = 8.0  # rad/s: a robot spinning faster drops a held ball
    dribbler_max_accel: float = 6.0  # m/s^2: a robot accelerating harder drops a held ball
    # balls left on the field besides the ball (x, y in m): seen by the cameras, not played
    other_balls: list[tuple[float, float]] = field(default_factory=list)

    # Events (goal, ball_out, collision) kept by the World and carried in the truth
    events_kept: int = 256  # World.events holds at most this many (oldest dropped)
    truth_events: int = 50  # the last this many go into every truth message

    # Vision
    cameras: int = 4  # 1, 2, 4 or 8 (division A: two rows of four)
    camera_hz: float = 60.0
    #: "spread": every camera its own random phase (unsynchronised cameras, frames spread
    #: over the period); "together": every camera captures at the same instant and the
    #: frames go out back to back (cameras triggered together: grSim sends its four in one
    #: burst per step)
    camera_phases: str = "spread"
    camera_overlap_mm: float = 400.0  # each camera sees this far past the centre lines
    camera_height_mm: float = 4000.0
    geometry_hz: float = 3.0
    noise_mm: float = 2.0
    noise_rad: float = 0.01
    miss_prob: float = 0.01
    false_prob: float = 0.0
    confidence: float = 0.9

    # Network
    interface: str = "127.0.0.1"
    vision_group: str = defaults.VISION_GROUP
    vision_port: int = defaults.VISION_PORT_SIM
    vision_ttl: int = 1
    sim_host: str = "127.0.0.1"
    control_port: int = defaults.SIM_CONTROL_PORT  # 0 picks a free port
    blue_port: int = defaults.SIM_BLUE_PORT
    yellow_port: int = defaults.SIM_YELLOW_PORT
    grsim_port: int = defaults.GRSIM_COMMAND_PORT
    # like grSim: Robots_Status to the IP of the last grSim command's sender, on these ports
    grsim_status_blue_port: int = defaults.GRSIM_STATUS_BLUE_PORT
    grsim_status_yellow_port: int = defaults.GRSIM_STATUS_YELLOW_PORT
    truth_pub: str | None = None  # e.g. "tcp://127.0.0.1:5580"
    max_catch_up_steps: int = 50  # physics steps per wake-up before the sim gives up real time

    def validate(self) -> None:
        """Raise ValueError for settings that cannot work."""
        if self.division not in ("A", "B"):
            raise ValueError("division must be 'A' or 'B'")
        for name in ("blue", "yellow"):
            n = getattr(self, name)
            if not 0 <= n <= 11:
                raise ValueError(f"{name} must be in 0..11")
        if self.generation not in (1, 2):
            raise ValueError("generation must be 1 or 2")
        if self.cameras not in (1, 2, 4, 8):
            raise ValueError("cameras must be 1, 2, 4 or 8")
        if self.camera_phases not in CAMERA_PHASES:
            raise ValueError(f"camera_phases must be one of {', '.join(CAMERA_PHASES)}")
        for name in ("physics_hz", "camera_hz", "geometry_hz"):
            if not getattr(self, name) > 0:
                raise ValueError(f"{name} must be > 0")
        for name in ("miss_prob", "false_prob"):
            p = getattr(self, name)
            if not 0.0 <= p <= 1.0:
                raise ValueError(f"{name} must be in [0, 1]")
        if self.noise_mm < 0 or self.noise_rad < 0:
            raise ValueError("noise must be >= 0")
        if self.gain_min <= 0 or self.gain_max < self.gain_min:
            raise ValueError("need 0 < gain_min <= gain_max")
        if self.gains is not None and any(not g > 0 for g in self.gains):
            raise ValueError("gains must be > 0")
        if not 0.0 <= self.chip_bounce_restitution < 1.0:
            raise ValueError("chip_bounce_restitution must be in [0, 1)")
        if not self.gravity > 0:
            raise ValueError("gravity must be > 0")
        if len(self.other_balls) > 8:
            raise ValueError("at most 8 other balls")
        if not 0.0 <= self.goal_wall_restitution <= 1.0:
            raise ValueError("goal_wall_restitution must be in [0, 1]")
        if not self.goal_wall_thickness_m > 0:
            raise ValueError("goal_wall_thickness_m must be > 0")
        if not 1 <= self.truth_events <= self.events_kept:
            raise ValueError("need 1 <= truth_events <= events_kept")
