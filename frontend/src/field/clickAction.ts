// What a click on the field means. Pure.

import type { Robot, RobotKey } from "../api/types";
import { hitTestRobot } from "./hitTest";
import type { Point } from "./transform";

export type ClickAction =
  | { kind: "select"; robot: RobotKey }
  | { kind: "target"; robot: RobotKey; point: Point }
  | { kind: "none" };

/**
 * A click on a robot selects it; a click elsewhere sends the selected robot there
 * (if one is selected); otherwise nothing happens.
 */
export function decideClick(
  robots: readonly Robot[],
  selected: RobotKey | null,
  point: Point,
  hitRadiusMm: number,
): ClickAction {
  const hit = hitTestRobot(robots, point, hitRadiusMm);
  if (hit) return { kind: "select", robot: { team: hit.team, id: hit.id } };
  if (selected) return { kind: "target", robot: selected, point };
  return { kind: "none" };
}
