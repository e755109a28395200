// Pure: the list of plays to offer and the current play, from whatever the station provides:
// GET /api/strategy (names, titles, descriptions), else the enum of the `strategy.play`
// parameter in the schema; the current play from the pushed parameters, else the world.

import type { ParamValues, PlayInfo, StrategyInfo, StrategyState } from "../api/types";

/** Path of the play parameter: PATCH {"strategy": {"play": name}}. */
export const PLAY_PATH = ["strategy", "play"] as const;

export function humanizePlay(name: string): string {
  const s = name.replace(/[_-]+/g, " ").trim();
  return s.charAt(0).toUpperCase() + s.slice(1);
}

function isObj(v: unknown): v is Record<string, unknown> {
  return typeof v === "object" && v !== null && !Array.isArray(v);
}

/** A play known only by name (the schema's choices, the parameter in force): taken as built-in. */
const BUILTIN = { source: "builtin", file: null, language: null } as const;

/** The plays to list, in the station's order; the current play is always among them. */
export function playList(
  info: StrategyInfo | null | undefined,
  schemaOptions: readonly (string | number)[] | undefined,
  current: string | null,
): PlayInfo[] {
  const out: PlayInfo[] = [];
  const seen = new Set<string>();
  const add = (p: PlayInfo) => {
    if (!p.name || seen.has(p.name)) return;
    seen.add(p.name);
    out.push(p);
  };
  if (info && Array.isArray(info.plays)) {
    for (const p of info.plays as unknown[]) {
      if (!isObj(p) || typeof p.name !== "string") continue;
      add({
        name: p.name,
        title: typeof p.title === "string" && p.title ? p.title : humanizePlay(p.name),
        description: typeof p.description === "string" ? p.description : "",
        source: p.source === "team" ? "team" : "builtin",
        file: typeof p.file === "string" ? p.file : null,
        language: p.language === "python" || p.language === "octave" ? p.language : null,
      });
    }
  }
  if (out.length === 0 && schemaOptions) {
    for (const o of schemaOptions) add({ name: String(o), title: humanizePlay(String(o)), description: "", ...BUILTIN });
  }
  if (current && !seen.has(current)) add({ name: current, title: humanizePlay(current), description: "", ...BUILTIN });
  return out;
}

/** The play in force: the parameter (pushed to every client), else the world's, else GET /api/strategy's. */
export function currentPlay(
  values: ParamValues | null | undefined,
  worldPlay: string | null | undefined,
  info: StrategyInfo | null | undefined,
): string | null {
  const group = values?.["strategy"];
  if (isObj(group) && typeof group.play === "string" && group.play) return group.play;
  if (typeof worldPlay === "string" && worldPlay) return worldPlay;
  return info && typeof info.play === "string" && info.play ? info.play : null;
}

/** "STOP: keep 0.5 m from the ball" plus the side we defend, for the banner near the field. */
export function situationLine(
  s: Pick<Partial<StrategyState>, "situation" | "situation_text" | "our_side" | "side_from_referee"> | null | undefined,
): { text: string; side: string } | null {
  if (!s) return null;
  const text = (typeof s.situation_text === "string" && s.situation_text) || (typeof s.situation === "string" ? s.situation : "");
  const side =
    s.our_side === "negative-x" ? "we defend the −x goal (left)" : s.our_side === "positive-x" ? "we defend the +x goal (right)" : "";
  if (!text && !side) return null;
  return { text, side: side && s.side_from_referee === true ? `${side}, side from the referee` : side };
}

export interface PlayGroup {
  label: "Built-in" | "Team";
  plays: PlayInfo[];
}

/**
 * The plays as the selectors group them: the station's own ("Built-in") and the team's files
 * ("Team"), each in the station's order. A single group without a label when the team has no
 * plays (nothing to tell apart).
 */
export function playGroups(list: readonly PlayInfo[]): PlayGroup[] {
  const builtin = list.filter((p) => p.source !== "team");
  const team = list.filter((p) => p.source === "team");
  if (team.length === 0) return builtin.length ? [{ label: "Built-in", plays: builtin }] : [];
  return builtin.length ? [{ label: "Built-in", plays: builtin }, { label: "Team", plays: team }] : [{ label: "Team", plays: team }];
}

/** Whether the selectors must show group labels (team plays beside built-in ones). */
export function showGroups(groups: readonly PlayGroup[]): boolean {
  return groups.some((g) => g.label === "Team");
}

/**
 * What of the team folder changes the list of plays (a file added, removed or renamed, a
 * title or description changed): when this differs from the last one seen, the page asks
 * the station for its plays again. Saves that change only code do not change it.
 */
export function teamPlaysKey(
  files: readonly { name: string; kind: string; play: string | null; title: string; description: string }[] | null | undefined,
): string {
  if (!Array.isArray(files)) return "";
  return files
    .filter((f) => f.kind === "play")
    .map((f) => `${f.name}\u0000${f.play ?? ""}\u0000${f.title}\u0000${f.description}`)
    .sort()
    .join("\u0001");
}

/** The per-robot plays in the parameters: `strategy.robot_plays` {"3": "pass_drill"}. */
export function robotPlays(values: ParamValues | null | undefined): Record<string, string> {
  const group = values?.["strategy"];
  const m = isObj(group) ? group.robot_plays : undefined;
  if (!isObj(m)) return {};
  const out: Record<string, string> = {};
  for (const [k, v] of Object.entries(m)) if (typeof v === "string" && v) out[k] = v;
  return out;
}

/** PATCH body giving robot `id` its own play (null: back to the team's play). */
export function robotPlayPatch(id: number, play: string | null): Record<string, unknown> {
  return { [PLAY_PATH[0]]: { robot_plays: { [String(id)]: play ? play : null } } };
}
