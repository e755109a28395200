// Pure: the team folder's files (GET /api/team, health.team_code) as the Code tab shows them:
// grouped by kind, each file's state, error, timing, robots and outputs as short texts, the
// robots stopped because their play failed, and the names and templates of new files.

import type { TeamError, TeamFile } from "../api/types";
import { fmtFixed } from "../format";

export type FileKind = TeamFile["kind"];

export interface FileGroup {
  kind: FileKind;
  label: string;
  files: TeamFile[];
}

const GROUPS: readonly { kind: FileKind; label: string }[] = [
  { kind: "play", label: "Plays" },
  { kind: "processor", label: "Processors" },
  { kind: "library", label: "Libraries" },
];

/** Plays, processors, libraries (always in that order, empty groups left out); files by name,
 * top-level before `lib/`. */
export function groupFiles(files: readonly TeamFile[]): FileGroup[] {
  const out: FileGroup[] = [];
  for (const g of GROUPS) {
    const fs = files
      .filter((f) => f.kind === g.kind)
      .sort((a, b) => {
        const la = a.name.includes("/") ? 1 : 0;
        const lb = b.name.includes("/") ? 1 : 0;
        return la - lb || a.name.localeCompare(b.name);
      });
    if (fs.length > 0) out.push({ kind: g.kind, label: g.label, files: fs });
  }
  return out;
}

/** The freshest list of files: the pushed health's (4 Hz) once there is one, else GET /api/team's. */
export function currentFiles(
  fromHealth: readonly TeamFile[] | null | undefined,
  fromApi: readonly TeamFile[] | null | undefined,
): readonly TeamFile[] {
  if (Array.isArray(fromHealth)) return fromHealth;
  return Array.isArray(fromApi) ? fromApi : [];
}

/** "exception at pass_drill.py:12: ZeroDivisionError: division by zero" (first line of the message). */
export function errorSummary(e: TeamError): string {
  const where = e.line !== null && e.line !== undefined ? `${e.file}:${e.line}` : e.file;
  const first = e.message.trim().split("\n")[0] ?? "";
  return `${e.kind} at ${where}${first ? `: ${first}` : ""}`;
}

export interface StateText {
  /** "running", "error", "idle", "starting" */
  label: string;
  /** CSS modifier: ok / bad / idle / busy */
  tone: "ok" | "bad" | "idle" | "busy";
  /** Longer text for the tooltip / the row: the error summary, or what idle means here. */
  detail: string;
}

export function stateText(f: TeamFile): StateText {
  switch (f.state) {
    case "running":
      return { label: "running", tone: "ok", detail: f.kind === "play" ? `drives ${robotsText(f.robots)}` : "running" };
    case "error":
      return { label: "error", tone: "bad", detail: f.error ? errorSummary(f.error) : "error" };
    case "starting":
      return { label: "starting", tone: "busy", detail: "its worker process is starting" };
    default:
      return {
        label: "idle",
        tone: "idle",
        detail: f.kind === "library" ? "a library: runs inside the plays and processors that import it" : "not in use: choose it as a play",
      };
  }
}

/** "1, 2, 5" or "no robots". */
export function robotsText(ids: readonly number[]): string {
  if (ids.length === 0) return "no robots";
  return [...ids].sort((a, b) => a - b).join(", ");
}

function ms(v: number | null | undefined): string {
  if (v === null || v === undefined || !Number.isFinite(v)) return "—";
  return `${fmtFixed(v, v < 10 ? 2 : 1)} ms`;
}

/** "p50 0.21 ms · p99 0.90 ms", or "—" before the first tick. */
export function tickText(f: Pick<TeamFile, "tick_ms_p50" | "tick_ms_p99">): string {
  if (f.tick_ms_p50 === null && f.tick_ms_p99 === null) return "—";
  return `p50 ${ms(f.tick_ms_p50)} · p99 ${ms(f.tick_ms_p99)}`;
}

function two(n: number): string {
  return String(n).padStart(2, "0");
}

/** "14:03:07 (12 s ago)" in the browser's time zone; "not loaded" while it never was. */
export function reloadedText(at: number | null | undefined, nowUnix: number): string {
  if (at === null || at === undefined || !Number.isFinite(at)) return "not loaded";
  const d = new Date(at * 1000);
  const clock = `${two(d.getHours())}:${two(d.getMinutes())}:${two(d.getSeconds())}`;
  const ago = Math.max(0, nowUnix - at);
  const rel = ago < 60 ? `${Math.floor(ago)} s ago` : ago < 3600 ? `${Math.floor(ago / 60)} min ago` : `${Math.floor(ago / 3600)} h ago`;
  return `${clock} (${rel})`;
}

/** A processor's outputs as [key, value] rows, keys sorted, numbers with up to 3 decimals. */
export function outputRows(outputs: Readonly<Record<string, number>> | null | undefined): [string, string][] {
  if (!outputs) return [];
  return Object.keys(outputs)
    .sort()
    .map((k) => {
      const v = outputs[k];
      if (typeof v !== "number" || !Number.isFinite(v)) return [k, "—"];
      return [k, Number.isInteger(v) ? String(v) : Math.abs(v) >= 100 ? fmtFixed(v, 0) : fmtFixed(v, 3)];
    });
}

/** The signal name of a processor output in the Plots tab (world.team.<name>.<key>). */
export function outputSignal(file: Pick<TeamFile, "name">, key: string): string {
  return `team.${stem(file.name)}.${key}`;
}

/** "pass_drill" of "pass_drill.py" / "lib/util.m". */
export function stem(name: string): string {
  const base = name.slice(name.lastIndexOf("/") + 1);
  const dot = base.lastIndexOf(".");
  return dot > 0 ? base.slice(0, dot) : base;
}

// ---- new files ----

/** The names a team file may have (the station's PUT accepts only these). */
export const FILE_NAME_RE = /^(lib\/)?[A-Za-z][A-Za-z0-9_]{0,62}\.(py|m)$/;

/**
 * The file name for a new play called `raw` ("My drill" -> "my_drill.py"), or the reason it
 * cannot be: the name rules, a file of that name, a play of that name (built-in or a team file).
 */
export function newPlayName(
  raw: string,
  language: "python" | "octave",
  existing: readonly string[],
  plays: readonly string[],
): { name: string; error: null } | { name: null; error: string } {
  const base = raw
    .trim()
    .replace(/\.(py|m)$/i, "")
    .replace(/[\s-]+/g, "_")
    .toLowerCase();
  if (!base) return { name: null, error: "give the play a name" };
  const name = `${base}.${language === "python" ? "py" : "m"}`;
  if (!FILE_NAME_RE.test(name) || name.includes("/"))
    return { name: null, error: `"${base}": a letter first, then letters, digits or _ (at most 63)` };
  if (existing.includes(name)) return { name: null, error: `${name} exists already` };
  if (plays.includes(base)) return { name: null, error: `a play is called ${base} already` };
  return { name, error: null };
}

/** A small, complete play to start from (Python or Octave), named after its file. */
export function playTemplate(name: string, language: "python" | "octave"): string {
  const s = stem(name);
  const title = s.replace(/_+/g, " ").replace(/^./, (c) => c.toUpperCase());
  if (language === "octave") {
    return `function orders = ${s}(ours, theirs, ball, game)
  % ${title}
  % My robots stand in a row on our half, facing the other goal.
  % ours: one row a robot (id x y orientation vx vy omega visible mine ball_contact), mm / rad.
  % orders: one row a robot (id mode x y orientation max_speed_mps kick_mps chip dribble).
  % Try changing X or the spacing, then save (Ctrl+S): the station reloads the file.
  X = -2000;
  mine = ours(ours(:, 9) == 1, :);
  orders = zeros(0, 9);
  for k = 1:size(mine, 1)
    orders(end + 1, :) = [mine(k, 1) 0 X (-1500 + 600 * (k - 1)) 0 NaN 0 0 0];
  end
end
`;
  }
  return `"""${title}: my robots stand in a row on our half, facing the other goal.

Try changing X or the spacing, then save (Ctrl+S): the station reloads the file.
"""

from __future__ import annotations

from touchline import Game, Target

TITLE = "${title}"
DESCRIPTION = "My robots stand in a row on our half"

X = -2000.0  #: mm, our frame (our goal at negative x)


def play(game: Game) -> dict[int, Target]:
    orders: dict[int, Target] = {}
    for k, rid in enumerate(sorted(game.mine)):
        orders[rid] = Target(X, -1500.0 + 600.0 * k, 0.0, role="row")
    return orders
`;
}

/**
 * The error to mark in the editor showing file `name`: its own error, else the error of a
 * play or processor that failed inside this file (a library it imports), with the line.
 * Null when nothing failed in it.
 */
export function errorIn(name: string, files: readonly TeamFile[]): { error: TeamError; line: number | null; of: string } | null {
  const own = files.find((f) => f.name === name && f.state === "error" && f.error);
  if (own?.error) return { error: own.error, line: own.error.file === name ? own.error.line : null, of: own.name };
  for (const f of files) {
    if (f.state === "error" && f.error && f.error.file === name) return { error: f.error, line: f.error.line, of: f.name };
  }
  return null;
}
