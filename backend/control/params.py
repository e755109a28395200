"""Parameters of the motion controllers as pydantic v2 models (for the API and the UI).

Every field has a default, bounds, a description and ``json_schema_extra`` with its unit and a
UI step. Defaults are the public ones of the URoboRus 2022 scripts where those exist (v = 1 m/s,
w = 3 m/s^2, K = 3, a = 1.5 m/s^2, C smoothing 0.997 / 0.003); see DESIGN.md section 4.
"""

from __future__ import annotations

import re
from typing import Literal

from pydantic import BaseModel, ConfigDict, Field, field_validator
from pydantic.config import JsonDict

AlgorithmName = Literal["algorithm1", "algorithm2", "proportional"]
ALGORITHMS: tuple[AlgorithmName, ...] = ("algorithm1", "algorithm2", "proportional")

_ROBOT_KEY = re.compile(r"^(blue|yellow)/(1[0-5]|[0-9])$")


def _u(unit: str, step: float) -> JsonDict:
    return {"unit": unit, "step": step}


class _Model(BaseModel):
    model_config = ConfigDict(allow_inf_nan=False, extra="forbid")


class LimitsParams(_Model):
    """What the robot can be commanded (in command units, i.e. before the robot's gain C)."""

    max_speed_mps: float = Field(
        default=3.0,
        ge=0.1,
        le=6.0,
        description="Maximum commanded speed",
        json_schema_extra=_u("m/s", 0.1),
    )
    max_accel_mps2: float = Field(
        default=5.0,
        ge=0.1,
        le=20.0,
        description="Maximum change of the commanded velocity vector "
        "per second (outer safety limit, shared by all algorithms)",
        json_schema_extra=_u("m/s^2", 0.1),
    )
    max_angular_radps: float = Field(
        default=6.0,
        ge=0.1,
        le=20.0,
        description="Maximum commanded angular speed",
        json_schema_extra=_u("rad/s", 0.1),
    )
    position_tolerance_mm: float = Field(
        default=10.0,
        ge=0.0,
        le=200.0,
        description="Within this distance of the target the robot holds still (noise deadband)",
        json_schema_extra=_u("mm", 1.0),
    )


class HeadingParams(_Model):
    """Heading control: a separate proportional controller, limited by max_angular_radps."""

    kp_per_s: float = Field(
        default=4.0,
        ge=0.0,
        le=30.0,
        description="Angular speed per radian of heading error",
        json_schema_extra=_u("1/s", 0.1),
    )
    tolerance_rad: float = Field(
        default=0.02,
        ge=0.0,
        le=0.5,
        description="Heading error treated as zero",
        json_schema_extra=_u("rad", 0.005),
    )


class LateralParams(_Model):
    """Correction towards the straight line A-B (perpendicular offset)."""

    kp_per_s: float = Field(
        default=3.0,
        ge=0.0,
        le=20.0,
        description="Sideways speed per metre of offset from the line",
        json_schema_extra=_u("1/s", 0.1),
    )
    max_mps: float = Field(
        default=0.5,
        ge=0.0,
        le=3.0,
        description="Maximum sideways correction speed",
        json_schema_extra=_u("m/s", 0.05),
    )


class Algorithm1Params(_Model):
    """Trapezoid reference x*(t) + online estimate of the gain C + feedback K (paper eq. 3)."""

    v_mps: float = Field(
        default=1.0,
        ge=0.05,
        le=5.0,
        description="Speed limit v of the reference",
        json_schema_extra=_u("m/s", 0.05),
    )
    w_mps2: float = Field(
        default=3.0,
        ge=0.1,
        le=10.0,
        description="Acceleration limit w of the reference",
        json_schema_extra=_u("m/s^2", 0.1),
    )
    k_per_s: float = Field(
        default=3.0,
        ge=0.0,
        le=20.0,
        description="Feedback gain K on the lag x*(t) - x(t)",
        json_schema_extra=_u("1/s", 0.1),
    )
    c_smoothing: float = Field(
        default=0.997,
        ge=0.0,
        le=0.99999,
        description="C <- s*C + (1-s)*distance/integral(u) each tick "
        "(public scripts: 0.997 / 0.003)",
        json_schema_extra=_u("", 0.001),
    )
    c_initial: float = Field(
        default=1.0,
        ge=0.05,
        le=5.0,
        description="Estimate of C before any motion (the public scripts "
        "start at 0.01, which is outside the clamp range and would command "
        "100x the reference speed)",
        json_schema_extra=_u("", 0.01),
    )
    c_min: float = Field(
        default=0.05,
        ge=0.01,
        le=1.0,
        description="Lower clamp of the C estimate",
        json_schema_extra=_u("", 0.01),
    )
    c_max: float = Field(
        default=5.0,
        ge=1.0,
        le=20.0,
        description="Upper clamp of the C estimate",
        json_schema_extra=_u("", 0.1),
    )
    c_min_integral_m: float = Field(
        default=0.2,
        ge=0.0,
        le=5.0,
        description="Update C only once integral(u) dt of this move exceeds this (command-metres)",
        json_schema_extra=_u("m", 0.05),
    )
    blocked_time_s: float = Field(
        default=0.5,
        ge=0.05,
        le=5.0,
        description="Commanded but not moving for this long: blocked, "
        "restart the profile from where the robot is",
        json_schema_extra=_u("s", 0.05),
    )
    blocked_move_mm: float = Field(
        default=30.0,
        ge=1.0,
        le=500.0,
        description="Moving less than this counts as not moving",
        json_schema_extra=_u("mm", 1.0),
    )
    blocked_speed_mps: float = Field(
        default=0.2,
        ge=0.0,
        le=3.0,
        description="Commanded speed above which the robot should be moving",
        json_schema_extra=_u("m/s", 0.05),
    )
    retarget_mm: float = Field(
        default=50.0,
        ge=0.0,
        le=1000.0,
        description="A target moved less than this keeps A and the "
        "profile time (only B moves); more restarts from the current "
        "position",
        json_schema_extra=_u("mm", 5.0),
    )


class Algorithm2Params(_Model):
    """V = sqrt(2 a S) towards the goal, limited by v and w from the last step's speed only."""

    v_mps: float = Field(
        default=1.0, ge=0.05, le=5.0, description="Speed limit v", json_schema_extra=_u("m/s", 0.05)
    )
    w_mps2: float = Field(
        default=3.0,
        ge=0.1,
        le=10.0,
        description="Acceleration limit w",
        json_schema_extra=_u("m/s^2", 0.1),
    )
    a_mps2: float = Field(
        default=1.5,
        ge=0.05,
        le=10.0,
        description="Braking acceleration a in V = sqrt(2 a S), set by hand",
        json_schema_extra=_u("m/s^2", 0.05),
    )


class ProportionalParams(_Model):
    """Baseline: the placeholder proportional go-to controller (backend/control/goto.py)."""

    kp_per_s: float = Field(
        default=2.5,
        ge=0.0,
        le=20.0,
        description="Speed per metre of error",
        json_schema_extra=_u("1/s", 0.1),
    )
    v_mps: float = Field(
        default=1.0, ge=0.05, le=5.0, description="Speed limit", json_schema_extra=_u("m/s", 0.05)
    )
    w_mps2: float = Field(
        default=3.0,
        ge=0.1,
        le=10.0,
        description="Acceleration limit",
        json_schema_extra=_u("m/s^2", 0.1),
    )


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
    v_mps: float | None = Field(
        default=None,
        ge=0.05,
        le=5.0,
        description="Speed limit v (all algorithms)",
        json_schema_extra=_u("m/s", 0.05),
    )
    w_mps2: float | None = Field(
        default=None,
        ge=0.1,
        le=10.0,
        description="Acceleration limit w (all algorithms)",
        json_schema_extra=_u("m/s^2", 0.1),
    )
    k_per_s: float | None = Field(
        default=None,
        ge=0.0,
        le=20.0,
        description="Algorithm 1 feedback K",
        json_schema_extra=_u("1/s", 0.1),
    )
    a_mps2: float | None = Field(
        default=None,
        ge=0.05,
        le=10.0,
        description="Algorithm 2 braking a",
        json_schema_extra=_u("m/s^2", 0.05),
    )


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
        for key in v:
            if not _ROBOT_KEY.match(key):
                raise ValueError(f'robot key {key!r} is not "blue/<0..15>" or "yellow/<0..15>"')
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
