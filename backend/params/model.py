"""Every tunable of the station, declared once. The UI renders its forms from the JSON schema
of ``StationParams``: each number has a default, a range, a step, a unit and a description."""

from __future__ import annotations

from typing import Any, Literal

from pydantic import BaseModel, ConfigDict, Field

from ..control.params import ControlSettings
from ..filters.params import FilterSettings


def num(default: float, ge: float, le: float, unit: str, step: float, description: str) -> Any:
    """A tunable number: its bounds, unit and step travel in the schema to the UI."""
    return Field(default=default, ge=ge, le=le, description=description,
                 json_schema_extra={"unit": unit, "step": step})


class Group(BaseModel):
    model_config = ConfigDict(extra="forbid", allow_inf_nan=False, validate_assignment=True)


class TeamParams(Group):
    """Which robots are ours and where our goal is."""

    our_team: Literal["blue", "yellow"] = Field(
        default="blue", description="the team the station controls")
    our_side: Literal["negative-x", "positive-x"] = Field(
        default="negative-x", description="the half our goal is on (vision frame)")
    demo: bool = Field(default=True, description="drive our robots between formation points "
                                                 "until an operator gives them targets")
    demo_period_s: float = num(5.0, 1.0, 60.0, "s", 0.5, "time on each demo formation")


class WorldParams(Group):
    """How camera frames are merged into objects."""

    merge_window_s: float = num(0.005, 0.0, 0.008, "s", 0.001,
                                "detections of different cameras this close in capture time "
                                "are one measurement")
    predict_after_s: float = num(0.05, 0.0, 1.0, "s", 0.01,
                                 "not seen for longer: position extrapolated (predicted)")
    visible_timeout_s: float = num(0.2, 0.05, 2.0, "s", 0.05,
                                   "not seen for this long: marked lost")
    drop_timeout_s: float = num(3.0, 0.5, 30.0, "s", 0.5, "not seen for this long: removed")


class SafetyParams(Group):
    """When the station commands zero on its own."""

    vision_stale_s: float = num(0.3, 0.05, 2.0, "s", 0.05,
                                "no vision for this long: every robot gets zero")
    stop_speed_mps: float = num(1.5, 0.1, 1.5, "m/s", 0.05,
                                "speed cap during STOP (the rules allow 1.5 m/s)")


class ProcessorParams(Group):
    """Processor rates."""

    strategy_hz: float = num(20.0, 1.0, 200.0, "Hz", 1.0, "strategy (targets) rate")
    control_max_wait_s: float = num(0.05, 0.005, 0.5, "s", 0.005,
                                    "control runs at least this often without vision")


class BusParams(Group):
    """Capacity of each Data Bus topic (records kept; older ones are evicted)."""

    vision_packets: int = num(64, 1, 10000, "records", 1, "raw vision datagrams")
    referee_packets: int = num(30, 1, 10000, "records", 1, "raw referee datagrams")
    vision_detections: int = num(64, 1, 10000, "records", 1, "decoded camera frames")
    referee: int = num(30, 1, 10000, "records", 1, "decoded referee states")
    world: int = num(30, 1, 10000, "records", 1, "world states")
    robot_commands: int = num(20, 1, 10000, "records", 1, "command sets")

    def sizes(self) -> dict[str, int]:
        return {name.replace("_", "-"): int(v) for name, v in self.model_dump().items()}


class StreamParams(Group):
    """Browser streaming."""

    ws_max_hz: float = num(60.0, 1.0, 120.0, "Hz", 1.0, "world updates per second per client")


class StationParams(Group):
    """All parameters, grouped by the part of the station that uses them."""

    team: TeamParams = Field(default_factory=TeamParams, description="Team and side")
    world: WorldParams = Field(default_factory=WorldParams, description="World model")
    filters: FilterSettings = Field(default_factory=FilterSettings,
                                    description="Vision filters (paper section 5.1)")
    control: ControlSettings = Field(default_factory=ControlSettings,
                                     description="Motion control (paper section 5.2)")
    safety: SafetyParams = Field(default_factory=SafetyParams, description="Safety")
    processors: ProcessorParams = Field(default_factory=ProcessorParams,
                                        description="Processors")
    bus: BusParams = Field(default_factory=BusParams, description="Data Bus topic sizes")
    stream: StreamParams = Field(default_factory=StreamParams, description="Browser stream")
