"""Parameters of the motion controllers as pydantic v2 models (for the API and the UI).

Every field has a default, bounds, a description and ``json_schema_extra`` with its unit and a
UI step. Defaults are the public ones of the URoboRus 2022 scripts where those exist (v = 1 m/s,
w = 3 m/s^2, K = 3, a = 1.5 m/s^2, C smoothing 0.997 / 0.003); see DESIGN.md section 4.
"""

from __future__ import annotations

from typing import Literal

from pydantic import BaseModel, ConfigDict, Field, field_validator

from ..params.fields import check_robot_keys, num

AlgorithmName = Literal["algorithm1", "algorithm2", "proportional"]
ALGORITHMS: tuple[AlgorithmName, ...] = ("algorithm1", "algorithm2", "proportional")


class _Model(BaseModel):
    model_config = ConfigDict(allow_inf_nan=False, extra="forbid")


class LimitsParams(_Model):
    """What the robot can be commanded (in command units, i.e. before the robot's gain C)."""

    max_speed_mps: float = num(3.0, 0.1, 6.0, "m/s", 0.1, "Maximum commanded speed")
    max_accel_mps2: float = num(5.0, 0.1, 20.0, "m/s^2", 0.1,
        "Maximum change of the commanded velocity vector per second (outer safety limit, shared "
        "by all algorithms)")
    max_angular_radps: float = num(6.0, 0.1, 20.0, "rad/s", 0.1, "Maximum commanded angular speed")
    position_tolerance_mm: float = num(10.0, 0.0, 200.0, "mm", 1.0,
        "Within this distance of the target the robot holds still (noise deadband)")


class HeadingParams(_Model):
    """Heading control: a separate proportional controller, limited by max_angular_radps."""

    kp_per_s: float = num(4.0, 0.0, 30.0, "1/s", 0.1, "Angular speed per radian of heading error")
    tolerance_rad: float = num(0.02, 0.0, 0.5, "rad", 0.005, "Heading error treated as zero")


class LateralParams(_Model):
    """Correction towards the straight line A-B (perpendicular offset)."""

    kp_per_s: float = num(3.0, 0.0, 20.0, "1/s", 0.1,
        "Sideways speed per metre of offset from the line")
    max_mps: float = num(0.5, 0.0, 3.0, "m/s", 0.05, "Maximum sideways correction speed")


class Algorithm1Params(_Model):
    """Trapezoid reference x*(t) + online estimate of the gain C + feedback K (paper eq. 3)."""

    v_mps: float = num(1.0, 0.05, 5.0, "m/s", 0.05, "Speed limit v of the reference")
    w_mps2: float = num(3.0, 0.1, 10.0, "m/s^2", 0.1, "Acceleration limit w of the reference")
    k_per_s: float = num(3.0, 0.0, 20.0, "1/s", 0.1, "Feedback gain K on the lag x*(t) - x(t)")
    c_smoothing: float = num(0.997, 0.0, 0.99999, "", 0.001,
        "C <- s*C + (1-s)*distance/integral(u) each tick (public scripts: 0.997 / 0.003)")
    c_initial: float = num(1.0, 0.05, 5.0, "", 0.01,
        "Estimate of C before any motion (the public scripts start at 0.01, which is outside "
        "the clamp range and would command 100x the reference speed)")
    c_min: float = num(0.05, 0.01, 1.0, "", 0.01, "Lower clamp of the C estimate")
    c_max: float = num(5.0, 1.0, 20.0, "", 0.1, "Upper clamp of the C estimate")
    c_min_integral_m: float = num(0.2, 0.0, 5.0, "m", 0.05,
        "Update C only once integral(u) dt of this move exceeds this (command-metres)")
    blocked_time_s: float = num(0.5, 0.05, 5.0, "s", 0.05,
        "Commanded but not moving for this long: blocked, restart the profile from where the "
        "robot is")
    blocked_move_mm: float = num(30.0, 1.0, 500.0, "mm", 1.0,
        "Moving less than this counts as not moving")
    blocked_speed_mps: float = num(0.2, 0.0, 3.0, "m/s", 0.05,
        "Commanded speed above which the robot should be moving")
    retarget_mm: float = num(50.0, 0.0, 1000.0, "mm", 5.0,
        "A target moved less than this keeps A and the profile time (only B moves); more "
        "restarts from the current position")


class Algorithm2Params(_Model):
    """V = sqrt(2 a S) towards the goal, limited by v and w from the last step's speed only."""

    v_mps: float = num(1.0, 0.05, 5.0, "m/s", 0.05, "Speed limit v")
    w_mps2: float = num(3.0, 0.1, 10.0, "m/s^2", 0.1, "Acceleration limit w")
    a_mps2: float = num(1.5, 0.05, 10.0, "m/s^2", 0.05,
        "Braking acceleration a in V = sqrt(2 a S), set by hand")


class ProportionalParams(_Model):
    """Baseline: the proportional go-to controller (backend/control/goto.py)."""

    kp_per_s: float = num(2.5, 0.0, 20.0, "1/s", 0.1, "Speed per metre of error")
    v_mps: float = num(1.0, 0.05, 5.0, "m/s", 0.05, "Speed limit")
    w_mps2: float = num(3.0, 0.1, 10.0, "m/s^2", 0.1, "Acceleration limit")


class ControllerParams(_Model):
    """Everything one robot's controller needs."""

    algorithm1: Algorithm1Params = Field(default_factory=Algorithm1Params)
    algorithm2: Algorithm2Params = Field(default_factory=Algorithm2Params)
    proportional: ProportionalParams = Field(default_factory=ProportionalParams)
    heading: HeadingParams = Field(default_factory=HeadingParams)
    lateral: LateralParams = Field(default_factory=LateralParams)
    limits: LimitsParams = Field(default_factory=LimitsParams)


class RobotOverride(_Model):
    """Per-robot choice of algorithm and overrides of v / w / K / a (None: the global value)."""

    algorithm: AlgorithmName | None = Field(default=None, description="Algorithm of this robot")
    v_mps: float | None = num(None, 0.05, 5.0, "m/s", 0.05, "Speed limit v (all algorithms)")
    w_mps2: float | None = num(None, 0.1, 10.0, "m/s^2", 0.1,
        "Acceleration limit w (all algorithms)")
    k_per_s: float | None = num(None, 0.0, 20.0, "1/s", 0.1, "Algorithm 1 feedback K")
    a_mps2: float | None = num(None, 0.05, 10.0, "m/s^2", 0.05, "Algorithm 2 braking a")


class ControlSettings(_Model):
    """Station-wide control settings: the default algorithm, global parameters and per-robot
    overrides keyed "blue/3"."""

    default_algorithm: AlgorithmName = Field(
        default="algorithm2", description="Algorithm of robots without override"
    )
    params: ControllerParams = Field(default_factory=ControllerParams)
    robots: dict[str, RobotOverride] = Field(
        default_factory=dict, description='Overrides keyed "blue/3"'
    )

    @field_validator("robots")
    @classmethod
    def _keys(cls, v: dict[str, RobotOverride]) -> dict[str, RobotOverride]:
        check_robot_keys(v)
        return v

    def algorithm_for(self, team: str, rid: int) -> AlgorithmName:
        o = self.robots.get(f"{team}/{rid}")
        return o.algorithm if o is not None and o.algorithm is not None else self.default_algorithm

    def params_for(self, team: str, rid: int) -> ControllerParams:
        """The global parameters with this robot's overrides applied."""
        o = self.robots.get(f"{team}/{rid}")
        p = self.params
        if o is None:
            return p
        a1: dict[str, float] = {}
        a2: dict[str, float] = {}
        pr: dict[str, float] = {}
        for d in (a1, a2, pr):
            if o.v_mps is not None:
                d["v_mps"] = o.v_mps
            if o.w_mps2 is not None:
                d["w_mps2"] = o.w_mps2
        if o.k_per_s is not None:
            a1["k_per_s"] = o.k_per_s
        if o.a_mps2 is not None:
            a2["a_mps2"] = o.a_mps2
        return p.model_copy(
            update={
                "algorithm1": p.algorithm1.model_copy(update=a1),
                "algorithm2": p.algorithm2.model_copy(update=a2),
                "proportional": p.proportional.model_copy(update=pr),
            }
        )
