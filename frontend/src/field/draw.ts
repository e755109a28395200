// Canvas rendering of the field, robots, targets and ball. Called from the animation
// frame loop with the latest store state; no React involved.

import type { Geometry, Robot, RobotKey, Team, World } from "../api/types";
import { sameRobot } from "../api/types";
import { ROBOT_RADIUS_MM } from "./hitTest";
import { angleToCanvas, worldToCanvas, type FieldTransform } from "./transform";

export const COLORS = {
  background: "#0b1220",
  grass: "#166534",
  grassOuter: "#14532d",
  line: "rgba(255,255,255,0.9)",
  boundary: "rgba(255,255,255,0.35)",
  goal: "#e5e7eb",
  blue: "#2563eb",
  yellow: "#facc15",
  robotOutline: "#0f172a",
  blueText: "#ffffff",
  yellowText: "#111827",
  ball: "#f97316",
  ballOutline: "#431407",
  selected: "#ffffff",
  target: "#f8fafc",
  estop: "rgba(220,38,38,0.9)",
} as const;

export function teamColor(team: Team): string {
  return team === "blue" ? COLORS.blue : COLORS.yellow;
}

export interface DrawInput {
  t: FieldTransform;
  geometry: Geometry;
  /** True when `geometry` is the default (no packet received yet). */
  waitingForGeometry: boolean;
  /** True when the live connection is down and the world shown is the last one received. */
  stale: boolean;
  world: World | null;
  selected: RobotKey | null;
  hovered: RobotKey | null;
}

export function drawField(ctx: CanvasRenderingContext2D, input: DrawInput): void {
  const { t, geometry: g, world } = input;
  ctx.save();
  ctx.fillStyle = COLORS.background;
  ctx.fillRect(0, 0, t.width, t.height);

  drawSurface(ctx, t, g);
  drawMarkings(ctx, t, g);
  drawGoals(ctx, t, g, world?.referee?.blue_team_on_positive_half ?? null);

  if (world) {
    const robots = world.robots;
    // Targets under robots, robots over them, the selected robot last.
    for (const r of robots) if (r.target) drawTarget(ctx, t, r, sameRobot(r, input.selected));
    for (const r of robots) {
      if (!sameRobot(r, input.selected)) drawRobot(ctx, t, r, false, sameRobot(r, input.hovered));
    }
    const sel = input.selected ? robots.find((r) => sameRobot(r, input.selected)) : undefined;
    if (sel) drawRobot(ctx, t, sel, true, false);
    if (world.ball) drawBall(ctx, t, world.ball, g.ball_radius > 0 ? g.ball_radius : 21.5);
  }

  let slot = 0;
  if (world?.estop) drawBanner(ctx, t, "EMERGENCY STOP ACTIVE", COLORS.estop, "#ffffff", slot++);
  const halt = world?.halt_reason;
  if (world && !world.estop && typeof halt === "string" && halt) {
    drawBanner(ctx, t, `robots held: ${halt}`, "rgba(146,64,14,0.92)", "#fef3c7", slot++);
  }
  if (input.stale && world) {
    drawBanner(ctx, t, "connection lost: showing the last data received", "rgba(120,53,15,0.92)", "#fef3c7", slot++);
  }
  if (input.waitingForGeometry) {
    drawBanner(ctx, t, "waiting for geometry", "rgba(15,23,42,0.8)", "#e2e8f0", slot++);
  }
  ctx.restore();
}

function drawSurface(ctx: CanvasRenderingContext2D, t: FieldTransform, g: Geometry) {
  const hl = g.field_length / 2;
  const hw = g.field_width / 2;
  const b = Math.max(0, g.boundary_width);
  const outer0 = worldToCanvas(t, -hl - b, hw + b);
  const outer1 = worldToCanvas(t, hl + b, -hw - b);
  ctx.fillStyle = COLORS.grassOuter;
  ctx.fillRect(outer0.x, outer0.y, outer1.x - outer0.x, outer1.y - outer0.y);
  const in0 = worldToCanvas(t, -hl, hw);
  const in1 = worldToCanvas(t, hl, -hw);
  ctx.fillStyle = COLORS.grass;
  ctx.fillRect(in0.x, in0.y, in1.x - in0.x, in1.y - in0.y);
  ctx.strokeStyle = COLORS.boundary;
  ctx.lineWidth = 1;
  ctx.strokeRect(outer0.x + 0.5, outer0.y + 0.5, outer1.x - outer0.x - 1, outer1.y - outer0.y - 1);
}

function drawMarkings(ctx: CanvasRenderingContext2D, t: FieldTransform, g: Geometry) {
  ctx.strokeStyle = COLORS.line;
  ctx.lineCap = "butt";
  for (const l of g.lines) {
    const a = worldToCanvas(t, l.p1.x, l.p1.y);
    const b = worldToCanvas(t, l.p2.x, l.p2.y);
    ctx.lineWidth = Math.max(1, (l.thickness || 10) * t.scale);
    ctx.beginPath();
    ctx.moveTo(a.x, a.y);
    ctx.lineTo(b.x, b.y);
    ctx.stroke();
  }
  for (const arc of g.arcs) {
    const c = worldToCanvas(t, arc.center.x, arc.center.y);
    ctx.lineWidth = Math.max(1, (arc.thickness || 10) * t.scale);
    ctx.beginPath();
    // Counter-clockwise from a1 to a2 in the world is clockwise-decreasing on the canvas.
    ctx.arc(c.x, c.y, arc.radius * t.scale, angleToCanvas(arc.a1), angleToCanvas(arc.a2), true);
    ctx.stroke();
  }
}

function drawGoals(
  ctx: CanvasRenderingContext2D,
  t: FieldTransform,
  g: Geometry,
  blueOnPositive: boolean | null,
) {
  if (!(g.goal_width > 0)) return;
  const hl = g.field_length / 2;
  const gw = g.goal_width / 2;
  const gd = Math.max(g.goal_depth, 1);
  for (const side of [-1, 1] as const) {
    let color: string = COLORS.goal;
    if (blueOnPositive !== null) {
      const blueSide = blueOnPositive ? 1 : -1;
      color = side === blueSide ? COLORS.blue : COLORS.yellow;
    }
    const p0 = worldToCanvas(t, side * hl, gw);
    const p1 = worldToCanvas(t, side * (hl + gd), gw);
    const p2 = worldToCanvas(t, side * (hl + gd), -gw);
    const p3 = worldToCanvas(t, side * hl, -gw);
    ctx.lineWidth = Math.max(2, 20 * t.scale);
    ctx.strokeStyle = COLORS.robotOutline;
    ctx.lineJoin = "miter";
    ctx.beginPath();
    ctx.moveTo(p0.x, p0.y);
    ctx.lineTo(p1.x, p1.y);
    ctx.lineTo(p2.x, p2.y);
    ctx.lineTo(p3.x, p3.y);
    ctx.stroke();
    ctx.lineWidth = Math.max(1, 12 * t.scale);
    ctx.strokeStyle = color;
    ctx.stroke();
  }
}

/** Smallest drawn robot radius in CSS px, so ids stay readable when zoomed out. */
export const MIN_ROBOT_PX = 10;

/** Fraction of the radius at which the flat front of the robot is cut. */
const FRONT_CUT = 0.72;

function drawRobot(
  ctx: CanvasRenderingContext2D,
  t: FieldTransform,
  r: Robot,
  selected: boolean,
  hovered: boolean,
) {
  const c = worldToCanvas(t, r.x, r.y);
  const rad = Math.max(MIN_ROBOT_PX, ROBOT_RADIUS_MM * t.scale);
  const heading = angleToCanvas(Number.isFinite(r.orientation) ? r.orientation : 0);
  const alpha = Math.acos(FRONT_CUT);

  ctx.save();
  if (!r.visible) ctx.globalAlpha = 0.4;

  if (selected || hovered) {
    ctx.beginPath();
    ctx.arc(c.x, c.y, rad + Math.max(4, 40 * t.scale), 0, 2 * Math.PI);
    ctx.fillStyle = selected ? "rgba(255,255,255,0.28)" : "rgba(255,255,255,0.14)";
    ctx.fill();
    if (selected) {
      ctx.lineWidth = 2;
      ctx.strokeStyle = COLORS.selected;
      ctx.stroke();
    }
  }

  // Body: a circle with the front cut flat, the chord facing the heading.
  ctx.beginPath();
  ctx.arc(c.x, c.y, rad, heading + alpha, heading - alpha + 2 * Math.PI, false);
  ctx.closePath();
  ctx.fillStyle = teamColor(r.team);
  ctx.fill();
  ctx.lineWidth = Math.max(1.5, Math.min(3, rad * 0.12));
  ctx.strokeStyle = COLORS.robotOutline;
  ctx.stroke();

  // Heading tick from the centre to the front, for small zoom levels.
  ctx.beginPath();
  ctx.moveTo(c.x, c.y);
  ctx.lineTo(c.x + Math.cos(heading) * rad * FRONT_CUT, c.y + Math.sin(heading) * rad * FRONT_CUT);
  ctx.lineWidth = Math.max(1, rad * 0.1);
  ctx.strokeStyle = r.team === "blue" ? "rgba(255,255,255,0.55)" : "rgba(17,24,39,0.45)";
  ctx.stroke();

  // Id on top, upright.
  const fontPx = Math.max(10, Math.round(rad * 1.1));
  ctx.font = `700 ${fontPx}px system-ui, -apple-system, "Segoe UI", Roboto, sans-serif`;
  ctx.textAlign = "center";
  ctx.textBaseline = "middle";
  ctx.fillStyle = r.team === "blue" ? COLORS.blueText : COLORS.yellowText;
  ctx.fillText(String(r.id), c.x, c.y + fontPx * 0.05);
  ctx.restore();
}

function drawTarget(ctx: CanvasRenderingContext2D, t: FieldTransform, r: Robot, selected: boolean) {
  if (!r.target) return;
  const from = worldToCanvas(t, r.x, r.y);
  const to = worldToCanvas(t, r.target.x, r.target.y);
  ctx.save();
  ctx.globalAlpha = selected ? 1 : 0.75;
  ctx.strokeStyle = r.target.source === "operator" ? COLORS.target : teamColor(r.team);
  ctx.lineWidth = selected ? 2 : 1.5;
  ctx.setLineDash([6, 5]);
  ctx.beginPath();
  ctx.moveTo(from.x, from.y);
  ctx.lineTo(to.x, to.y);
  ctx.stroke();
  ctx.setLineDash([]);
  const s = Math.max(5, 60 * t.scale);
  ctx.lineWidth = selected ? 3 : 2;
  ctx.beginPath();
  ctx.moveTo(to.x - s, to.y - s);
  ctx.lineTo(to.x + s, to.y + s);
  ctx.moveTo(to.x - s, to.y + s);
  ctx.lineTo(to.x + s, to.y - s);
  ctx.stroke();
  if (r.target.orientation !== null && Number.isFinite(r.target.orientation)) {
    const a = angleToCanvas(r.target.orientation);
    ctx.beginPath();
    ctx.moveTo(to.x, to.y);
    ctx.lineTo(to.x + Math.cos(a) * s * 2, to.y + Math.sin(a) * s * 2);
    ctx.stroke();
  }
  ctx.restore();
}

function drawBall(
  ctx: CanvasRenderingContext2D,
  t: FieldTransform,
  ball: NonNullable<World["ball"]>,
  radiusMm: number,
) {
  const c = worldToCanvas(t, ball.x, ball.y);
  const rad = Math.max(4, radiusMm * t.scale);
  ctx.save();
  if (!ball.visible) ctx.globalAlpha = 0.45;
  ctx.beginPath();
  ctx.arc(c.x, c.y, rad, 0, 2 * Math.PI);
  ctx.fillStyle = COLORS.ball;
  ctx.fill();
  ctx.lineWidth = 1.5;
  ctx.strokeStyle = COLORS.ballOutline;
  ctx.stroke();
  ctx.restore();
}

function drawBanner(
  ctx: CanvasRenderingContext2D,
  t: FieldTransform,
  text: string,
  bg: string,
  fg: string,
  slot: number,
) {
  ctx.save();
  const fontPx = Math.max(13, Math.min(22, Math.round(t.width / 45)));
  ctx.font = `700 ${fontPx}px system-ui, -apple-system, "Segoe UI", Roboto, sans-serif`;
  const w = ctx.measureText(text).width + fontPx * 1.6;
  const h = fontPx * 2;
  const x = (t.width - w) / 2;
  const y = 14 + slot * (h + 8);
  ctx.fillStyle = bg;
  ctx.beginPath();
  ctx.roundRect(x, y, w, h, 6);
  ctx.fill();
  ctx.fillStyle = fg;
  ctx.textAlign = "center";
  ctx.textBaseline = "middle";
  ctx.fillText(text, t.width / 2, y + h / 2);
  ctx.restore();
}
