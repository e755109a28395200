// What the referee state means for the page (pure; no React).

import type { Health, Referee, RefereeCommand, Robot, Team, Vec } from "./api/types";

/** The commands during which the designated position is where the ball goes. */
export const PLACEMENT_COMMANDS: readonly RefereeCommand[] = ["BALL_PLACEMENT_BLUE", "BALL_PLACEMENT_YELLOW"];

/**
 * The ball placement target, only while a ball placement runs. The official game controller
 * sends `designated_position` whenever its placement position is set, not only during a
 * placement: (0, 0) at the start, the old mark during STOP and timeouts. That one means
 * nothing and is not shown.
 */
export function placementTarget(ref: Referee | null | undefined): Vec | null {
  if (!ref || ref.source === "none" || !ref.designated_position) return null;
  return PLACEMENT_COMMANDS.includes(ref.command) ? ref.designated_position : null;
}

/** Robots of `team` the station sees on the field now. */
export function visibleRobots(robots: readonly Robot[] | undefined, team: Team): number {
  return (robots ?? []).filter((r) => r.team === team && r.visible).length;
}

/**
 * Whole seconds the referee the station obeys has been silent, null while it speaks (or none
 * was heard, or the station ignores it). The station keeps obeying its last command meanwhile.
 */
export function refereeSilentFor(health: Health | null | undefined): number | null {
  const r = health?.referee;
  if (!r || !r.silent || !Number.isFinite(r.last_heard_s)) return null;
  return Math.floor(r.last_heard_s);
}
