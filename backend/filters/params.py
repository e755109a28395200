"""Filter parameters as pydantic models: defaults, bounds, units, descriptions.

Every model rejects NaN/inf and unknown fields, so a settings document from the browser either
validates completely or is refused with a 422 naming the field.
"""

from __future__ import annotations

from typing import Literal

from pydantic import BaseModel, ConfigDict, field_validator

from ..params.fields import check_robot_keys, group, num, plain

FilterKind = Literal["raw", "median", "paper", "kalman", "adaptive"]
FILTER_KINDS: tuple[FilterKind, ...] = ("raw", "median", "paper", "kalman", "adaptive")

_CFG = ConfigDict(allow_inf_nan=False, extra="forbid", frozen=True)


class RawParams(BaseModel):
    """No filtering: the latest measurement. Velocity from a line fit over recent measurements."""

    model_config = _CFG
    velocity_window_s: float = num(0.1, 0.02, 1.0, "s", 0.01,
        "time window of the line fit that gives the velocity")


class MedianParams(BaseModel):
    """Median of the last N measurements per coordinate (removes isolated outliers)."""

    model_config = _CFG
    window: int = num(5, 1, 31, "samples", 1, "number of measurements in the median")
    gap_s: float = num(1.0, 0.01, 10.0, "s", 0.05,
        "no measurement for longer than this: start over")
    velocity_window_s: float = num(0.1, 0.02, 1.0, "s", 0.01,
        "time window of the line fit that gives the velocity")


class PaperParams(BaseModel):
    """URoboRus 2022 (TDP section 5.1): median of the last N measurements per coordinate, then
    est = w_prev * est_prev + w_new * median with w_prev = 1 - w_new, per measurement step."""

    model_config = _CFG
    window: int = num(5, 1, 31, "samples", 1, "number of measurements in the median")
    w_new: float = num(0.05, 0.001, 1.0, "", 0.01, "weight of the new median (w_prev = 1 - w_new)")
    gap_s: float = num(1.0, 0.01, 10.0, "s", 0.05,
        "no measurement for longer than this: re-initialise")
    jump_mm: float = num(200.0, 1.0, 10000.0, "mm", 10.0,
        "median this far from the estimate: re-initialise to it")
    jump_rad: float = num(0.5, 0.01, 3.1416, "rad", 0.05,
        "orientation: median this far from the estimate: re-initialise to it")
    velocity_window_s: float = num(0.1, 0.02, 1.0, "s", 0.01,
        "time window of the line fit that gives the velocity")

    @property
    def w_prev(self) -> float:
        return 1.0 - self.w_new


class KalmanParams(BaseModel):
    """Constant-velocity Kalman filter (state x, y, vx, vy; white-noise acceleration)."""

    model_config = _CFG
    accel_noise_mm_s2: float = num(4000.0, 1.0, 1e6, "mm/s^2", 100.0,
        "process noise: std of the white acceleration")
    meas_noise_mm: float = num(3.0, 0.01, 1000.0, "mm", 0.5,
        "measurement noise: std of one position")
    gate_mm: float = num(0.0, 0.0, 10000.0, "mm", 10.0,
        "reject a measurement this far from the prediction (0 = accept all)")
    gap_s: float = num(1.0, 0.01, 10.0, "s", 0.05,
        "no measurement for longer than this: re-initialise")
    angle_accel_noise_rad_s2: float = num(40.0, 0.01, 1e4, "rad/s^2", 1.0,
        "orientation: std of the white angular acceleration")
    angle_meas_noise_rad: float = num(0.01, 1e-4, 1.0, "rad", 0.005,
        "orientation: std of one measurement")


class AdaptiveParams(BaseModel):
    """The default: a still/moving IMM that estimates the measurement noise and the outlier rate
    from the data (no tuning needed). The bounds below only limit what it may learn."""

    model_config = _CFG
    init_noise_mm: float = num(10.0, 0.1, 500.0, "mm", 1.0,
        "measurement noise assumed before any data (then estimated)")
    min_noise_mm: float = num(0.3, 0.01, 100.0, "mm", 0.1,
        "lower bound of the estimated measurement noise")
    max_noise_mm: float = num(100.0, 1.0, 1000.0, "mm", 5.0,
        "upper bound of the estimated measurement noise")
    noise_horizon: int = num(100, 5, 10000, "samples", 10,
        "measurements the noise and outlier-rate estimates average over")
    accel_init_mm_s2: float = num(30.0, 0.1, 1e6, "mm/s^2", 10.0,
        "moving model: std of the white acceleration before any data (then estimated)")
    accel_min_mm_s2: float = num(1.0, 0.01, 1e6, "mm/s^2", 1.0,
        "moving model: lower bound of the estimated acceleration noise")
    accel_max_mm_s2: float = num(2e4, 1.0, 1e7, "mm/s^2", 1000.0,
        "moving model: upper bound of the estimated acceleration noise")
    accel_adapt_rate: float = num(0.3, 0.0, 2.0, "", 0.05,
        "how fast the acceleration noise follows the innovations (log step per unit of "
        "normalised innovation squared)")
    accel_shrink_bias: float = num(0.5, 0.0, 5.0, "", 0.1,
        "normalised innovation squared below 1 + this shrinks the acceleration noise")
    cruise_accel_mm_s2: float = num(10.0, 0.01, 1e5, "mm/s^2", 1.0,
        "cruise model (beside the moving one): std of its fixed white acceleration, the "
        "straight run's; the data weigh it against the moving model's estimated one")
    cruise_switch_per_s: float = num(5.0, 0.001, 30.0, "1/s", 0.1,
        "switching rate between the cruise and the moving model")
    cruise_rest_s: float = num(0.1, 0.0, 5.0, "s", 0.05,
        "the cruise model, ruled out by a maneuver, rests this long (the moving model alone)")
    still_drift_mm_s: float = num(0.1, 0.0, 1000.0, "mm/s^0.5", 0.5,
        "still model: random-walk drift of the position")
    still_to_moving_per_s: float = num(0.03, 0.001, 30.0, "1/s", 0.1,
        "switching rate still -> moving")
    moving_to_still_per_s: float = num(0.03, 0.001, 30.0, "1/s", 0.1,
        "switching rate moving -> still")
    gate_sigma: float = num(4.5, 2.0, 20.0, "sigma", 0.5,
        "a measurement farther than this many standard deviations is not used as is")
    outlier_rate_trust: float = num(0.005, 0.0, 1.0, "", 0.005,
        "below this estimated outlier rate a reachable jump is a maneuver at once (above it, "
        "once the next measurement confirms it); one outlier raises the rate to "
        "1 / noise_horizon, which decays below 0.005 in about 70 measurements: one false "
        "detection seen in the last second is enough to make the next jump wait for its "
        "confirmation")
    outlier_spread_mm: float = num(1000.0, 10.0, 20000.0, "mm", 100.0,
        "false detections lie within about this distance of the object (a ball seen on a "
        "robot nearby): with outliers seen, a measurement is used only where it is likelier "
        "the object's than a false one's")
    max_speed_mm_s: float = num(6500.0, 100.0, 20000.0, "mm/s", 100.0,
        "a jump farther than this speed allows is an outlier, not a maneuver")
    gap_s: float = num(1.0, 0.01, 10.0, "s", 0.05,
        "no measurement for longer than this: re-initialise")
    angle_init_noise_rad: float = num(0.05, 1e-4, 1.0, "rad", 0.005,
        "orientation: noise assumed before any data")
    angle_min_noise_rad: float = num(0.001, 1e-5, 0.5, "rad", 0.001,
        "orientation: lower bound of the estimated noise")
    angle_max_noise_rad: float = num(0.5, 1e-3, 3.0, "rad", 0.01,
        "orientation: upper bound of the estimated noise")
    angle_accel_init_rad_s2: float = num(10.0, 0.001, 1e4, "rad/s^2", 1.0,
        "orientation, moving model: std of the white angular acceleration before any data")
    angle_accel_min_rad_s2: float = num(0.01, 1e-4, 1e4, "rad/s^2", 0.01,
        "orientation: lower bound of the estimated angular acceleration noise")
    angle_accel_max_rad_s2: float = num(1000.0, 0.01, 1e5, "rad/s^2", 10.0,
        "orientation: upper bound of the estimated angular acceleration noise")
    angle_still_drift_rad_s: float = num(0.002, 0.0, 10.0, "rad/s^0.5", 0.001,
        "orientation, still model: random-walk drift")
    angle_max_rate_rad_s: float = num(30.0, 0.1, 200.0, "rad/s", 1.0,
        "orientation: a jump faster than this is an outlier")


class FilterSettings(BaseModel):
    """Which filter each object uses, and the parameters of every kind."""

    model_config = _CFG
    # adaptive: no tuning for the noise level (docs/experiments/filters, section (d), with the
    # closed-loop runs behind the choice); the others stay selectable per class and per robot
    ball: FilterKind = plain(default="adaptive", description="filter of the ball")
    robot: FilterKind = plain(default="adaptive",
                              description="filter of every robot without an override")
    robot_overrides: dict[str, FilterKind] = plain(
        default_factory=dict, description='per-robot filter, keyed "team/id", e.g. "blue/3"')
    raw: RawParams = group(RawParams, "parameters of 'raw'")
    median: MedianParams = group(MedianParams, "parameters of 'median'")
    paper: PaperParams = group(PaperParams, "parameters of 'paper'")
    kalman: KalmanParams = group(KalmanParams, "parameters of 'kalman'")
    adaptive: AdaptiveParams = group(AdaptiveParams, "parameters of 'adaptive'")

    @field_validator("robot_overrides")
    @classmethod
    def _keys(cls, v: dict[str, FilterKind]) -> dict[str, FilterKind]:
        check_robot_keys(v)
        if len(v) > 32:
            raise ValueError("at most 32 robot overrides")
        return v

    def robot_kind(self, team: str, rid: int) -> FilterKind:
        return self.robot_overrides.get(f"{team}/{rid}", self.robot)

    def params_for(self, kind: FilterKind) -> (RawParams | MedianParams | PaperParams
                                               | KalmanParams | AdaptiveParams):
        if kind == "adaptive":
            return self.adaptive
        if kind == "raw":
            return self.raw
        if kind == "median":
            return self.median
        if kind == "paper":
            return self.paper
        return self.kalman
