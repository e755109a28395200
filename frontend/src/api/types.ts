// The browser contract: generated from backend/contract.py (contract.gen.ts, do not edit it;
// regenerate with `make contract`), plus a few helpers of the page's own.

export type {
  ArmIn,
  DrivingIn,
  DrivingInfo,
  OperatorAction,
  OperatorInfo,
  ArmingInfo,
  Ball,
  CardIn,
  EnableIn,
  EstopIn,
  Point,
  RefereeCommand,
  RefereeCommandIn,
  TargetIn,
  TeleportBallIn,
  TeleportRobotIn,
  ControlAlgorithm,
  EngineHealth,
  EstopAnswer,
  EstopInfo,
  EvaluateCancelIn,
  EvaluateReplayIn,
  EvaluateStartIn,
  EvaluationCell,
  EvaluationCheck,
  EvaluationGrade,
  EvaluationJob,
  EvaluationReport,
  EvaluationReportInfo,
  EvaluationRun,
  EvaluationScenario,
  EvaluationSuite,
  EvaluationView,
  FieldArc,
  FieldLine,
  Geometry,
  Health,
  InternalReferee,
  LatencyHealth,
  LatencyStage,
  LogFileInfo,
  LogList,
  StationFolder,
  StationFolders,
  ParamChange,
  ParamsDiff,
  ParamsState,
  PlayInfo,
  Player,
  PlayerEvent,
  PlayerHistory,
  PlayerJumpIn,
  PlayerLiveIn,
  PlayerOpenIn,
  PlayerPauseIn,
  PlayerPlayIn,
  PlayerSeekIn,
  PlayerStepIn,
  PresetDetail,
  PresetList,
  ProcessorHealth,
  RawCamera,
  RawRobot,
  RecordedCommand,
  RecordedWorld,
  Recording,
  RecordingIn,
  Referee,
  RefereeGameEvent,
  RefereeHealth,
  RefereeTeam,
  RefereeView,
  RelayHealth,
  ReplayClock,
  Robot,
  RobotCommand,
  RobotControl,
  RobotFeedback,
  RobotKick,
  RobotTarget,
  ServerMessage,
  Side,
  StrategyState,
  StrategyView,
  StoppedRobot,
  StreamHealth,
  TargetAnswer,
  TeamCode,
  TeamError,
  TeamFile,
  TeamFileIn,
  TeamFileSaved,
  TeamFileText,
  TargetSource,
  Team,
  TopicHealth,
  Vec,
  World,
  WorldHealth,
} from "./contract.gen";

import type {
  PlayerJumpIn,
  PlayerLiveIn,
  PlayerOpenIn,
  PlayerPauseIn,
  PlayerPlayIn,
  PlayerSeekIn,
  PlayerStepIn,
  StrategyView,
  Team,
} from "./contract.gen";

/** A body of POST /api/player (one per action). */
export type PlayerIn =
  | PlayerOpenIn
  | PlayerPlayIn
  | PlayerPauseIn
  | PlayerSeekIn
  | PlayerStepIn
  | PlayerJumpIn
  | PlayerLiveIn;

export const TEAMS: readonly Team[] = ["blue", "yellow"];

/** GET /api/strategy. */
export type StrategyInfo = StrategyView;

/** Parameter values: nested groups of leaves (numbers, strings, booleans). */
export type ParamValues = { [key: string]: unknown };

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
