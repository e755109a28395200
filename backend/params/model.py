"""Every tunable of the station, declared once. The UI renders its forms from the JSON schema
of ``StationParams``: each number has a default, a range, a step, a unit and a description.

No parameter names a folder or a file: those are set when the station starts
(``backend/config.py``, docs/security.md). A string parameter is a Literal, or carries a pattern
that excludes '/', '\\' and '..' (tests/backend/test_params_paths.py walks the schema)."""

from __future__ import annotations

from typing import Annotated, Literal

from pydantic import BaseModel, ConfigDict, Field

from ..control.params import ControlSettings
from ..filters.params import FilterSettings
from .fields import num


class Group(BaseModel):
    model_config = ConfigDict(extra="forbid", allow_inf_nan=False, validate_assignment=True)


class TeamParams(Group):
    """Which robots are ours and where our goal is."""

    our_team: Literal["blue", "yellow"] = Field(
        default="blue", description="the team the station controls")
    our_side: Literal["negative-x", "positive-x"] = Field(
        default="negative-x", description="the half our goal is on (vision frame)")
    side_from_referee: bool = Field(
        default=True, description="follow the referee's side (blue_team_on_positive_half) when "
                                  "it sends one, e.g. after the half-time side switch")


PlayName = Literal["match", "defend", "attack-drill", "formation", "simple", "idle"]
#: the built-in plays; the team folder's plays come beside them (a play is checked against
#: both when it is chosen: ``ParamStore.play_names``)
PLAYS: tuple[PlayName, ...] = ("match", "defend", "attack-drill", "formation", "simple", "idle")
#: a play's name: a built-in one, or a team file's stem
PLAY_NAME_PATTERN = r"^[A-Za-z][A-Za-z0-9_-]{0,62}$"
#: a robot id as a key of a per-robot map ("0" .. "15")
RobotKey = Annotated[str, Field(pattern=r"^(1[0-5]|[0-9])$")]


class StrategyParams(Group):
    """What our robots do on their own (operator targets always come first), and the compute
    engine that may compute a role (its scripts folder is set at start: --scripts-dir)."""

    play: str = Field(
        default="formation", pattern=PLAY_NAME_PATTERN,
        description="match: full game; defend: keeper + defenders only; attack-drill: go for "
                    "the ball and score; formation: classroom formations; simple: the simple "
                    "opponent; idle: robots only move on operator targets; or a play of the "
                    "team folder (its file name, e.g. pass_drill for team/pass_drill.py)")
    robot_plays: dict[RobotKey, Annotated[str, Field(pattern=PLAY_NAME_PATTERN)]] = Field(
        default_factory=dict, max_length=16,
        description='a play per robot of ours, by id ({"3": "pass_drill"}); the others run '
                    "strategy.play (null for an id removes it)")
    team_budget_ms: float = num(10.0, 1.0, 200.0, "ms", 1.0,
                                "CPU time a team play may use per tick: over it, that tick's "
                                "orders are discarded (the robots stop); 3 ticks in a row, "
                                "or 10 budgets (at least 0.25 s) of CPU time in one call, "
                                "and the play stops until its file is saved again")
    formation_period_s: float = num(5.0, 1.0, 60.0, "s", 0.5, "time on each formation")
    kick_speed_mps: float = num(5.5, 1.0, 6.5, "m/s", 0.1, "shot speed (the rules allow 6.5)")
    pass_speed_mps: float = num(3.0, 0.5, 6.5, "m/s", 0.1, "pass and free-kick speed")
    stop_distance_mm: float = num(650.0, 500.0, 1500.0, "mm", 10.0,
                                  "distance to the ball our robots keep during STOP and the "
                                  "other team's set pieces (rules: 500 mm; includes margin)")
    robot_margin_mm: float = num(60.0, 0.0, 500.0, "mm", 5.0,
                                 "clearance kept from other robots when planning paths")
    defense_margin_mm: float = num(120.0, 0.0, 500.0, "mm", 5.0,
                                   "clearance kept from defence areas robots may not enter")
    placement_speed_mps: float = num(0.8, 0.1, 1.5, "m/s", 0.05,
                                     "speed while carrying the ball for ball placement")
    keeper_min_speed_mmps: float = num(300.0, 0.0, 3000.0, "mm/s", 10.0,
                                       "the keeper intercepts balls faster than this towards "
                                       "our goal; slower ones it mirrors")
    assignment: Literal["sum", "bottleneck"] = Field(
        default="sum", description="role assignment: least total distance (sum) or soonest "
                                   "last arrival (bottleneck)")
    assignment_hysteresis_mm: float = num(400.0, 0.0, 3000.0, "mm", 10.0,
                                          "a robot keeps its role unless a swap saves more")
    engine: Literal["off", "numpy", "octave"] = Field(
        default="off", description="compute engine for the goalkeeper: off (built-in code), "
                                   "numpy (worker process) or octave (the .m scripts)")
    goalkeeper_function: str = Field(
        default="goalkeeper", pattern=r"^[A-Za-z]\w*(\.[A-Za-z]\w*)?$",
        description="engine function computing the keeper's target, called as "
                    "f(ball, velocity, goal_x, goal_width, margin, min_speed); file.function "
                    "for multi-function files")
    engine_timeout_s: float = num(0.2, 0.01, 2.0, "s", 0.01,
                                  "an engine call slower than this is abandoned (its worker "
                                  "restarted); the strategy never waits for the engine: it "
                                  "uses the newest answer up to 0.25 s old, else built-in code")


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


class KickParams(Group):
    """Kick detection (backend/world/kick.py): a ball whose speed jumps next to a robot's
    front starts a kick, with its stop point predicted by constant rolling deceleration."""

    enabled: bool = Field(default=True, description="detect kicks (world message, tracked "
                          "vision kicked_ball, the field's kick layer)")
    decel_mps2: float = num(0.4, 0.05, 5.0, "m/s^2", 0.05,
                            "rolling deceleration of the ball, for the stop prediction "
                            "(fieldsim: 0.4; real balls roll at about 0.3-0.5 after sliding)")
    jump_mps: float = num(1.0, 0.2, 6.0, "m/s", 0.1,
                          "a kick: the ball's speed rises by more than this ...")
    jump_window_s: float = num(0.05, 0.01, 0.3, "s", 0.01, "... within this long")
    reach_mm: float = num(100.0, 0.0, 500.0, "mm", 10.0,
                          "the kick starts at most this far beyond a robot's radius")
    front_half_angle_deg: float = num(60.0, 10.0, 180.0, "deg", 5.0,
                                      "a robot's front: this far either side of its heading")
    stop_mps: float = num(0.1, 0.01, 1.0, "m/s", 0.01, "slower than this: the kick is over")
    max_turn_deg: float = num(30.0, 5.0, 120.0, "deg", 5.0,
                              "the ball turned more than this (touch, bounce): the kick is over")
    fit_window_s: float = num(0.15, 0.05, 1.0, "s", 0.05,
                              "the stop point is fitted on this long of the newest measurements")
    chips: bool = Field(default=True, description="estimate chipped balls in 3D from the "
                        "cameras' positions (backend/world/flight.py)")
    chip_restitution: float = num(0.5, 0.0, 0.95, "", 0.05,
                                  "vertical speed a chipped ball keeps at a bounce, for its "
                                  "landing and stop prediction (fieldsim: 0.5)")


class SafetyParams(Group):
    """When the station commands zero on its own."""

    vision_stale_s: float = num(0.3, 0.05, 2.0, "s", 0.05,
                                "no vision for this long: every robot gets zero")
    strategy_stale_s: float = num(0.5, 0.1, 5.0, "s", 0.1,
                                  "no new targets from the strategy for this long (stalled "
                                  "or crashed): every robot gets zero")
    stop_speed_mps: float = num(1.5, 0.1, 1.5, "m/s", 0.05,
                                "speed cap during STOP (the rules allow 1.5 m/s)")
    other_team_in_simulator: bool = Field(
        default=False, description="let operators drive the other team's robots too, in a "
        "simulator only (classroom); never on real robots, whose datagrams have no team")


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


class RecordingParams(Group):
    """The session recorder: every live session as an SSL log file (docs/logformat.md), into
    the folder set at start (--record-dir, else logs/ in the state folder)."""

    enabled: bool = Field(default=True, description="record every live session (vision, "
                          "referee, world, commands, operator actions, health)")
    max_mb: int = num(1024, 1, 65536, "MB", 64, "a file larger than this is closed and the "
                      "next one started")
    rotate_on_stage: bool = Field(default=True, description="start a new file when the game "
                                  "stage changes (first half, half time, ...)")


class TrackerParams(Group):
    """The world estimate published as the league's tracked vision (TrackerWrapperPacket,
    through the relay: on loopback unless the relay is started with --tracker-out)."""

    publish: bool = Field(default=True, description="send the world estimate to the relay as "
                          "tracked vision, one frame per world tick up to max_hz (the relay "
                          "puts it on loopback only, unless started with --tracker-out)")
    max_hz: float = num(100.0, 10.0, 1000.0, "Hz", 10.0,
                        "at most this many tracked frames a second (eight cameras update the "
                        "world hundreds of times a second; the game controller and the "
                        "autorefs need no more)")
    publish_in_replay: bool = Field(default=False, description="publish it while a log is "
                                    "replayed too (off: a replay is never mistaken for the "
                                    "live field)")


class StationParams(Group):
    """All parameters, grouped by the part of the station that uses them."""

    team: TeamParams = Field(default_factory=TeamParams, description="Team and side")
    strategy: StrategyParams = Field(default_factory=StrategyParams,
                                     description="Strategy and plays (paper section 5.3)")
    world: WorldParams = Field(default_factory=WorldParams, description="World model")
    kicks: KickParams = Field(default_factory=KickParams, description="Kick detection")
    filters: FilterSettings = Field(default_factory=FilterSettings,
                                    description="Vision filters (paper section 5.1)")
    control: ControlSettings = Field(default_factory=ControlSettings,
                                     description="Motion control (paper section 5.2)")
    safety: SafetyParams = Field(default_factory=SafetyParams, description="Safety")
    processors: ProcessorParams = Field(default_factory=ProcessorParams,
                                        description="Processors")
    bus: BusParams = Field(default_factory=BusParams, description="Data Bus topic sizes")
    stream: StreamParams = Field(default_factory=StreamParams, description="Browser stream")
    recording: RecordingParams = Field(default_factory=RecordingParams,
                                       description="Recording (SSL log files)")
    tracker: TrackerParams = Field(default_factory=TrackerParams,
                                   description="Tracked vision out")
