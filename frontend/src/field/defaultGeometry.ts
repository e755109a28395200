// Division B field used until the first geometry packet, and field markings derived from
// the dimensions when a geometry packet carries no line/arc lists.

import type { FieldArc, FieldLine, Geometry } from "../api/types";

export function standardMarkings(g: Omit<Geometry, "lines" | "arcs">): {
  lines: FieldLine[];
  arcs: FieldArc[];
} {
  const hl = g.field_length / 2;
  const hw = g.field_width / 2;
  const pd = g.penalty_area_depth;
  const pw = g.penalty_area_width / 2;
  const t = 10;
  const line = (name: string, x1: number, y1: number, x2: number, y2: number): FieldLine => ({
    name,
    p1: { x: x1, y: y1 },
    p2: { x: x2, y: y2 },
    thickness: t,
  });
  return {
    lines: [
      line("TopTouchLine", -hl, hw, hl, hw),
      line("BottomTouchLine", -hl, -hw, hl, -hw),
      line("LeftGoalLine", -hl, -hw, -hl, hw),
      line("RightGoalLine", hl, -hw, hl, hw),
      line("HalfwayLine", 0, -hw, 0, hw),
      line("CenterLine", -hl, 0, hl, 0),
      line("LeftPenaltyStretch", -hl + pd, -pw, -hl + pd, pw),
      line("RightPenaltyStretch", hl - pd, -pw, hl - pd, pw),
      line("LeftFieldLeftPenaltyStretch", -hl, -pw, -hl + pd, -pw),
      line("LeftFieldRightPenaltyStretch", -hl, pw, -hl + pd, pw),
      line("RightFieldLeftPenaltyStretch", hl - pd, -pw, hl, -pw),
      line("RightFieldRightPenaltyStretch", hl - pd, pw, hl, pw),
    ],
    arcs: [
      {
        name: "CenterCircle",
        center: { x: 0, y: 0 },
        radius: g.center_circle_radius,
        a1: 0,
        a2: 2 * Math.PI,
        thickness: t,
      },
    ],
  };
}

const divisionBDims: Omit<Geometry, "lines" | "arcs"> = {
  field_length: 9000,
  field_width: 6000,
  goal_width: 1000,
  goal_depth: 180,
  boundary_width: 300,
  penalty_area_depth: 1000,
  penalty_area_width: 2000,
  goal_center_to_penalty_mark: 6000,
  center_circle_radius: 500,
  ball_radius: 21.5,
  max_robot_radius: 90,
  cameras: [],
};

export const DEFAULT_GEOMETRY: Geometry = { ...divisionBDims, ...standardMarkings(divisionBDims) };

/** Geometry to draw: the default before any packet, derived markings if none were sent. */
export function effectiveGeometry(g: Geometry | null): Geometry {
  if (g === null || !(g.field_length > 0) || !(g.field_width > 0)) return DEFAULT_GEOMETRY;
  if (g.lines.length === 0 && g.arcs.length === 0) return { ...g, ...standardMarkings(g) };
  return g;
}
