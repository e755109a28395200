// Pure: the robots held still because the team-code play that drives them failed
// (world.strategy.stopped): grouped for the Code tab, one line for a robot's tooltip and
// details, and the lookup the field drawing uses. Small on purpose: the field, the robot
// panel and the (lazily loaded) Code tab share it.

import type { StoppedRobot, TeamFile } from "../api/types";

/** Robots a failed play holds still, grouped by play: [{play, ids, reason}] (reason of the first). */
export function stoppedByPlay(stopped: readonly StoppedRobot[] | null | undefined): { play: string; ids: number[]; reason: string }[] {
  const by = new Map<string, { play: string; ids: number[]; reason: string }>();
  for (const s of stopped ?? []) {
    const g = by.get(s.play);
    if (g) g.ids.push(s.id);
    else by.set(s.play, { play: s.play, ids: [s.id], reason: s.reason });
  }
  return [...by.values()].map((g) => ({ ...g, ids: g.ids.sort((a, b) => a - b) })).sort((a, b) => a.play.localeCompare(b.play));
}

/** The robots stopped because of this play file (its play name), sorted. */
export function stoppedOf(f: Pick<TeamFile, "play">, stopped: readonly StoppedRobot[] | null | undefined): number[] {
  if (!f.play) return [];
  return (stopped ?? []).filter((s) => s.play === f.play).map((s) => s.id).sort((a, b) => a - b);
}

/** "Play pass_drill stopped: exception at ..." for a robot's tooltip and details. */
export function stoppedText(s: Pick<StoppedRobot, "play" | "reason">): string {
  return `play ${s.play} failed, robot stopped: ${s.reason}`;
}

/** The stopped entry of our robot `id`, if its play failed. */
export function stoppedEntry(
  strategy: { our_team: string; stopped?: readonly StoppedRobot[] | null } | null | undefined,
  team: string,
  id: number,
): StoppedRobot | null {
  if (!strategy || strategy.our_team !== team) return null;
  return strategy.stopped?.find((s) => s.id === id) ?? null;
}
