// HTTP calls to the backend (docs/api.md, "HTTP"). Errors carry the server's message.

import type {
  ArmIn,
  ArmingInfo,
  CardIn,
  DrivingIn,
  DrivingInfo,
  EnableIn,
  EstopAnswer,
  EstopIn,
  EvaluateReplayIn,
  EvaluateStartIn,
  EvaluationJob,
  EvaluationReport,
  EvaluationView,
  RefereeCommand,
  RefereeCommandIn,
  LogList,
  OperatorAction,
  OperatorInfo,
  Player,
  PlayerHistory,
  PlayerIn,
  Recording,
  RecordingIn,
  TargetIn,
  TeleportBallIn,
  TeleportRobotIn,
  ParamChange,
  ParamsState,
  PresetDetail,
  PresetList,
  RefereeView,
  StationFolders,
  StrategyInfo,
  TargetAnswer,
  Team,
  TeamCode,
  TeamFileIn,
  TeamFileSaved,
  TeamFileText,
} from "./types";
import { pushToast } from "../store/toasts";

export class ApiError extends Error {
  readonly status: number;
  /** The parsed error body (e.g. FastAPI's `{"detail": ...}`), when there was one. */
  readonly body: unknown;
  constructor(status: number, message: string, body: unknown = null) {
    super(message);
    this.name = "ApiError";
    this.status = status;
    this.body = body;
  }
}

/**
 * Human-readable message from a FastAPI error body: `{"detail": "text"}` or
 * `{"detail": [{"loc": [...], "msg": "..."}]}`.
 */
export function errorMessageFromBody(status: number, body: unknown, fallback = ""): string {
  if (typeof body === "object" && body !== null && "detail" in body) {
    const detail = (body as { detail: unknown }).detail;
    if (typeof detail === "string" && detail) return detail;
    if (Array.isArray(detail)) {
      const parts = detail
        .map((d) => {
          if (typeof d !== "object" || d === null) return typeof d === "string" ? d : "";
          const msg = typeof (d as { msg?: unknown }).msg === "string" ? (d as { msg: string }).msg : "";
          const loc = (d as { loc?: unknown }).loc;
          const where = Array.isArray(loc)
            ? loc.filter((p) => p !== "body").map(String).join(".")
            : "";
          return where && msg ? `${where}: ${msg}` : msg;
        })
        .filter(Boolean);
      if (parts.length > 0) return parts.join("; ");
    }
  }
  if (typeof body === "string" && body.trim()) return body.trim().slice(0, 300);
  return fallback || `HTTP ${status}`;
}

/** How to log in, for the 401 message (docs/security.md). */
export const LOGIN_HELP =
  "open the login URL printed when the station started (http://HOST:PORT/login?token=…) once in this browser, or ask the station's operator for it";

/** The message a 401 shows: what the station wants, and how to log in. */
export function unauthorizedMessage(serverText: string): string {
  const view = /to view/i.test(serverText);
  return (
    `Not logged in: this station needs the ${view ? "viewer or operator" : "operator"} token ` +
    `${view ? "to show anything" : "to change anything"}. To log in, ${LOGIN_HELP}.`
  );
}

let lastUnauthorized = -Infinity;

/** A 401: the station wants a token this browser does not have. Says how to log in, at most
 * once every 10 s (every refused click would repeat it). True when shown. */
export function notifyUnauthorized(serverText: string, now: number = Date.now()): boolean {
  if (now - lastUnauthorized < 10_000) return false;
  lastUnauthorized = now;
  pushToast("error", unauthorizedMessage(serverText), 15_000);
  return true;
}

/** For tests: the next 401 is shown again. */
export function resetUnauthorizedNotice(): void {
  lastUnauthorized = -Infinity;
}

export async function request<T>(
  method: string,
  path: string,
  body?: unknown,
  rawBody?: string,
  extraHeaders: Record<string, string> = {},
): Promise<T> {
  let res: Response;
  try {
    res = await fetch(path, {
      method,
      // X-Touchline: the station refuses state-changing requests without it (or JSON):
      // a page on another site cannot send it without a preflight the station never grants
      headers:
        body === undefined && rawBody === undefined
          ? { "X-Touchline": "1", ...extraHeaders }
          : { "Content-Type": "application/json", "X-Touchline": "1", ...extraHeaders },
      body: rawBody !== undefined ? rawBody : body === undefined ? undefined : JSON.stringify(body),
    });
  } catch (e) {
    throw new ApiError(0, `cannot reach the station: ${(e as Error).message}`);
  }
  const text = await res.text();
  let parsed: unknown = text;
  if (text) {
    try {
      parsed = JSON.parse(text);
    } catch {
      /* keep text */
    }
  }
  if (!res.ok) {
    if (res.status === 401) notifyUnauthorized(errorMessageFromBody(res.status, parsed));
    throw new ApiError(res.status, errorMessageFromBody(res.status, parsed, `${res.status} ${res.statusText}`), parsed);
  }
  return parsed as T;
}

/** POST /api/robots/{team}/{id}/target. */
export type TargetReply = TargetAnswer;

export function postTarget(
  team: Team,
  id: number,
  target: { x: number; y: number; orientation?: number },
): Promise<TargetReply> {
  const body: TargetIn = {
    x: Math.round(target.x),
    y: Math.round(target.y),
  };
  if (target.orientation !== undefined) body.orientation = target.orientation;
  return request<TargetReply>("POST", `/api/robots/${team}/${id}/target`, body);
}

export function deleteTarget(team: Team, id: number): Promise<unknown> {
  return request<TargetAnswer>("DELETE", `/api/robots/${team}/${id}/target`);
}

/** Press (one request) or release the emergency stop; the station refuses a release that is
 * not confirmed (409), so the page asks the operator first (`confirm`). */
export function postEstop(active: boolean, confirm = false): Promise<EstopAnswer> {
  const body: EstopIn = active ? { active } : { active, confirm };
  return request<EstopAnswer>("POST", "/api/estop", body);
}

/** Arm (refused with 409 and the reason: no vision, the e-stop, a replay) or disarm. */
export function postArm(armed: boolean): Promise<ArmingInfo> {
  const body: ArmIn = { armed };
  return request<ArmingInfo>("POST", "/api/arm", body);
}

// ---- parameters and presets ----

export type ParamsReply = ParamsState;
export type DiffEntry = ParamChange;

export const getParamsSchema = () => request<Record<string, unknown>>("GET", "/api/params/schema");
/** PATCH the parameters; `version`: the one the page showed when the change was made (a
 * value changed since by someone else is refused with 409 and the value now). */
export const patchParams = (patch: Record<string, unknown>, version?: number) =>
  request<ParamsReply>(
    "PATCH",
    "/api/params",
    patch,
    undefined,
    version === undefined ? {} : { "X-Touchline-Params-Version": String(version) },
  );
export const importParams = (text: string) => request<ParamsReply>("POST", "/api/params/import", undefined, text);
export const listPresets = () => request<PresetList>("GET", "/api/presets");
export const savePreset = (name: string) => request<PresetList>("PUT", `/api/presets/${encodeURIComponent(name)}`);
export const getPreset = (name: string) =>
  request<PresetDetail>(
    "GET",
    `/api/presets/${encodeURIComponent(name)}`,
  );
export const loadPreset = (name: string) => request<ParamsReply>("POST", `/api/presets/${encodeURIComponent(name)}/load`);
export const deletePreset = (name: string) => request<PresetList>("DELETE", `/api/presets/${encodeURIComponent(name)}`);

// ---- strategy ----

/** The plays the strategy offers and the current one. A play is chosen with PATCH /api/params. */
export const getStrategy = () => request<StrategyInfo>("GET", "/api/strategy");

// ---- the team's own code (team/, issue 27) ----

/** The team folder: its files and their states, and whether this browser may edit. */
export const getTeam = () => request<TeamCode>("GET", "/api/team");

/** A team file's path in the URL: its folder's slash stays a slash ("lib/util.py"). */
const teamFileUrl = (name: string) => `/api/team/files/${name.split("/").map(encodeURIComponent).join("/")}`;

/** The text and version of a team file. */
export const getTeamFile = (name: string) => request<TeamFileText>("GET", teamFileUrl(name));

/** Save a team file (created when `base_version` is null). 409: it changed on disk since
 * `base_version`; 403: this browser may not edit code (the reason in the message). */
export function putTeamFile(name: string, text: string, base_version: string | null): Promise<TeamFileSaved> {
  const body: TeamFileIn = { text, base_version };
  return request<TeamFileSaved>("PUT", teamFileUrl(name), body);
}

// ---- referee and simulator ----

/** A card from the internal referee: yellow (one robot fewer for 120 s), red (for the rest of
 * the game), or clear (withdraw the team's cards). */
export type Card = CardIn["card"];

export function postRefereeCommand(command: RefereeCommand, designated_position?: { x: number; y: number }): Promise<RefereeView> {
  const body: RefereeCommandIn = designated_position
    ? { command, designated_position: { x: Math.round(designated_position.x), y: Math.round(designated_position.y) } }
    : { command };
  return request<RefereeView>("POST", "/api/referee/internal/command", body);
}
export function postRefereeCard(team: Team, card: Card): Promise<RefereeView> {
  const body: CardIn = { team, card };
  return request<RefereeView>("POST", "/api/referee/internal/card", body);
}
export function postRefereeEnabled(enabled: boolean): Promise<RefereeView> {
  const body: EnableIn = { enabled };
  return request<RefereeView>("POST", "/api/referee/internal/enabled", body);
}

export function teleportBall(x: number, y: number): Promise<unknown> {
  const body: TeleportBallIn = { x: Math.round(x), y: Math.round(y) };
  return request<unknown>("POST", "/api/sim/ball", body);
}
export function teleportRobot(team: Team, id: number, x: number, y: number, orientation?: number): Promise<unknown> {
  const body: TeleportRobotIn = { x: Math.round(x), y: Math.round(y) };
  if (orientation !== undefined) body.orientation = orientation;
  return request<unknown>("POST", `/api/sim/robots/${team}/${id}`, body);
}

// ---- log player and recorder ----

/** The player's state (live or a log). */
export const getPlayer = () => request<Player>("GET", "/api/player");
/** One player action (open, play, pause, seek, step, jump, live); answers the new state. */
export const postPlayer = (body: PlayerIn) => request<Player>("POST", "/api/player", body);
/** The world model's estimate over `seconds` before the playhead (plots after a seek). */
export const getPlayerHistory = (seconds: number) =>
  request<PlayerHistory>("GET", `/api/player/history?seconds=${encodeURIComponent(String(seconds))}`);
/** The logs the player may open. */
export const getLogs = () => request<LogList>("GET", "/api/logs");
/** The station's folders, set when it started (read-only: docs/security.md). */
export const getFolders = () => request<StationFolders>("GET", "/api/folders");
/** Start a new recording file, start or stop recording. */
export function postRecording(action: RecordingIn["action"]): Promise<Recording> {
  const body: RecordingIn = { action };
  return request<Recording>("POST", "/api/recording", body);
}

// ---- several operators (docs/security.md) ----

export interface Me {
  key: string;
  name: string;
  role: string;
  address: string;
}
export interface OperatorsState {
  me: Me;
  operators: OperatorInfo[];
  driving: DrivingInfo[];
  actions: OperatorAction[];
}
export const getOperators = () => request<OperatorsState>("GET", "/api/operators");
/** Ask the holder for driving `team` (a free team is taken at once). */
export const requestDriving = (team: Team) => request<OperatorsState>("POST", `/api/driving/${team}/request`);
/** The holder gives driving to the one who asked. */
export const giveDriving = (team: Team) => request<OperatorsState>("POST", `/api/driving/${team}/give`);
/** Take over driving: the page asks the operator first (the station wants `confirm`). */
export function takeDriving(team: Team): Promise<OperatorsState> {
  const body: DrivingIn = { confirm: true };
  return request<OperatorsState>("POST", `/api/driving/${team}/take`, body);
}
export const releaseDriving = (team: Team) => request<OperatorsState>("POST", `/api/driving/${team}/release`);

// ---- the Evaluate tab (docs/evaluate.md): names only, the station finds the files ----

export const getEvaluation = () => request<EvaluationView>("GET", "/api/evaluate");

export const startEvaluation = (body: Omit<EvaluateStartIn, "action">) =>
  request<EvaluationJob>("POST", "/api/evaluate", { action: "start", ...body });

export const cancelEvaluation = () => request<EvaluationJob>("POST", "/api/evaluate", { action: "cancel" });

export const getEvaluationReport = (name: string) =>
  request<EvaluationReport>("GET", `/api/evaluate/reports/${encodeURIComponent(name)}`);

export const evaluationReportPage = (name: string) => `/api/evaluate/reports/${encodeURIComponent(name)}/html`;

export const replayEvaluationRun = (body: EvaluateReplayIn) => request<Player>("POST", "/api/evaluate/replay", body);
