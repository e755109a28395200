"""Vision filters: raw, median, the URoboRus 2022 paper filter, constant-velocity Kalman."""

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
    FilterKind,
    FilterSettings,
    KalmanParams,
    MedianParams,
    PaperParams,
    RawParams,
)

__all__ = [
    "FILTER_KINDS", "AngleFilter", "FilterKind", "FilterSettings", "KalmanCV", "KalmanParams",
    "MedianFilter", "MedianParams", "MedianWeighted", "PaperFilter", "PaperParams",
    "PositionFilter", "RawFilter", "RawParams", "VelocityFit", "make_filter",
]
