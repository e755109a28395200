// Test fixtures (only imported by tests).
import type {
  EvaluationJob,
  ArmingInfo,
  EngineHealth,
  Geometry,
  Health,
  InternalReferee,
  Player,
  PlayInfo,
  TeamFile,
  Recording,
  Referee,
  RefereeCommand,
  RefereeTeam,
  StrategyView,
  StreamHealth,
  ReplayClock,
  World,
} from "../api/types";
import { DEFAULT_GEOMETRY } from "../field/defaultGeometry";
import { robot } from "../field/testRobots";

export function world(seq: number, extra: Partial<World> = {}): World {
  return {
    seq,
    t_capture: 1_700_000_000 + seq / 60,
    ball: {
      x: 10, y: 20, vx: 0, vy: 0, visible: true, age_s: 0, cameras: [0],
      raw_x: 10, raw_y: 20, predicted: false, lost: false, filter: "kalman", kick: null,
      z: 0, vz: 0, flying: false,
    },
    other_balls: [],
    robots: [robot("blue", 0, -1000, 0), robot("yellow", 0, 1000, 0)],
    cameras: [],
    referee: null,
    estop: false,
    estop_info: { active: false, since: 0, by: "", relay_latched: false },
    armed: true,
    arming_required: false,
    arming: arming(),
    halt_reason: "",
    strategy: null,
    internal_referee: internalReferee(),
    team: {},
    replay: null,
    recorded: null,
    ...extra,
  };
}

/** Arming: not required (the built-in simulator), so armed. */
export const arming = (extra: Partial<ArmingInfo> = {}): ArmingInfo => ({
  required: false,
  armed: true,
  since: 0,
  by: "",
  relay_armed: null,
  relay_unconfirmed: null,
  refusal: null,
  ...extra,
});

/** The internal referee, off (as a station starts). */
export const internalReferee = (extra: Partial<InternalReferee> = {}): InternalReferee => ({
  enabled: false,
  disabled_reason: "",
  foreign_source: null,
  command: "HALT",
  stage: "NORMAL_FIRST_HALF_PRE",
  command_counter: 0,
  designated_position: null,
  score: { blue: 0, yellow: 0 },
  max_allowed_bots: { blue: 6, yellow: 6 },
  commands: ["HALT", "STOP", "FORCE_START"],
  ...extra,
});

export function health(rate = 60): Health {
  return {
    ok: true,
    warnings: [],
    estop: { active: false, since: 0, by: "", relay_latched: false },
    arming: arming(),
    world: null,
    referee: null,
    uptime_s: 10,
    streams: { vision: stream({ rate_hz: rate }) },
    processors: [],
    topics: [],
    relay: null,
    latency: null,
    latency_stages: [],
    websocket_clients: 1,
    websocket_dropped: 0,
    supervisor: null,
    engine: null,
    recording: recording(),
    processes: [
      { name: "backend", cpu_percent: 23.5, rss_mb: 120 },
      { name: "relay", cpu_percent: 11.2, rss_mb: 40 },
    ],
    access: { token_required: false, view_token: false, estop_for_all: false, refused: {}, blocked_clients: 0 },
    operators: [],
    driving: [],
    operator_actions: [],
    startup: { restarted: false, standby: false, steps_s: { imports: 0.6, "first command": 0.7 } },
    team_code: [],
    evaluation: evaluationJob(),
  };
}

export const evaluationJob = (extra: Partial<EvaluationJob> = {}): EvaluationJob => ({
  id: 0,
  state: "idle",
  kind: null,
  suite: "",
  play: null,
  done: 0,
  total: 0,
  passed: 0,
  failed: 0,
  started_unix: null,
  finished_unix: null,
  report: null,
  by: "",
  error: "",
  last: "",
  ...extra,
});

export const stream = (extra: Partial<StreamHealth> = {}): StreamHealth => ({
  packets: 100,
  errors: 0,
  errors_by_reason: {},
  rate_hz: 60,
  last_age_s: 0.01,
  last_error: "",
  ...extra,
});

export const geometry: Geometry = { ...DEFAULT_GEOMETRY, field_length: 12000, field_width: 9000 };

export const engineHealth = (extra: Partial<EngineHealth> = {}): EngineHealth => ({
  kind: "octave",
  function: "goalkeeper",
  running: true,
  calls_per_s: 19.96,
  latency_mean_ms: 3.214,
  latency_p99_ms: 11.5,
  calls: 1200,
  ok: 1190,
  errors: 0,
  timeouts: 0,
  crashes: 0,
  restarts: 0,
  start_failures: 0,
  last_error: "",
  workers: 2,
  busy: 1,
  idle: 1,
  fallbacks: 0,
  ...extra,
});

export const refereeTeam = (name: string, extra: Partial<RefereeTeam> = {}): RefereeTeam => ({
  name,
  score: 0,
  yellow_cards: 0,
  red_cards: 0,
  goalkeeper: 0,
  yellow_card_times_s: [],
  timeouts: 4,
  timeout_time_s: 300,
  foul_counter: null,
  ball_placement_failures: null,
  can_place_ball: null,
  max_allowed_bots: null,
  bot_substitution_intent: null,
  bot_substitution_allowed: null,
  ...extra,
});

/** A referee state with only the basic fields (as the internal referee sends). */
export const referee = (command: RefereeCommand, extra: Partial<Referee> = {}): Referee => ({
  source: "game-controller",
  source_identifier: "gc-1",
  command,
  stage: "NORMAL_FIRST_HALF",
  command_counter: 3,
  stage_time_left_s: 240,
  blue: refereeTeam("Blue"),
  yellow: refereeTeam("Yellow"),
  designated_position: null,
  blue_team_on_positive_half: false,
  next_command: null,
  status_message: "",
  match_type: null,
  current_action_time_remaining_s: null,
  game_events: [],
  age_s: 0.02,
  ...extra,
});

/** GET /api/strategy with three plays (`plays` replaces them; built-in unless they say). */
export const strategyView = (
  plays: Array<Pick<PlayInfo, "name" | "title" | "description"> & Partial<PlayInfo>>,
  extra: Partial<StrategyView> = {},
): StrategyView => ({
  play: "match",
  plays: plays.map((p) => ({ source: "builtin", file: null, language: null, ...p })),
  situation: "running",
  situation_text: "Game running",
  our_team: "blue",
  our_side: "negative-x",
  side_from_referee: false,
  tick_ms: 0.5,
  robot_plays: {},
  stopped: [],
  roles: {},
  ...extra,
});

/** The recorder, idle. */
export const recording = (extra: Partial<Recording> = {}): Recording => ({
  enabled: true,
  recording: false,
  file: "",
  folder: "var/logs",
  size_bytes: 0,
  duration_s: 0,
  records: 0,
  dropped: 0,
  error: "",
  ...extra,
});

/** The player, live (as a station starts). */
export const player = (extra: Partial<Player> = {}): Player => ({
  source: "live",
  file: null,
  duration_s: 0,
  position_s: 0,
  playing: false,
  speed: 1,
  start_unix: 0,
  loading: null,
  error: "",
  warning: null,
  events: [],
  epoch: 0,
  ...extra,
});

/** A log open in the player: 120 s, a few events. */
export const logPlayer = (extra: Partial<Player> = {}): Player =>
  player({
    source: "log",
    file: "var/logs/match.log.gz",
    duration_s: 120,
    position_s: 30,
    playing: false,
    start_unix: 1_700_000_000,
    events: [
      { t_s: 10, kind: "command", label: "FORCE_START" },
      { t_s: 40, kind: "goal", label: "goal blue" },
      { t_s: 60, kind: "stage", label: "NORMAL_HALF_TIME" },
      { t_s: 90, kind: "card", label: "yellow card yellow" },
    ],
    epoch: 1,
    ...extra,
  });

export const replayClock = (extra: Partial<ReplayClock> = {}): ReplayClock => ({
  file: "match.log.gz",
  position_s: 30,
  t_unix: 1_700_000_030,
  duration_s: 120,
  playing: false,
  speed: 1,
  epoch: 1,
  ...extra,
});

/** A team file as GET /api/team and health.team_code list it (a library unless `extra` says). */
export function teamFile(name: string, extra: Partial<TeamFile> = {}): TeamFile {
  const py = name.endsWith(".py");
  return {
    name,
    kind: "library",
    language: py ? "python" : "octave",
    play: null,
    title: "",
    description: "",
    state: "idle",
    error: null,
    version: "0123456789ab",
    mtime_unix: 1_700_000_000,
    size_bytes: 100,
    reloaded_at_unix: null,
    reloads: 0,
    ticks: 0,
    errors: 0,
    overruns: 0,
    late: 0,
    moved_out: 0,
    tick_ms_p50: null,
    tick_ms_p99: null,
    robots: [],
    outputs: {},
    ...extra,
  };
}
