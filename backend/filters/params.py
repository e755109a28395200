"""Filter parameters as pydantic models: defaults, bounds, units, descriptions.

Every model rejects NaN/inf and unknown fields, so a settings document from the browser either
validates completely or is refused with a 422 naming the field.
"""

from __future__ import annotations

import re
from typing import Literal

from pydantic import BaseModel, ConfigDict, Field, field_validator
from pydantic.config import JsonDict

FilterKind = Literal["raw", "median", "paper", "kalman"]
FILTER_KINDS: tuple[FilterKind, ...] = ("raw", "median", "paper", "kalman")

_CFG = ConfigDict(allow_inf_nan=False, extra="forbid", frozen=True)


def _unit(unit: str, step: float) -> JsonDict:
    return {"unit": unit, "step": step}


class RawParams(BaseModel):
    """No filtering: the latest measurement. Velocity from a line fit over recent measurements."""

    model_config = _CFG
    velocity_window_s: float = Field(
        default=0.1, ge=0.02, le=1.0,
        description="time window of the line fit that gives the velocity",
        json_schema_extra=_unit("s", 0.01))


class MedianParams(BaseModel):
    """Median of the last N measurements per coordinate (removes isolated outliers)."""

    model_config = _CFG
    window: int = Field(default=5, ge=1, le=31, description="number of measurements in the median",
                        json_schema_extra=_unit("samples", 1))
    gap_s: float = Field(default=1.0, ge=0.01, le=10.0,
                         description="no measurement for longer than this: start over",
                         json_schema_extra=_unit("s", 0.05))
    velocity_window_s: float = Field(
        default=0.1, ge=0.02, le=1.0,
        description="time window of the line fit that gives the velocity",
        json_schema_extra=_unit("s", 0.01))


class PaperParams(BaseModel):
    """URoboRus 2022 (TDP section 5.1): median of the last N measurements per coordinate, then
    est = w_prev * est_prev + w_new * median with w_prev = 1 - w_new, per measurement step."""

    model_config = _CFG
    window: int = Field(default=5, ge=1, le=31, description="number of measurements in the median",
                        json_schema_extra=_unit("samples", 1))
    w_new: float = Field(default=0.05, ge=0.001, le=1.0,
                         description="weight of the new median (w_prev = 1 - w_new)",
                         json_schema_extra=_unit("", 0.01))
    gap_s: float = Field(default=1.0, ge=0.01, le=10.0,
                         description="no measurement for longer than this: re-initialise",
                         json_schema_extra=_unit("s", 0.05))
    jump_mm: float = Field(default=200.0, ge=1.0, le=10000.0,
                           description="median this far from the estimate: re-initialise to it",
                           json_schema_extra=_unit("mm", 10.0))
    jump_rad: float = Field(default=0.5, ge=0.01, le=3.1416,
                            description="orientation: median this far from the estimate: "
                                        "re-initialise to it",
                            json_schema_extra=_unit("rad", 0.05))
    velocity_window_s: float = Field(
        default=0.1, ge=0.02, le=1.0,
        description="time window of the line fit that gives the velocity",
        json_schema_extra=_unit("s", 0.01))

    @property
    def w_prev(self) -> float:
        return 1.0 - self.w_new


class KalmanParams(BaseModel):
    """Constant-velocity Kalman filter (state x, y, vx, vy; white-noise acceleration)."""

    model_config = _CFG
    accel_noise_mm_s2: float = Field(
        default=4000.0, ge=1.0, le=1e6, description="process noise: std of the white acceleration",
        json_schema_extra=_unit("mm/s^2", 100.0))
    meas_noise_mm: float = Field(default=3.0, ge=0.01, le=1000.0,
                                 description="measurement noise: std of one position",
                                 json_schema_extra=_unit("mm", 0.5))
    gate_mm: float = Field(default=0.0, ge=0.0, le=10000.0,
                           description="reject a measurement this far from the prediction "
                                       "(0 = accept all)",
                           json_schema_extra=_unit("mm", 10.0))
    gap_s: float = Field(default=1.0, ge=0.01, le=10.0,
                         description="no measurement for longer than this: re-initialise",
                         json_schema_extra=_unit("s", 0.05))
    angle_accel_noise_rad_s2: float = Field(
        default=40.0, ge=0.01, le=1e4,
        description="orientation: std of the white angular acceleration",
        json_schema_extra=_unit("rad/s^2", 1.0))
    angle_meas_noise_rad: float = Field(default=0.01, ge=1e-4, le=1.0,
                                        description="orientation: std of one measurement",
                                        json_schema_extra=_unit("rad", 0.005))


_ROBOT_KEY = re.compile(r"^(blue|yellow)/([0-9]|1[0-5])$")


class FilterSettings(BaseModel):
    """Which filter each object uses, and the parameters of every kind."""

    model_config = _CFG
    ball: FilterKind = Field(default="kalman", description="filter of the ball",
                             json_schema_extra={"unit": "", "step": None})
    robot: FilterKind = Field(default="kalman",
                              description="filter of every robot without an override",
                              json_schema_extra={"unit": "", "step": None})
    robot_overrides: dict[str, FilterKind] = Field(
        default_factory=dict, description='per-robot filter, keyed "team/id", e.g. "blue/3"',
        json_schema_extra={"unit": "", "step": None})
    raw: RawParams = Field(default=RawParams(), description="parameters of 'raw'",
                           json_schema_extra={"unit": "", "step": None})
    median: MedianParams = Field(default=MedianParams(),
                                 description="parameters of 'median'",
                                 json_schema_extra={"unit": "", "step": None})
    paper: PaperParams = Field(default=PaperParams(), description="parameters of 'paper'",
                               json_schema_extra={"unit": "", "step": None})
    kalman: KalmanParams = Field(default=KalmanParams(),
                                 description="parameters of 'kalman'",
                                 json_schema_extra={"unit": "", "step": None})

    @field_validator("robot_overrides")
    @classmethod
    def _keys(cls, v: dict[str, FilterKind]) -> dict[str, FilterKind]:
        for k in v:
            if not _ROBOT_KEY.match(k):
                raise ValueError(f"robot key {k!r} is not 'blue/<0..15>' or 'yellow/<0..15>'")
        if len(v) > 32:
            raise ValueError("at most 32 robot overrides")
        return v

    def robot_kind(self, team: str, rid: int) -> FilterKind:
        return self.robot_overrides.get(f"{team}/{rid}", self.robot)

    def params_for(self, kind: FilterKind) -> RawParams | MedianParams | PaperParams | KalmanParams:
        if kind == "raw":
            return self.raw
        if kind == "median":
            return self.median
        if kind == "paper":
            return self.paper
        return self.kalman
