// Types of the backend contract (docs/api.md). Lengths mm, angles rad, speeds mm/s, times s.

export type Team = "blue" | "yellow";
export const TEAMS: readonly Team[] = ["blue", "yellow"];

export interface Vec {
  x: number;
  y: number;
}

export interface Ball {
  x: number;
  y: number;
  vx: number;
  vy: number;
  visible: boolean;
  age_s: number;
  cameras: number[];
  /** Latest merged measurement (mm), null without one. */
  raw_x?: number | null;
  raw_y?: number | null;
  /** Position extrapolated (no fresh detection) / dropped from the world soon. */
  predicted?: boolean;
  lost?: boolean;
  /** Filter of the ball ("raw" | "median" | "paper" | "kalman"). */
  filter?: string;
}

export type ControlAlgorithm = "algorithm1" | "algorithm2" | "proportional";

/** Telemetry of a robot's controller (when the station commands it). */
export interface RobotControl {
  algorithm: ControlAlgorithm | string;
  phase: string;
  t_s: number;
  ref_x_m: number;
  has_reference: number;
  x_m: number;
  path_length_m: number;
  lateral_m: number;
  cmd_speed_mps: number;
  meas_speed_mps: number;
  c_estimate: number;
  heading_error_rad: number;
  restarts: number;
}

export interface RobotTarget {
  x: number;
  y: number;
  orientation: number | null;
  source: "operator" | "demo";
}

export interface RobotCommand {
  forward_mps: number;
  left_mps: number;
  angular_radps: number;
}

export interface Robot {
  team: Team;
  id: number;
  x: number;
  y: number;
  orientation: number;
  vx: number;
  vy: number;
  omega: number;
  visible: boolean;
  age_s: number;
  cameras: number[];
  target: RobotTarget | null;
  controlled: boolean;
  command: RobotCommand | null;
  raw_x?: number | null;
  raw_y?: number | null;
  raw_orientation?: number | null;
  predicted?: boolean;
  lost?: boolean;
  /** Filter of this robot: "raw" | "median" | "paper" | "kalman". */
  filter?: string;
  control?: RobotControl | null;
  /** Strategy role of one of our robots ("goalkeeper", "attacker", ...; null when none). */
  role?: string | null;
  /** Planned waypoints (mm) from the robot's position to its target; the last one is the target. */
  path?: Vec[] | null;
  /** Kicker armed: the kick speed and whether it chips. */
  kick?: RobotKick | null;
  dribbler?: boolean;
}

export interface RobotKick {
  speed_mps: number;
  chip: boolean;
}

export interface RawCamera {
  camera_id: number;
  frame_number: number;
  t_capture: number;
  age_s: number;
  balls: Vec[];
  robots: { team: Team; id: number; x: number; y: number; orientation: number }[];
}

export interface RefereeTeam {
  name: string;
  score: number;
  yellow_cards: number;
  red_cards: number;
  goalkeeper: number;
  // Optional below: what the official game controller sends beyond the basics. Absent from an
  // older backend; null when this game controller does not send the field.
  /** Seconds left on each of the team's active yellow cards. */
  yellow_card_times_s?: number[];
  timeouts?: number;
  /** Timeout time left (s). */
  timeout_time_s?: number;
  foul_counter?: number | null;
  ball_placement_failures?: number | null;
  /** False: the team may not place the ball (too many failed placements). */
  can_place_ball?: boolean | null;
  /** Robots the team may have on the field now (cards lower it). */
  max_allowed_bots?: number | null;
  bot_substitution_intent?: boolean | null;
  bot_substitution_allowed?: boolean | null;
}

/** A game event as the game controller reports it (newest first in Referee.game_events). */
export interface RefereeGameEvent {
  id: string;
  /** Proto enum name ("BOT_CRASH_UNIQUE", "BALL_LEFT_FIELD_TOUCH_LINE", ...). */
  type: string;
  /** "BLUE", "YELLOW" (or "UNKNOWN"); null when the event names no team. */
  by_team: string | null;
  /** Who reported it: autorefs' names, "UI", "Engine", ... */
  origin: string[];
  /** Unix s, null when not sent. */
  created_s: number | null;
}

export interface Referee {
  /** "game-controller" (a real one on the network), "internal" (the station's own), or "none". */
  source: string;
  command: string;
  stage: string;
  command_counter: number;
  stage_time_left_s: number | null;
  blue: RefereeTeam;
  yellow: RefereeTeam;
  /** The game controller's position for a ball placement. It may be sent during other commands
   * too (the official one sends its last one always): use `placementTarget` (referee.ts). */
  designated_position: Vec | null;
  blue_team_on_positive_half: boolean | null;
  age_s: number;
  source_identifier?: string;
  // Optional below: absent from an older backend.
  /** The command that follows the current one, null when none is announced. */
  next_command?: string | null;
  /** The game controller's message to the teams, "" when none. */
  status_message?: string;
  /** "FRIENDLY", "GROUP_PHASE", ...; null when not sent. */
  match_type?: string | null;
  /** Seconds left for the current action (placement, free kick, ...); negative once over. */
  current_action_time_remaining_s?: number | null;
  /** Recent game events, newest first. */
  game_events?: RefereeGameEvent[];
}

/** The latched emergency stop (GET /api/estop, world.estop_info, health.estop). */
export interface EstopInfo {
  active: boolean;
  /** Unix s of the last press or release (0: never) */
  since: number;
  /** who pressed (or released) it: "operator at <address>", "relay latch (...)" */
  by: string;
  /** the relay's latch from its statistics; null before any arrived */
  relay_latched: boolean | null;
}

export interface World {
  seq: number;
  t_capture: number;
  ball: Ball | null;
  robots: Robot[];
  cameras: RawCamera[];
  referee: Referee | null;
  estop: boolean;
  /** the latched emergency stop: when and by whom; relay_latched from the relay's stats */
  estop_info?: EstopInfo;
  /** Not in docs/api.md yet: why the station holds every robot ("emergency stop", "HALT", "no vision"), or "". */
  halt_reason?: string;
  /** The strategy's view of the game (absent before the strategy runs). */
  strategy?: StrategyState | null;
}

export type Side = "negative-x" | "positive-x";

export interface StrategyState {
  play: string;
  situation: string;
  situation_text: string;
  our_team: Team;
  our_side: Side;
  /** True when our side comes from the referee (blue_team_on_positive_half), not the parameter. */
  side_from_referee: boolean;
  tick_ms: number;
}

/** One play the strategy offers (GET /api/strategy). */
export interface PlayInfo {
  name: string;
  title: string;
  description: string;
}

/** GET /api/strategy. */
export interface StrategyInfo {
  play: string;
  plays: PlayInfo[];
  situation: string;
  situation_text: string;
}

export interface FieldLine {
  name: string;
  p1: Vec;
  p2: Vec;
  thickness: number;
}

export interface FieldArc {
  name: string;
  center: Vec;
  radius: number;
  a1: number;
  a2: number;
  thickness: number;
}

export interface Geometry {
  field_length: number;
  field_width: number;
  goal_width: number;
  goal_depth: number;
  boundary_width: number;
  penalty_area_depth: number;
  penalty_area_width: number;
  center_circle_radius: number;
  ball_radius: number;
  max_robot_radius: number;
  lines: FieldLine[];
  arcs: FieldArc[];
}

export interface StreamHealth {
  packets: number;
  errors: number;
  /** refused datagrams (and, for vision, what the world model dropped) by reason:
   * "truncated", "not protobuf", "missing required field", "time out of range", ... */
  errors_by_reason?: Record<string, number>;
  rate_hz: number;
  last_age_s: number;
  last_error: string;
}

export interface ProcessorHealth {
  name: string;
  trigger: string;
  configured_hz: number | null;
  measured_hz: number;
  tick_mean_ms: number;
  tick_p99_ms: number;
  overruns: number;
  runs: number;
  errors: number;
  last_error: string;
}

export interface TopicHealth {
  name: string;
  size: number;
  capacity: number;
  seq: number;
  age_s: number;
}

export interface RelayHealth {
  alive: boolean;
  age_s: number;
  output_mode: string;
  output_rate_hz: number;
  active_robots: number;
  stale_robots: number;
  command_latency_ms: number;
  /** the relay's own e-stop latch: only zeros leave it while true */
  estop_latched?: boolean;
  estop_by?: string;
}

export interface LatencyHealth {
  mean_ms: number;
  p50_ms: number;
  p99_ms: number;
}

/** The compute engine the strategy calls (null/absent when off). */
export interface EngineHealth {
  kind: "numpy" | "octave" | string;
  function: string;
  calls_per_s: number;
  latency_mean_ms: number;
  latency_p99_ms: number;
  calls: number;
  ok: number;
  errors: number;
  timeouts: number;
  crashes: number;
  restarts: number;
  start_failures: number;
  last_error: string;
  workers: number;
  busy: number;
  idle: number;
  /** Strategy ticks that used the built-in numpy code because the engine call failed or timed out. */
  fallbacks: number;
}

/** The newest referee message as health sees it (docs/api.md, "A silent referee"). */
export interface RefereeHealth {
  /** Seconds since it arrived. */
  last_heard_s: number;
  source_identifier: string;
  source: "game-controller" | "internal" | string;
  /** Its command: what the station still obeys. */
  command: string;
  /** False: the internal referee, switched off by the operator (its silence is no warning). */
  obeyed: boolean;
  /** Obeyed and quiet for longer than `silent_after_s`: the station keeps obeying `command`. */
  silent: boolean;
  silent_after_s: number;
}

export interface Health {
  latency?: LatencyHealth | null;
  engine?: EngineHealth | null;
  /** The station's own loop works (fresh vision, relay alive); a silent referee leaves it true. */
  ok: boolean;
  /** One line per problem (absent from an older backend). */
  warnings?: string[];
  /** Null before any referee message was heard (absent from an older backend). */
  referee?: RefereeHealth | null;
  streams: Record<string, StreamHealth>;
  processors: ProcessorHealth[];
  topics: TopicHealth[];
  relay: RelayHealth | null;
  websocket_clients: number;
  /** The latched emergency stop (absent from an older backend). */
  estop?: EstopInfo;
}

/** Parameter values: nested groups of leaves (numbers, strings, booleans). */
export type ParamValues = { [key: string]: unknown };

export interface ParamsState {
  version: number;
  values: ParamValues;
}

export type ServerMessage =
  | { type: "snapshot"; world: World; geometry: Geometry | null; health: Health }
  | { type: "world"; world: World }
  | { type: "geometry"; geometry: Geometry }
  | { type: "health"; health: Health }
  | { type: "params"; version: number; values: ParamValues };

export interface RobotKey {
  team: Team;
  id: number;
}

export function robotKeyString(k: RobotKey): string {
  return `${k.team}-${k.id}`;
}

export function sameRobot(a: RobotKey | null, b: RobotKey | null): boolean {
  return a !== null && b !== null && a.team === b.team && a.id === b.id;
}
