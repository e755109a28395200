"""Vision filters: raw, median, the URoboRus 2022 paper filter, constant-velocity Kalman, and the
default: an adaptive still/moving IMM."""

from .adaptive import AdaptiveIMM
from .core import (
    AngleFilter,
    KalmanCV,
    MedianFilter,
    MedianWeighted,
    PaperFilter,
    PositionFilter,
    RawFilter,
    VelocityFit,
    make_filter,
)
from .params import (
    FILTER_KINDS,
    AdaptiveParams,
    FilterKind,
    FilterSettings,
    KalmanParams,
    MedianParams,
    PaperParams,
    RawParams,
)

__all__ = [
    "FILTER_KINDS", "AdaptiveIMM", "AdaptiveParams", "AngleFilter", "FilterKind", "FilterSettings",
    "KalmanCV", "KalmanParams", "MedianFilter", "MedianParams", "MedianWeighted", "PaperFilter",
    "PaperParams", "PositionFilter", "RawFilter", "RawParams", "VelocityFit", "make_filter",
]
