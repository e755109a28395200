"""The browser contract, defined once: every websocket message and every JSON body the station
sends, as typed dictionaries.

The station builds these dictionaries directly (mypy checks every builder against them, at no
cost at run time); the tests validate real payloads against them with pydantic, refusing any key
not declared here; ``scripts/gen_contract.py`` generates the TypeScript types
(``frontend/src/api/contract.gen.ts``) and the message reference of ``docs/api.md`` from them,
and a test fails when either is out of date. Units: lengths mm, angles rad, speeds m/s where the
name says ``_mps`` (else mm/s), times s. The HTTP request bodies are pydantic models here too
(FastAPI validates every request against them; their TypeScript types are generated as well).
"""

from __future__ import annotations

from typing import Annotated, Literal, NotRequired

from pydantic import BaseModel, ConfigDict, Field, with_config
from typing_extensions import TypedDict

# the contract's names for the domain's types (one definition each, in domain/)
from domain.rules import BALL_RADIUS_MM, ROBOT_RADIUS_MM
from domain.rules import RefereeCommand as RefereeCommand
from domain.teams import Team as Team

Side = Literal["negative-x", "positive-x"]
ControlAlgorithm = Literal["algorithm1", "algorithm2", "proportional"]
#: the filter in use for an object: "raw", "median", "paper", "kalman", "adaptive" ("" before any)
FilterName = Annotated[str, Field(
    description='"raw", "median", "paper", "kalman" or "adaptive"')]
#: who set a robot's target: an operator's click, the strategy (a built-in play), or a play of
#: the team's own code (team/)
TargetSource = Literal["operator", "strategy", "team"]

_STRICT = ConfigDict(extra="forbid")


@with_config(_STRICT)
class Vec(TypedDict):
    x: float
    y: float


# ------------------------------------------------------------------------------ world


@with_config(_STRICT)
class RobotRef(TypedDict):
    team: Team
    id: int


@with_config(_STRICT)
class BallKick(TypedDict):
    """A kick in progress (backend/world/kick.py): where and when it started, its initial
    velocity, and where and when the ball is predicted to stop (constant rolling
    deceleration, parameter kicks.decel_mps2)."""

    robot: Annotated[RobotRef | None, Field(description="the kicker (nearest robot front)")]
    start_x: Annotated[float, Field(description="mm, where the kick began")]
    start_y: float
    start_t: Annotated[float, Field(description="Unix s (capture time) of the kick")]
    vx: Annotated[float, Field(description="mm/s, initial velocity")]
    vy: float
    speed_mps: Annotated[float, Field(description="initial speed, m/s")]
    stop_x: Annotated[float, Field(description="mm, predicted stop point")]
    stop_y: float
    stop_t: Annotated[float, Field(description="Unix s (capture time), predicted stop")]
    stop_in_s: Annotated[float, Field(description="predicted stop_t - the world's t_capture")]
    chip: Annotated[bool, Field(
        description="the ball flies (3D estimate): stop after the bounces and the roll")]
    vz: Annotated[float, Field(description="mm/s, a chip's initial vertical speed")]
    land_x: Annotated[float | None, Field(description="mm, where the flight in progress lands")]
    land_y: float | None
    land_t: Annotated[float | None, Field(description="Unix s (capture time) of that landing")]


@with_config(_STRICT)
class Ball(TypedDict):
    """The filtered ball."""

    x: float
    y: float
    vx: float
    vy: float
    visible: bool
    age_s: Annotated[float, Field(description="since the ball was last seen")]
    cameras: list[int]
    raw_x: Annotated[float | None, Field(description="latest merged measurement, mm")]
    raw_y: float | None
    predicted: Annotated[bool, Field(description="position extrapolated: no fresh detection")]
    lost: Annotated[bool, Field(description="not seen for long: dropped from the world soon")]
    filter: FilterName
    kick: Annotated[BallKick | None, Field(description="the kick in progress, if any")]
    z: Annotated[float, Field(description="mm above the field (a chipped ball in flight)")]
    vz: Annotated[float, Field(description="mm/s, upwards")]
    flying: Annotated[bool, Field(
        description="x, y, z from the flight estimate (the cameras see it elsewhere)")]


@with_config(_STRICT)
class OtherBall(TypedDict):
    """A ball seen consistently besides the ball (a second ball left on the field)."""

    x: Annotated[float, Field(description="mm, its latest detection")]
    y: float
    age_s: Annotated[float, Field(description="since it was last seen")]
    cameras: list[int]
    detections: Annotated[int, Field(description="consistent detections so far")]


@with_config(_STRICT)
class RobotControl(TypedDict):
    """Telemetry of a robot's controller (when the station commands it)."""

    algorithm: ControlAlgorithm
    phase: str
    t_s: float
    ref_x_m: float
    has_reference: float
    x_m: float
    path_length_m: float
    lateral_m: float
    cmd_speed_mps: float
    meas_speed_mps: float
    c_estimate: float
    heading_error_rad: float
    restarts: float


@with_config(_STRICT)
class RobotTarget(TypedDict):
    x: float
    y: float
    orientation: float | None
    source: TargetSource


@with_config(_STRICT)
class RobotCommand(TypedDict):
    """The velocity the station commands, in the robot's frame."""

    forward_mps: float
    left_mps: float
    angular_radps: float


@with_config(_STRICT)
class RobotFeedback(TypedDict):
    """What the robot (or the simulator for it) reports back."""

    transport: Annotated[Literal["sim", "grsim"], Field(
        description='"sim": SSL simulation protocol RobotControlResponse (answers every '
        'command); "grsim": grSim Robots_Status (only on a change)')]
    ball_contact: Annotated[bool, Field(
        description="the ball touches the dribbler (dribbler_ball_contact, grSim infrared)")]
    age_s: Annotated[float | None, Field(description="since the last answer")]
    no_answer: Annotated[bool, Field(
        description="commanded but no answer for more than 0.5 s")]
    last_kick: Literal["flat", "chip"] | None
    last_kick_age_s: Annotated[float | None, Field(description="since the last kick reported")]
    round_trip_ms: Annotated[float | None, Field(
        description="command sent by the relay -> answer received (mean of the last 20)")]
    commands_sent: Annotated[int | None, Field(description="commands sent, last 2 s")]
    answers: Annotated[int | None, Field(description="answers received, last 2 s")]
    loss: Annotated[float | None, Field(description="1 - answers / commands sent, last 2 s")]
    battery_v: Annotated[float | None, Field(
        description="battery voltage, V (null until a transport reports it)")]
    kicker_v: Annotated[float | None, Field(
        description="kicker capacitor charge, V (null until a transport reports it)")]


@with_config(_STRICT)
class RobotKick(TypedDict):
    """Kicker armed: the kick speed and whether it chips."""

    speed_mps: float
    chip: bool


@with_config(_STRICT)
class Robot(TypedDict):
    team: Team
    id: int
    x: float
    y: float
    orientation: float
    vx: float
    vy: float
    omega: float
    visible: bool
    age_s: float
    cameras: list[int]
    target: RobotTarget | None
    role: Annotated[str | None, Field(description="strategy role (goalkeeper, attacker, ...)")]
    path: Annotated[list[Vec] | None, Field(
        description="planned waypoints to the target; the last one is the target")]
    kick: RobotKick | None
    dribbler: bool
    controlled: Annotated[bool, Field(description="the station commands this robot")]
    raw_x: float | None
    raw_y: float | None
    raw_orientation: float | None
    predicted: bool
    lost: bool
    filter: FilterName
    control: RobotControl | None
    command: RobotCommand | None
    feedback: RobotFeedback | None


@with_config(_STRICT)
class RawRobot(TypedDict):
    team: Team
    id: int
    x: float
    y: float
    orientation: float


@with_config(_STRICT)
class RawCamera(TypedDict):
    """One camera's latest frame, as detected (before merging and filtering)."""

    camera_id: int
    frame_number: int
    t_capture: float
    age_s: float
    balls: list[Vec]
    robots: list[RawRobot]


@with_config(_STRICT)
class RecordedCommand(TypedDict):
    """In replay: the command the live station sent one robot at this time, as recorded
    (TYPE_TL_COMMANDS), in the robot's frame: what the robot was told, beside what the
    strategy in force now commands it (what-if)."""

    team: Team
    id: int
    forward_mps: float
    left_mps: float
    angular_radps: float
    kick_speed_mps: float
    chip: bool
    dribbler_rpm: float
    age_s: Annotated[float, Field(
        description="log time from the recorded command to the playhead (a robot sent nothing "
                    "for longer than the relay's command timeout, 0.1 s, is not listed: the "
                    "relay sent it zero)")]


@with_config(_STRICT)
class RecordedWorld(TypedDict):
    """In replay: the world the live station estimated at this time, as recorded (tracked
    vision, type 5), drawn beside today's estimate of the same vision (what-if); and the
    commands it sent then (type 1001), beside the commands computed now."""

    source: Annotated[str, Field(
        description='the tracker\'s source name, e.g. Touchline ("" when the log has no '
                    'tracked vision)')]
    ball: Vec | None
    robots: list[RawRobot]
    commands: Annotated[list[RecordedCommand], Field(
        description="the commands recorded for the robots at the playhead (empty when the log "
                    "has none: only Touchline's logs record them)")]


@with_config(_STRICT)
class RefereeTeam(TypedDict):
    name: str
    score: int
    yellow_cards: int
    red_cards: int
    goalkeeper: int
    yellow_card_times_s: Annotated[list[float], Field(
        description="seconds left on each active yellow card")]
    timeouts: int
    timeout_time_s: float
    foul_counter: int | None
    ball_placement_failures: int | None
    can_place_ball: bool | None
    max_allowed_bots: Annotated[int | None, Field(
        description="robots the team may have on the field now (cards lower it)")]
    bot_substitution_intent: bool | None
    bot_substitution_allowed: bool | None


@with_config(_STRICT)
class RefereeGameEvent(TypedDict):
    """A game event as the game controller reports it (newest first)."""

    id: str
    type: Annotated[str, Field(description='proto enum name ("BOT_CRASH_UNIQUE", ...)')]
    by_team: Annotated[str | None, Field(description='"BLUE", "YELLOW"; null: no team')]
    origin: list[str]
    created_s: Annotated[float | None, Field(description="Unix s; null when not sent")]


@with_config(_STRICT)
class Referee(TypedDict):
    """The referee the station obeys (the game controller's or the internal one)."""

    source: Annotated[str, Field(description='"game-controller", "internal" or "none"')]
    source_identifier: str
    command: RefereeCommand
    stage: str
    command_counter: int
    stage_time_left_s: float | None
    blue: RefereeTeam
    yellow: RefereeTeam
    designated_position: Annotated[Vec | None, Field(
        description="the placement position; the official controller sends its last one "
                    "always: use placementTarget (referee.ts)")]
    blue_team_on_positive_half: bool | None
    next_command: str | None
    status_message: str
    match_type: str | None
    current_action_time_remaining_s: float | None
    game_events: list[RefereeGameEvent]
    age_s: float


@with_config(_STRICT)
class EstopInfo(TypedDict):
    """The latched emergency stop."""

    active: bool
    since: Annotated[float, Field(description="Unix s of the last press or release (0: never)")]
    by: Annotated[str, Field(description="who pressed or released it")]
    relay_latched: Annotated[bool | None, Field(
        description="the relay's latch from its statistics; null before any arrived")]


@with_config(_STRICT)
class ArmingInfo(TypedDict):
    """Arming: a relay driving real robots or an external simulator sends nothing but stops
    until an operator arms the station; the e-stop disarms it."""

    required: Annotated[bool, Field(
        description="the relay requires arming (false: the built-in simulator, always armed)")]
    armed: Annotated[bool, Field(
        description="commands may reach the robots (always true when not required)")]
    since: Annotated[float, Field(description="Unix s of the last arm or disarm (0: never)")]
    by: Annotated[str, Field(description="who armed or disarmed it")]
    relay_armed: Annotated[bool | None, Field(
        description="the relay's arming from its statistics; null before any arrived")]
    relay_unconfirmed: Annotated[str | None, Field(
        description="why the relay is not known to be in the station's state (no statistics, "
                    "stale ones, or they say otherwise; POST: not confirmed within 2 s); "
                    "null: it confirmed")]
    refusal: Annotated[str | None, Field(
        description="why arming would be refused now (null: it would be accepted)")]


@with_config(_STRICT)
class StoppedRobot(TypedDict):
    """One of our robots stopped because its play (team code) failed."""

    id: int
    play: str
    reason: Annotated[str, Field(description='the error in one line ("exception at '
                                             'pass_drill.py:12: ZeroDivisionError ...")')]


@with_config(_STRICT)
class StrategyState(TypedDict):
    """What the strategy is doing now (sent with every world update)."""

    play: str
    situation: str
    situation_text: str
    our_team: Team
    our_side: Side
    side_from_referee: Annotated[bool, Field(
        description="our side comes from the referee (blue_team_on_positive_half)")]
    tick_ms: float
    robot_plays: Annotated[dict[str, str], Field(
        description='the play each of our robots runs now, keyed by id ("3"); robots an '
        'operator drives and robots not on the field are left out')]
    stopped: Annotated[list[StoppedRobot], Field(
        description="robots held still because the team-code play that drives them failed "
        "(marked on the field)")]


@with_config(_STRICT)
class Score(TypedDict):
    blue: int
    yellow: int


@with_config(_STRICT)
class InternalReferee(TypedDict):
    """The station's own referee."""

    enabled: bool
    disabled_reason: str
    foreign_source: Annotated[str | None, Field(
        description="a game controller heard on the network (the internal referee steps aside)")]
    command: RefereeCommand
    stage: str
    command_counter: int
    designated_position: Vec | None
    score: Score
    max_allowed_bots: Score
    commands: Annotated[list[RefereeCommand], Field(
        description="the commands an operator may give")]


@with_config(_STRICT)
class ReplayClock(TypedDict):
    """Where a replay is (in every world message while a log plays; null when live)."""

    file: str
    position_s: Annotated[float, Field(description="playhead, s from the log's first record")]
    t_unix: Annotated[float, Field(description="the log's wall time at the playhead, Unix s")]
    duration_s: float
    playing: bool
    speed: Annotated[float, Field(description="1 = real time; 0 = as fast as possible")]
    epoch: Annotated[int, Field(
        description="changes on every open and seek (time jumps: plots start again)")]


@with_config(_STRICT)
class World(TypedDict):
    """The world as the station sees it, with what it commands."""

    seq: int
    t_capture: float
    ball: Ball | None
    other_balls: Annotated[list[OtherBall], Field(
        description="other balls on the field (not the one played), faint on the field")]
    robots: list[Robot]
    cameras: list[RawCamera]
    referee: Referee | None
    estop: bool
    estop_info: EstopInfo
    armed: Annotated[bool, Field(
        description="commands may reach the robots (always true when arming is not required)")]
    arming_required: bool
    arming: ArmingInfo
    halt_reason: Annotated[str, Field(
        description='why every robot is held ("emergency stop", "HALT", "no vision ..."), or ""')]
    strategy: StrategyState | None
    internal_referee: Annotated[InternalReferee, Field(
        description="the station's own referee (the referee panel shows it)")]
    replay: Annotated[ReplayClock | None, Field(
        description="set while the station replays a log (nothing is sent to robots then)")]
    recorded: Annotated[RecordedWorld | None, Field(
        description="in replay, the estimate and the commands recorded in the log (null live, "
                    "or if the log has neither)")]
    team: Annotated[dict[str, dict[str, float]], Field(
        description="the team's processors' latest outputs (team/<name>.py: {key: number}; "
        "booleans as 0/1), plotted as team.<name>.<key>")]


# ------------------------------------------------------------------------------ geometry


@with_config(_STRICT)
class FieldLine(TypedDict):
    name: str
    p1: Vec
    p2: Vec
    thickness: float


@with_config(_STRICT)
class FieldArc(TypedDict):
    name: str
    center: Vec
    radius: float
    a1: float
    a2: float
    thickness: float


@with_config(_STRICT)
class CameraPose(TypedDict):
    """A camera's position from its calibration (mm): the flight estimate needs it."""

    id: int
    x: float
    y: float
    z: Annotated[float, Field(description="height above the field")]


@with_config(_STRICT)
class Geometry(TypedDict):
    """The field from the geometry packet (mm)."""

    field_length: float
    field_width: float
    goal_width: float
    goal_depth: float
    boundary_width: float
    penalty_area_depth: Annotated[float, Field(
        description="as sent, else read off the field lines (grSim sends only those), else 0")]
    penalty_area_width: Annotated[float, Field(
        description="as sent, else read off the field lines, else 0")]
    goal_center_to_penalty_mark: Annotated[float, Field(
        description="the penalty mark's distance from the goal centre; 0 when not sent "
                    "(grSim): the division's, 8 m in A and 6 m in B")]
    center_circle_radius: float
    ball_radius: float
    max_robot_radius: float
    lines: list[FieldLine]
    arcs: list[FieldArc]
    cameras: Annotated[list[CameraPose], Field(
        description="where the cameras hang (calibration derived_camera_world_t*), if sent")]


# ------------------------------------------------------------------------------ health


@with_config(_STRICT)
class StreamHealth(TypedDict):
    packets: int
    errors: int
    errors_by_reason: Annotated[dict[str, int], Field(
        description='refused datagrams (for vision also what the world model dropped) by '
                    'reason: "truncated", "not protobuf", "time out of range", ...')]
    rate_hz: float
    last_age_s: float
    last_error: str


@with_config(_STRICT)
class ProcessorHealth(TypedDict):
    name: str
    trigger: str
    configured_hz: float | None
    measured_hz: float
    tick_mean_ms: float
    tick_p99_ms: float
    overruns: int
    runs: int
    errors: int
    last_error: str


@with_config(_STRICT)
class TopicHealth(TypedDict):
    name: str
    size: int
    capacity: int
    seq: int
    age_s: Annotated[float, Field(description="since the last write; -1: never written")]


@with_config(_STRICT)
class RelayHealth(TypedDict):
    """The relay's statistics, as it last published them."""

    time_ns: int
    output_mode: str
    active_robots: int
    stale_robots: int
    output_rate_hz: float
    command_latency_ms: Annotated[float, Field(
        description="mean vision arrival -> first command datagram sent, last second")]
    command_latency_p50_ms: float
    command_latency_p99_ms: float
    stale_stops: int
    estop_latched: Annotated[bool, Field(description="only zeros leave the relay while true")]
    estop_by: str
    armed: Annotated[bool, Field(description="the relay sends commands (else only stops)")]
    arming_required: Annotated[bool, Field(description="the relay started with --require-arming")]
    alive: bool
    age_s: float


@with_config(_STRICT)
class LatencyHealth(TypedDict):
    mean_ms: float
    p50_ms: float
    p99_ms: float
    n: int


@with_config(_STRICT)
class LatencyStage(TypedDict):
    """One stage from a vision datagram's arrival at the relay, in pipeline order."""

    stage: str
    mean_ms: float
    p50_ms: float | None
    p99_ms: float | None
    n: int | None


@with_config(_STRICT)
class EngineHealth(TypedDict):
    """The compute engine the strategy calls (null when off)."""

    kind: str
    function: str
    running: bool
    calls_per_s: float
    latency_mean_ms: float
    latency_p99_ms: float
    calls: int
    ok: int
    errors: int
    timeouts: int
    crashes: int
    restarts: int
    start_failures: int
    last_error: str
    workers: int
    busy: int
    idle: int
    fallbacks: Annotated[int, Field(
        description="strategy ticks that used the built-in code because the engine failed")]


@with_config(_STRICT)
class RefereeHealth(TypedDict):
    """The newest referee message as health sees it."""

    last_heard_s: float
    source_identifier: str
    source: Literal["game-controller", "internal"]
    command: Annotated[str, Field(description="what the station still obeys")]
    obeyed: Annotated[bool, Field(description="false: the internal referee, switched off")]
    silent: bool
    silent_after_s: float


@with_config(_STRICT)
class CameraPair(TypedDict):
    """How far camera b sees the robots both see from where camera a sees them (b - a, mm):
    a calibration offset between two cameras. Still robots only; a running mean."""

    camera_a: int
    camera_b: int
    dx_mm: float
    dy_mm: float
    samples: int


@with_config(_STRICT)
class WorldHealth(TypedDict):
    """The world model: its age by the receive clock, what it dropped and why."""

    age_s: float | None
    stale: bool
    rejected: dict[str, int]
    recent_rejections: dict[str, int]
    last_rejection: str
    clock_resyncs: int
    camera_clock_offsets_s: Annotated[dict[str, float | None], Field(
        description="per camera: receive - capture (s)")]
    camera_pairs: list[CameraPair]
    camera_rates_hz: Annotated[dict[str, float], Field(
        description="per camera heard within the last second: frames a second by the receive "
        "clock (0: not measured yet)")]
    lost_after_s: Annotated[float | None, Field(
        description="every camera silent this long: every robot is stopped (6 frame periods, "
        "at most 0.1 s less 20 ms for the stop to reach the robots; null: a camera slower than "
        "30 Hz or not measured yet, then safety.vision_stale_s)")]
    vision_lost: Annotated[str | None, Field(
        description="every camera silent past lost_after_s: why every robot is stopped (as "
        "world.halt_reason says), else null")]


@with_config(_STRICT)
class ProcessHealth(TypedDict):
    """One process of the station: what it costs the machine."""

    name: Annotated[str, Field(description='"backend", "relay"')]
    cpu_percent: Annotated[float, Field(description="% of one core over the last second")]
    rss_mb: Annotated[float, Field(description="resident memory")]


@with_config(_STRICT)
class SupervisedProcess(TypedDict):
    """A process the launcher started and restarts when it dies."""

    name: str
    pid: int | None
    restarts: int
    last_exit: Annotated[int | None, Field(description="exit code of the last crash")]
    up_s: Annotated[float, Field(description="since it was (re)started")]


@with_config(_STRICT)
class Recording(TypedDict):
    """The session recorder (SSL log files in var/logs/, docs/logformat.md)."""

    enabled: bool
    recording: Annotated[bool, Field(description="a file is open and being written")]
    file: Annotated[str, Field(description="name of the file being written, or the last one")]
    folder: str
    size_bytes: int
    duration_s: float
    records: int
    dropped: Annotated[int, Field(description="records lost because the writer fell behind")]
    error: Annotated[str, Field(description='why recording stopped (e.g. disk full), or ""')]


@with_config(_STRICT)
class StationFolder(TypedDict):
    """A folder the station reads code from or writes to. Set when the station starts (its
    flag, or its environment variable), never by a parameter or a request (docs/security.md)."""

    name: Annotated[str, Field(description='the setting: "scripts_dir", "record_dir", ...')]
    label: str
    what: Annotated[str, Field(description="what the station reads or writes there")]
    paths: Annotated[list[str], Field(
        description="absolute, as this run uses them; empty: none (e.g. no state kept)")]
    flag: Annotated[str, Field(description='the command-line flag, e.g. "--scripts-dir"')]
    env: Annotated[str, Field(description='the environment variable, e.g. '
                                          '"TOUCHLINE_SCRIPTS_DIR"')]


@with_config(_STRICT)
class StationFolders(TypedDict):
    """GET /api/folders: the station's folders, read-only."""

    folders: list[StationFolder]


# ------------------------------------------------------------------------------ evaluation


EvaluationState = Literal["idle", "running", "done", "failed", "cancelled"]


@with_config(_STRICT)
class EvaluationJob(TypedDict):
    """The Evaluate tab's job (one at a time; evaluate/, docs/evaluate.md), in every health
    message: its progress as the runs come back from the pool."""

    id: Annotated[int, Field(description="counts the jobs since the start (0: none yet)")]
    state: EvaluationState
    kind: Literal["suite", "class"] | None
    suite: str
    play: Annotated[str | None, Field(description="null: each scenario's own play")]
    done: int
    total: int
    passed: int
    failed: int
    started_unix: float | None
    finished_unix: float | None
    report: Annotated[str | None, Field(description="the report's name (its folder)")]
    by: Annotated[str, Field(description="who started it")]
    error: Annotated[str, Field(description='why the job failed, or ""')]
    last: Annotated[str, Field(description="the last run that came back, and how")]


@with_config(_STRICT)
class EvaluationScenario(TypedDict):
    name: str
    title: str
    statement: Annotated[str, Field(description="what a student reads")]
    runs: int
    play: Annotated[str | None, Field(description="the play the scenario names")]
    duration_s: float


@with_config(_STRICT)
class EvaluationSuite(TypedDict):
    name: str
    error: Annotated[str, Field(description='a scenario file that cannot be used, or ""')]
    scenarios: list[EvaluationScenario]


@with_config(_STRICT)
class EvaluationReportInfo(TypedDict):
    name: Annotated[str, Field(description="the report's folder in the reports folder")]
    title: str
    kind: Annotated[str, Field(description="suite, ab-suite, matches, ab-matches, class")]
    created_unix: float
    runs: int
    passed: int
    score: float | None


@with_config(_STRICT)
class EvaluationView(TypedDict):
    """GET /api/evaluate: what can be run, the job, the reports."""

    available: bool
    reason: Annotated[str, Field(description='why the tab cannot run jobs, or ""')]
    suites: list[EvaluationSuite]
    class_dir: str | None
    students: Annotated[list[str], Field(description="the class folder's sub-folders")]
    workers: Annotated[int, Field(description="the local pool's workers")]
    cluster: Annotated[str | None, Field(
        description="the Dask cluster the jobs run on (--eval-cluster), or null: the local "
                    "pool")]
    job: EvaluationJob
    reports: list[EvaluationReportInfo]


@with_config(_STRICT)
class EvaluationCheck(TypedDict):
    name: str
    label: str
    passed: bool
    score: float
    detail: str


@with_config(_STRICT)
class EvaluationRun(TypedDict):
    id: Annotated[str, Field(description="the run's name in its report (POST "
                                         "/api/evaluate/replay takes it)")]
    name: str
    scenario: str
    title: str
    student: str | None
    seed: int
    passed: bool
    score: float
    detail: Annotated[str, Field(description="a match's score line")]
    error: str
    team_error: Annotated[str, Field(
        description='why the team play failed (its file\'s error with its line first, or why '
                    'its robots were stopped), or ""')]
    sim_s: float
    replay: Annotated[bool, Field(description="its SSL log was kept")]
    checks: list[EvaluationCheck]


@with_config(_STRICT)
class EvaluationCell(TypedDict):
    passed: bool
    score: float
    runs: int
    runs_passed: int
    sim_s: float
    note: str
    run: Annotated[str | None, Field(description="the run to replay (the first failed one)")]


@with_config(_STRICT)
class EvaluationGrade(TypedDict):
    student: str
    score: float
    passed: int
    scenarios: int
    cells: Annotated[dict[str, EvaluationCell], Field(description="by exercise")]


@with_config(_STRICT)
class EvaluationReport(TypedDict):
    """GET /api/evaluate/reports/{name}: the runs with their checks, and a class's grades."""

    name: str
    title: str
    kind: str
    created_unix: float
    passed: int
    score: float | None
    verdict: Annotated[str, Field(description="an A/B or a match series: is the difference "
                                              'real ("not significant: ...")')]
    exercises: list[str]
    grades: list[EvaluationGrade]
    runs: Annotated[list[EvaluationRun], Field(description="every run, in the report's order")]
    timing: dict[str, float]


@with_config(_STRICT)
class AccessHealth(TypedDict):
    """Who may do what (docs/security.md) and what was refused since the start."""

    token_required: Annotated[bool, Field(
        description="changes need the operator token (not on loopback, or --require-token)")]
    view_token: Annotated[bool, Field(description="viewing needs a token too (--view-token)")]
    estop_for_all: Annotated[bool, Field(
        description="a viewer may press the emergency stop (--estop-for-all)")]
    refused: Annotated[dict[str, int], Field(
        description='refusals by reason: "no operator token", "no viewer token", '
                    '"wrong token", "rate-limited"')]
    blocked_clients: Annotated[int, Field(
        description="addresses refused now for too many wrong tokens")]


@with_config(_STRICT)
class OperatorInfo(TypedDict):
    """One page connected (a websocket client): who, from where, since when."""

    session: Annotated[int, Field(description="this connection's number")]
    name: Annotated[str, Field(description="the name given at login")]
    role: Annotated[str, Field(description='"operator" or "viewer"')]
    address: str
    since_unix: float


@with_config(_STRICT)
class DrivingInfo(TypedDict):
    """Who drives a team (one operator per team: docs/security.md, "Several operators")."""

    team: str
    key: Annotated[str, Field(
        description="the holder: name@address (GET /api/operators tells the page its own)")]
    name: str
    address: str
    since_unix: float
    connected: Annotated[bool, Field(
        description="the holder has a page open (else it is released a few seconds after)")]
    requested_by: Annotated[str | None, Field(description="who asked to drive, if anyone")]
    requested_key: str | None
    requested_unix: float | None


@with_config(_STRICT)
class OperatorAction(TypedDict):
    """One operator action (the newest are kept; the session log has them all)."""

    seq: int
    time_unix: float
    action: Annotated[str, Field(description="target, params, play, referee, estop, arm, ...")]
    by: str
    details: str


# ------------------------------------------------------------------------------ team code


TeamFileKind = Literal["play", "processor", "library"]
TeamLanguage = Literal["python", "octave"]
TeamFileState = Literal["idle", "starting", "running", "error"]
TeamErrorKind = Literal["import", "exception", "output", "budget", "crash", "missing"]


@with_config(_STRICT)
class TeamError(TypedDict):
    """Why a file of the team's code does not run (it stays so until the file, or a library
    it uses, is saved again)."""

    kind: Annotated[TeamErrorKind, Field(
        description='"import": does not load (syntax, import, a name taken); "exception": '
        'raised; "output": malformed answer (wrong type, NaN, a robot it does not drive); '
        '"budget": over its time budget 3 ticks in a row, spinning (over its CPU limit in '
        'one call) or stuck (no answer within the wall-clock backstop), its worker ended; '
        '"crash": its worker process died; "missing": the file of a chosen play is gone')]
    message: str
    file: Annotated[str, Field(description='the team file it happened in ("lib/util.py")')]
    line: int | None
    traceback: str
    at_unix: float


@with_config(_STRICT)
class TeamFile(TypedDict):
    """One file of the team folder and how it runs."""

    name: Annotated[str, Field(description='path in the team folder: "pass_drill.py", '
                                           '"lib/util.m"')]
    kind: TeamFileKind
    language: TeamLanguage
    play: Annotated[str | None, Field(description="the play's name (a play's file stem)")]
    title: Annotated[str, Field(description="TITLE (Python) or the first help line (.m)")]
    description: str
    state: Annotated[TeamFileState, Field(
        description='"idle": not in use (a play nobody runs, a library); "starting": its '
        'worker is starting; "running"; "error": see error')]
    error: TeamError | None
    version: Annotated[str, Field(description="12 hex digits of the content's SHA-256")]
    mtime_unix: float
    size_bytes: int
    reloaded_at_unix: Annotated[float | None, Field(
        description="when the running version was loaded (null: not loaded)")]
    reloads: int
    ticks: int
    errors: int
    overruns: Annotated[int, Field(description="ticks over the time budget (output discarded)")]
    late: Annotated[int, Field(
        description="ticks whose answer came after the tick stopped waiting (the budget + a "
                    "grace, wall clock: a busy machine), not over the budget (output discarded)")]
    moved_out: Annotated[int, Field(
        description="targets the safety envelope moved out of a forbidden area, or capped")]
    tick_ms_p50: Annotated[float | None, Field(description="CPU time of a tick, ms")]
    tick_ms_p99: float | None
    robots: Annotated[list[int], Field(description="our robots it drives now (plays)")]
    outputs: Annotated[dict[str, float], Field(
        description="a processor's latest outputs (booleans as 0/1)")]


@with_config(_STRICT)
class TeamEdit(TypedDict):
    allowed: Annotated[bool, Field(description="this caller may save files from the page")]
    reason: Annotated[str | None, Field(description="why not (null when allowed)")]


@with_config(_STRICT)
class TeamCode(TypedDict):
    """GET /api/team: the team folder (a start-time setting: --team-dir, make run TEAM=)."""

    dir: str
    api_version: Annotated[int, Field(description="touchline.API_VERSION the station speaks")]
    edit: TeamEdit
    files: list[TeamFile]


@with_config(_STRICT)
class TeamFileText(TypedDict):
    """GET /api/team/files/{name}."""

    name: str
    text: str
    version: str
    language: TeamLanguage


@with_config(_STRICT)
class TeamFileSaved(TypedDict):
    """The answer of PUT /api/team/files/{name}: saved, and being reloaded."""

    name: str
    version: str
    saved_at_unix: float


@with_config(_STRICT)
class StartupInfo(TypedDict):
    """The backend's start (backend/startup.py): the first command's steps first, then what
    it does not need."""

    restarted: Annotated[bool, Field(
        description="restarted by the launcher's supervisor after a crash (arming taken back)")]
    standby: Annotated[bool, Field(
        description="a warm spare the supervisor told to start: imported before the crash; "
                    "its steps count from the word to start")]
    steps_s: Annotated[dict[str, float], Field(
        description="seconds from the backend's process start (a warm spare: from the word to "
                    "start) at which each step was done: "
                    "imports, station built, station running, first frame, first targets, "
                    "first command; then recorder open, engine started, web imports, web "
                    "serving (a step not done yet is absent)")]


@with_config(_STRICT)
class Health(TypedDict):
    """The station's health (GET /api/health and the websocket)."""

    ok: Annotated[bool, Field(
        description="the loop works (fresh vision, relay alive); a silent referee leaves it true")]
    warnings: Annotated[list[str], Field(description="one line per problem")]
    estop: EstopInfo
    arming: ArmingInfo
    world: WorldHealth | None
    referee: RefereeHealth | None
    uptime_s: float
    streams: dict[str, StreamHealth]
    processors: list[ProcessorHealth]
    topics: list[TopicHealth]
    relay: RelayHealth | None
    latency: LatencyHealth | None
    latency_stages: list[LatencyStage]
    websocket_clients: int
    websocket_dropped: Annotated[int, Field(
        description="clients dropped because their peer took none of the bytes sent to it for "
                    "1.25 s (stalled: within 2 s of its last read; the connection is reset)")]
    engine: EngineHealth | None
    recording: Recording
    processes: Annotated[list[ProcessHealth], Field(
        description="CPU and memory of the backend and (from its stats) the relay")]
    supervisor: Annotated[list[SupervisedProcess] | None, Field(
        description="what the launcher started, with restarts (null: not started by it)")]
    access: AccessHealth
    operators: Annotated[list[OperatorInfo], Field(description="the pages connected")]
    driving: Annotated[list[DrivingInfo], Field(description="who drives which team")]
    operator_actions: Annotated[list[OperatorAction], Field(
        description="the latest operator actions, newest first")]
    startup: StartupInfo
    team_code: Annotated[list[TeamFile], Field(
        description="the team folder's files and their states (as GET /api/team)")]
    evaluation: EvaluationJob


# ------------------------------------------------------------------------------ parameters


#: parameter values: nested groups of leaves (numbers, strings, booleans)
ParamValues = dict[str, object]


# ------------------------------------------------------------------------------ HTTP bodies


@with_config(_STRICT)
class PlayInfo(TypedDict):
    name: str
    title: str
    description: str
    source: Annotated[Literal["builtin", "team"], Field(
        description='"team": a play of the team folder (its file stem)')]
    file: Annotated[str | None, Field(description="the team file (null for built-in plays)")]
    language: TeamLanguage | None


@with_config(_STRICT)
class StrategyView(StrategyState):
    """GET /api/strategy: the strategy state, the plays to choose from and the roles."""

    plays: list[PlayInfo]
    roles: Annotated[dict[str, str], Field(description='role of each robot, keyed "blue/3"')]


@with_config(_STRICT)
class RefereeView(TypedDict):
    """GET /api/referee (and the answer of every internal-referee POST, without ``active``)."""

    internal: InternalReferee
    active: NotRequired[Annotated[Referee | None, Field(
        description="the referee the station obeys (as in the world message)")]]


@with_config(_STRICT)
class TargetPoint(TypedDict):
    x: float
    y: float
    orientation: float | None


@with_config(_STRICT)
class TargetAnswer(TypedDict):
    """POST /api/robots/{team}/{id}/target (``target`` null after DELETE)."""

    team: Team
    id: int
    target: TargetPoint | None


#: one parameter that differs: its dotted path and both values ("from" is a Python keyword,
#: hence the functional form)
ParamChange = TypedDict("ParamChange", {"path": str, "from": object, "to": object})
with_config(_STRICT)(ParamChange)


@with_config(_STRICT)
class ParamsDiff(TypedDict):
    """GET /api/params/diff: what differs from the defaults."""

    version: int
    changes: list[ParamChange]


@with_config(_STRICT)
class PresetList(TypedDict):
    """GET /api/presets (and the answer of PUT and DELETE /api/presets/{name})."""

    presets: list[str]


@with_config(_STRICT)
class PresetDetail(TypedDict):
    """GET /api/presets/{name}: its values and how they differ from the defaults and from
    the parameters in force."""

    name: str
    values: ParamValues
    diff_from_defaults: list[ParamChange]
    diff_from_current: list[ParamChange]


@with_config(_STRICT)
class EstopAnswer(EstopInfo):
    """The answer of POST /api/estop."""

    estop: bool


# ------------------------------------------------------------------------------ request bodies
# (pydantic models: FastAPI validates each request against them; NaN and unknown keys refused)


class TeamFileIn(BaseModel):
    model_config = ConfigDict(extra="forbid")
    text: str = Field(description="the whole file (UTF-8; at most 256 KB)")
    base_version: str | None = Field(
        default=None, description="the version the edit started from (409 when the file "
        "changed on disk since); null: a new file")


class TargetIn(BaseModel):
    model_config = ConfigDict(allow_inf_nan=False, extra="forbid")
    x: float = Field(description="target x in mm (vision frame)")
    y: float = Field(description="target y in mm")
    orientation: float | None = Field(default=None, description="target heading in rad")


class Point(BaseModel):
    model_config = ConfigDict(allow_inf_nan=False, extra="forbid")
    x: float = Field(description="mm")
    y: float = Field(description="mm")


class RefereeCommandIn(BaseModel):
    model_config = ConfigDict(allow_inf_nan=False, extra="forbid")
    command: RefereeCommand = Field(description="a referee command the operator may give "
                                    "(InternalReferee.commands)")
    designated_position: Point | None = Field(default=None, description="for ball placement")


class CardIn(BaseModel):
    model_config = ConfigDict(extra="forbid")
    team: Literal["blue", "yellow"]
    card: Literal["yellow", "red", "clear"]


class EnableIn(BaseModel):
    model_config = ConfigDict(extra="forbid")
    enabled: bool


class TeleportBallIn(BaseModel):
    model_config = ConfigDict(allow_inf_nan=False, extra="forbid")
    x: float = Field(description="mm")
    y: float = Field(description="mm")
    vx: float = Field(default=0.0, ge=-10, le=10, description="m/s")
    vy: float = Field(default=0.0, ge=-10, le=10, description="m/s")


class TeleportRobotIn(BaseModel):
    model_config = ConfigDict(allow_inf_nan=False, extra="forbid")
    x: float = Field(description="mm")
    y: float = Field(description="mm")
    orientation: float | None = Field(default=None, description="rad")
    present: bool = True


class ArmIn(BaseModel):
    model_config = ConfigDict(extra="forbid")
    armed: bool = Field(description="true: arm (refused with 409 and the reason while vision "
                        "is missing, the e-stop is active or a log is replayed); false: disarm "
                        "(always)")


class DrivingIn(BaseModel):
    model_config = ConfigDict(extra="forbid")
    confirm: bool = Field(default=False, description="required (true) to take over driving")


class EstopIn(BaseModel):
    model_config = ConfigDict(extra="forbid")
    active: bool
    confirm: bool = Field(default=False, description="required (true) to release the stop")
    reason: str = Field(default="", max_length=200, description="why it is released (logged)")


# ------------------------------------------------------------------------------ log player


PlayerEventKind = Literal["command", "stage", "goal", "card", "operator"]


@with_config(_STRICT)
class PlayerEvent(TypedDict):
    """A marker on the timeline."""

    t_s: Annotated[float, Field(description="s from the log's first record")]
    kind: PlayerEventKind
    label: str


@with_config(_STRICT)
class Player(TypedDict):
    """The log player (GET/POST /api/player; the websocket's "player" message)."""

    source: Literal["live", "log"]
    file: Annotated[str | None, Field(description="the open log's path")]
    duration_s: float
    position_s: float
    playing: bool
    speed: Annotated[float, Field(description="1 = real time; 0 = as fast as possible")]
    start_unix: Annotated[float, Field(description="wall time of the log's first record")]
    loading: Annotated[float | None, Field(
        description="0..1 while the log is being indexed, else null")]
    error: Annotated[str, Field(description='why the last action failed, or ""')]
    warning: Annotated[str | None, Field(description="e.g. a truncated tail")]
    events: list[PlayerEvent]
    epoch: int


@with_config(_STRICT)
class HistoryBall(TypedDict):
    x: float
    y: float
    vx: float
    vy: float


@with_config(_STRICT)
class HistoryRobot(TypedDict):
    team: Team
    id: int
    x: float
    y: float
    orientation: float
    vx: float
    vy: float
    omega: float


@with_config(_STRICT)
class HistoryWorld(TypedDict):
    """The world model's estimate at one time (the signals a plot of a World has)."""

    ball: HistoryBall | None
    robots: list[HistoryRobot]


@with_config(_STRICT)
class HistorySample(TypedDict):
    t_unix: Annotated[float, Field(description="the log's wall time of the sample")]
    world: HistoryWorld


@with_config(_STRICT)
class PlayerHistory(TypedDict):
    """GET /api/player/history: the plots' past after a seek (the world model re-run over
    the log before the playhead)."""

    epoch: Annotated[int, Field(description="the player's epoch it belongs to")]
    samples: list[HistorySample]


@with_config(_STRICT)
class LogFileInfo(TypedDict):
    name: str
    path: str
    size_bytes: int
    modified_unix: float


@with_config(_STRICT)
class LogList(TypedDict):
    """GET /api/logs: the logs a player can open."""

    folders: list[str]
    files: list[LogFileInfo]


class PlayerOpenIn(BaseModel):
    model_config = ConfigDict(extra="forbid")
    action: Literal["open"]
    path: str = Field(min_length=1, max_length=4096,
                      description="a .log or .log.gz file in var/logs/ or a configured folder")


class PlayerPlayIn(BaseModel):
    model_config = ConfigDict(extra="forbid")
    action: Literal["play"]
    speed: float = Field(default=1.0, allow_inf_nan=False,
                         description="0.1 .. 10, or 0 for as fast as possible")


class PlayerPauseIn(BaseModel):
    model_config = ConfigDict(extra="forbid")
    action: Literal["pause"]


class PlayerSeekIn(BaseModel):
    model_config = ConfigDict(extra="forbid")
    action: Literal["seek"]
    position_s: float = Field(ge=0, allow_inf_nan=False, description="s from the log's start")


class PlayerStepIn(BaseModel):
    model_config = ConfigDict(extra="forbid")
    action: Literal["step"]
    frames: int = Field(ge=-100, le=100, description="camera frames forward (+) or back (-)")


class PlayerJumpIn(BaseModel):
    model_config = ConfigDict(extra="forbid")
    action: Literal["jump"]
    kind: Literal["command", "stage", "goal", "card", "operator", "any"] = "command"
    direction: Literal["next", "prev"] = "next"


class PlayerLiveIn(BaseModel):
    model_config = ConfigDict(extra="forbid")
    action: Literal["live"]


PlayerIn = Annotated[
    PlayerOpenIn | PlayerPlayIn | PlayerPauseIn | PlayerSeekIn | PlayerStepIn | PlayerJumpIn
    | PlayerLiveIn, Field(discriminator="action")]


class RecordingIn(BaseModel):
    model_config = ConfigDict(extra="forbid")
    action: Literal["new-file", "start", "stop"]


_EVAL_NAME = r"^[A-Za-z0-9][A-Za-z0-9_.#-]{0,119}$"


class EvaluateStartIn(BaseModel):
    """Start a job: a suite (shipped, or of a --suite-dir folder) for one play (null: each
    scenario's own), or the class folder's students through a suite."""

    model_config = ConfigDict(extra="forbid")
    action: Literal["start"]
    kind: Literal["suite", "class"] = "suite"
    suite: str = Field(pattern=_EVAL_NAME)
    play: str | None = Field(default=None, pattern=r"^[A-Za-z_][A-Za-z0-9_-]{0,63}$")


class EvaluateCancelIn(BaseModel):
    model_config = ConfigDict(extra="forbid")
    action: Literal["cancel"]


EvaluateIn = Annotated[EvaluateStartIn | EvaluateCancelIn, Field(discriminator="action")]


class EvaluateReplayIn(BaseModel):
    """Open a run's SSL log in the player (names only: the station finds the file in its
    reports folder)."""

    model_config = ConfigDict(extra="forbid")
    report: str = Field(pattern=_EVAL_NAME)
    run: str = Field(pattern=_EVAL_NAME)


# ------------------------------------------------------------------------------ websocket


@with_config(_STRICT)
class ParamsState(TypedDict):
    """The parameters in force (GET /api/params) and their version."""

    version: int
    values: ParamValues


@with_config(_STRICT)
class SnapshotMessage(TypedDict):
    """The first message on every websocket."""

    type: Literal["snapshot"]
    world: World
    geometry: Geometry | None
    health: Health
    params: ParamsState
    player: Player


@with_config(_STRICT)
class PlayerMessage(TypedDict):
    """The player's state: on open, play, pause, speed, seek and the end of a log."""

    type: Literal["player"]
    player: Player


@with_config(_STRICT)
class WorldMessage(TypedDict):
    type: Literal["world"]
    world: World


@with_config(_STRICT)
class GeometryMessage(TypedDict):
    type: Literal["geometry"]
    geometry: Geometry


@with_config(_STRICT)
class HealthMessage(TypedDict):
    type: Literal["health"]
    health: Health


@with_config(_STRICT)
class ParamsMessage(TypedDict):
    """A parameter change (any client's), with the new version."""

    type: Literal["params"]
    version: int
    values: ParamValues


ServerMessage = (SnapshotMessage | WorldMessage | GeometryMessage | HealthMessage | ParamsMessage
                 | PlayerMessage)

#: the rules' numbers the page draws with before a geometry packet names its own (exported
#: to TypeScript as constants: the page keeps no copy)
#: the health's latency stage of each robot's newest frame's age when its command is sent (the
#: latency the robot sees; the Health tab and bench/loop_bench.py look it up by this name)
FRAME_AGE_STAGE = "each robot's newest frame -> its command sent to relay"

CONSTANTS: dict[str, float | str] = {"ROBOT_RADIUS_MM": ROBOT_RADIUS_MM,
                                     "BALL_RADIUS_MM": BALL_RADIUS_MM,
                                     "FRAME_AGE_STAGE": FRAME_AGE_STAGE}

#: what scripts/gen_contract.py exports to TypeScript, in this order
EXPORTS: dict[str, object] = {
    "Team": Team, "Side": Side, "ControlAlgorithm": ControlAlgorithm,
    "RefereeCommand": RefereeCommand,
    "TargetSource": TargetSource, "Vec": Vec, "World": World, "Geometry": Geometry,
    "Health": Health, "ServerMessage": ServerMessage, "ParamsState": ParamsState,
    "StrategyView": StrategyView, "RefereeView": RefereeView, "EstopAnswer": EstopAnswer,
    "ArmingInfo": ArmingInfo, "TargetAnswer": TargetAnswer, "ParamsDiff": ParamsDiff,
    "PresetList": PresetList, "OperatorInfo": OperatorInfo, "DrivingInfo": DrivingInfo,
    "OperatorAction": OperatorAction,
    "PresetDetail": PresetDetail, "Player": Player, "PlayerEvent": PlayerEvent,
    "ReplayClock": ReplayClock, "Recording": Recording, "LogList": LogList,
    "StationFolders": StationFolders,
    "PlayerHistory": PlayerHistory, "TeamCode": TeamCode, "TeamFile": TeamFile,
    "TeamError": TeamError, "TeamFileText": TeamFileText, "TeamFileSaved": TeamFileSaved,
    "StoppedRobot": StoppedRobot,
    "EvaluationJob": EvaluationJob, "EvaluationView": EvaluationView,
    "EvaluationReport": EvaluationReport,
    # request bodies (their optional fields are optional in TypeScript too)
    "TargetIn": TargetIn, "RefereeCommandIn": RefereeCommandIn, "CardIn": CardIn,
    "EnableIn": EnableIn, "ArmIn": ArmIn, "TeleportBallIn": TeleportBallIn,
    "TeleportRobotIn": TeleportRobotIn,
    "EstopIn": EstopIn, "DrivingIn": DrivingIn, "PlayerOpenIn": PlayerOpenIn,
    "PlayerPlayIn": PlayerPlayIn,
    "PlayerPauseIn": PlayerPauseIn, "PlayerSeekIn": PlayerSeekIn, "PlayerStepIn": PlayerStepIn,
    "PlayerJumpIn": PlayerJumpIn, "PlayerLiveIn": PlayerLiveIn, "RecordingIn": RecordingIn,
    "TeamFileIn": TeamFileIn,
    "EvaluateStartIn": EvaluateStartIn, "EvaluateCancelIn": EvaluateCancelIn,
    "EvaluateReplayIn": EvaluateReplayIn,
}
