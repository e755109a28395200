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
