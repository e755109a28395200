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
    role: null,
    path: null,
    kick: null,
    dribbler: false,
    controlled: false,
    raw_x: x,
    raw_y: y,
    raw_orientation: 0,
    predicted: false,
    lost: false,
    filter: "kalman",
    control: null,
    command: null,
    feedback: null,
    ...extra,
  };
}
