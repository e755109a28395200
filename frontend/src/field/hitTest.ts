// Which robot is under a point given in world mm. Pure.

import { ROBOT_RADIUS_MM } from "../api/contract.gen";
import type { Robot } from "../api/types";
import type { Point } from "./transform";

export { ROBOT_RADIUS_MM };

/**
 * The robot whose centre is nearest to `p` among those within `radiusMm` (the robot
 * radius plus any click tolerance), or null. Invisible robots are hit only when
 * `includeInvisible` is true (they are drawn faded at their last position).
 */
export function hitTestRobot(
  robots: readonly Robot[],
  p: Point,
  radiusMm: number = ROBOT_RADIUS_MM,
  includeInvisible = true,
): Robot | null {
  let best: Robot | null = null;
  let bestD2 = radiusMm * radiusMm;
  for (const r of robots) {
    if (!includeInvisible && !r.visible) continue;
    if (!Number.isFinite(r.x) || !Number.isFinite(r.y)) continue;
    const dx = r.x - p.x;
    const dy = r.y - p.y;
    const d2 = dx * dx + dy * dy;
    if (d2 <= bestD2) {
      best = r;
      bestD2 = d2;
    }
  }
  return best;
}

/** Click tolerance in mm: the robot radius, grown so a robot is at least `minPx` px wide to hit. */
export function hitRadiusMm(scalePxPerMm: number, minPx = 10, robotRadiusMm = ROBOT_RADIUS_MM): number {
  if (!(scalePxPerMm > 0)) return robotRadiusMm;
  return Math.max(robotRadiusMm, minPx / scalePxPerMm);
}
