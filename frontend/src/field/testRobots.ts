// Test fixtures (only imported by tests).
import type { Robot, Team } from "../api/types";

export function robot(team: Team, id: number, x: number, y: number, extra: Partial<Robot> = {}): Robot {
  return {
    team,
    id,
    x,
    y,
    orientation: 0,
    vx: 0,
    vy: 0,
    omega: 0,
    visible: true,
    age_s: 0,
    cameras: [0],
    target: null,
    controlled: false,
    command: null,
    ...extra,
  };
}
