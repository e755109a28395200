// Canvas rendering of the field, robots, targets and ball. Called from the animation
// frame loop with the latest store state; no React involved.

import type { Geometry, RecordedCommand, RecordedWorld, Robot, RobotKey, Team, World } from "../api/types";
import { sameRobot } from "../api/types";
import { placementTarget } from "../referee";
import { roleColor, roleTag } from "../strategy/roles";
import { BALL_RADIUS_MM } from "../api/contract.gen";
import { ROBOT_RADIUS_MM } from "./hitTest";
import { pathPoints, tracePath } from "./paths";
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
  lost: "#9ca3af",
  kick: "#f43f5e",
  chip: "#c084fc",
  dribbler: "#22d3ee",
  /** The robot reports the ball at its dribbler (feedback.ball_contact). */
  ballContact: "#fb923c",
  /** The robot does not answer its commands (feedback.no_answer). */
  noAnswer: "#f87171",
  /** The velocity control commands (what-if arrows in replay). */
  command: "#e879f9",
  bluePath: "rgba(147,197,253,0.9)",
  yellowPath: "rgba(253,224,71,0.9)",
  roleBg: "rgba(15,23,42,0.82)",
  /** A robot held still because its team-code play failed (world.strategy.stopped). */
  stopped: "#ef4444",
  /** The estimate recorded in a replayed log (what-if ghosts): neutral, unlike the lost grey. */
  recorded: "rgba(241,245,249,0.9)",
} as const;

/** Dash of the recorded-estimate ghosts (long dashes; lost robots use a shorter [4, 3]). */
export const RECORDED_DASH = [7, 4];

/** Opacity of a predicted object (no fresh detection, position extrapolated). */
export const PREDICTED_ALPHA = 0.45;

/** How an object is drawn: measured (solid), predicted (semi-transparent), lost (hollow grey outline). */
export type TrackStyle = "measured" | "predicted" | "lost";

export function trackStyle(o: { visible?: boolean; predicted?: boolean; lost?: boolean }): TrackStyle {
  if (o.lost) return "lost";
  if (o.predicted || o.visible === false) return "predicted";
  return "measured";
}

export function teamColor(team: Team): string {
  return team === "blue" ? COLORS.blue : COLORS.yellow;
}

/** Camera colours for raw detections: distinct from the team colours and the ball. */
export const CAMERA_COLORS = ["#f472b6", "#22d3ee", "#a3e635", "#c084fc", "#fb7185", "#2dd4bf", "#fde68a", "#93c5fd"];

export function cameraColor(id: number): string {
  return CAMERA_COLORS[((id % CAMERA_COLORS.length) + CAMERA_COLORS.length) % CAMERA_COLORS.length] as string;
}

export interface DrawLayers {
  raw: boolean;
  filtered: boolean;
  velocity: boolean;
  targets: boolean;
  trails: boolean;
  referee: boolean;
  /** Planned paths of the strategy (dashed polylines through the waypoints). */
  paths: boolean;
  /** Role tags next to our robots. */
  roles: boolean;
  /** In replay: the estimate recorded in the log (world.recorded), as dashed ghost outlines. */
  recorded: boolean;
  /** A kick in progress (ball.kick): dashed line to the predicted stop point, a cross there, the kicker. */
  kicks: boolean;
  /** In replay: the velocity control commands now for each robot (what-if: nothing is sent), as arrows. */
  commands: boolean;
}

export const ALL_LAYERS: DrawLayers = {
  raw: false, filtered: true, velocity: false, targets: true, trails: false, referee: true, paths: true, roles: true,
  recorded: true, kicks: true, commands: true,
};

export interface DrawInput {
  layers?: DrawLayers;
  /** Trails: per object key, world points oldest first. */
  trails?: ReadonlyMap<string, readonly { x: number; y: number }[]>;
  /** Arrow being dragged to set a target with a heading (world mm). */
  drag?: { from: { x: number; y: number }; to: { x: number; y: number } } | null;
  /** Ball placement waiting for a click. */
  placing?: string | null;
  t: FieldTransform;
  geometry: Geometry;
  /** True when `geometry` is the default (no packet received yet). */
  waitingForGeometry: boolean;
  /** True when the live connection is down and the world shown is the last one received. */
  stale: boolean;
  world: World | null;
  selected: RobotKey | null;
  hovered: RobotKey | null;
  /** Large-text mode (projector): bigger role tags. */
  largeText?: boolean;
}

/** What one frame drew (for window.__touchline.stats). */
export interface DrawCounts {
  robots: number;
  raw: number;
  /** Robots whose planned path was drawn. */
  paths: number;
  /** Role tags drawn. */
  roles: number;
  /** The ball placement mark drawn (world mm), null when none. */
  designated: { x: number; y: number } | null;
  /** Objects of the recorded estimate drawn (robots + ball; 0 live or with the layer off). */
  recorded: number;
  /** The predicted stop point of the kick drawn (world mm), null when none. */
  kickStop: { x: number; y: number } | null;
  /** Other balls drawn faintly (a second ball left on the field). */
  otherBalls: number;
  /** Our robots marked as stopped because their team-code play failed ("blue 3"). */
  stopped: string[];
  /** Command arrows drawn (replay only). */
  commands: number;
  /** Arrows of the commands the replayed log sent (world.recorded.commands), beside those. */
  recordedCommands: number;
}

export function drawField(ctx: CanvasRenderingContext2D, input: DrawInput): DrawCounts {
  const counts: DrawCounts = { robots: 0, raw: 0, paths: 0, roles: 0, designated: null, recorded: 0, kickStop: null, otherBalls: 0, stopped: [], commands: 0, recordedCommands: 0 };
  const { t, geometry: g, world } = input;
  ctx.save();
  ctx.fillStyle = COLORS.background;
  ctx.fillRect(0, 0, t.width, t.height);

  drawSurface(ctx, t, g);
  drawMarkings(ctx, t, g);
  drawGoals(ctx, t, g, world?.referee?.blue_team_on_positive_half ?? null);

  const L = input.layers ?? ALL_LAYERS;
  if (world) {
    const robots = world.robots;
    const ref = world.referee;
    // Only during a ball placement: the game controller sends its last mark at other times too.
    const mark = placementTarget(ref);
    if (L.referee && ref && mark) {
      drawDesignated(ctx, t, mark, ref.command);
      counts.designated = { x: mark.x, y: mark.y };
    }
    if (L.trails && input.trails) drawTrails(ctx, t, input.trails);
    if (L.raw) counts.raw = drawRaw(ctx, t, world);
    // Paths and targets under robots, robots over them, the selected robot last, role tags on top.
    if (L.paths) counts.paths = drawPaths(ctx, t, robots, input.selected);
    if (L.targets) {
      for (const r of robots) {
        // A drawn path already leads to the target: only its mark then, no straight line.
        if (r.target) drawTarget(ctx, t, r, sameRobot(r, input.selected), !(L.paths && pathPoints(r.path)));
      }
    }
    if (L.filtered) {
      for (const r of robots) {
        if (!sameRobot(r, input.selected)) {
          drawRobot(ctx, t, r, false, sameRobot(r, input.hovered));
          counts.robots++;
        }
      }
    }
    const sel = input.selected ? robots.find((r) => sameRobot(r, input.selected)) : undefined;
    if (sel) {
      drawRobot(ctx, t, sel, true, false);
      counts.robots++;
    }
    // The recorded estimate over today's: a ring just outside each robot, so both stay visible.
    if (L.recorded && world.recorded) counts.recorded = drawRecorded(ctx, t, world.recorded, g.ball_radius > 0 ? g.ball_radius : BALL_RADIUS_MM);
    if (L.roles && L.filtered) counts.roles = drawRoleTags(ctx, t, robots, world.strategy?.our_team ?? null, input.largeText === true);
    // Always (not a layer): robots standing still because their play failed must not look idle.
    if (L.filtered && world.strategy?.stopped?.length) counts.stopped = drawStopped(ctx, t, robots, world.strategy);
    const kick = world.ball?.kick;
    if (L.kicks && world.ball && kick) {
      // Under the ball: the line leaves from under it.
      drawKick(ctx, t, world.ball, kick);
      counts.kickStop = { x: kick.stop_x, y: kick.stop_y };
    }
    if (L.filtered) {
      const br = g.ball_radius > 0 ? g.ball_radius : BALL_RADIUS_MM;
      for (const o of world.other_balls ?? []) {
        drawOtherBall(ctx, t, o, br);
        counts.otherBalls++;
      }
      if (world.ball) drawBall(ctx, t, world.ball, br);
    }
    // What-if: what control would command now, beside what the robots did (the log).
    if (L.commands && world.replay) {
      // what the log's station sent then (dashed, neutral) under what control commands now
      if (world.recorded?.commands.length) counts.recordedCommands = drawRecordedCommands(ctx, t, robots, world.recorded.commands);
      counts.commands = drawCommands(ctx, t, robots);
    }
    if (L.velocity) {
      for (const r of robots) if (r.visible) drawVelocity(ctx, t, r.x, r.y, r.vx, r.vy, teamColor(r.team));
      if (world.ball?.visible) drawVelocity(ctx, t, world.ball.x, world.ball.y, world.ball.vx, world.ball.vy, COLORS.ball);
    }
  }
  if (input.drag) drawDrag(ctx, t, input.drag.from, input.drag.to);

  let slot = 0;
  if (world?.estop) drawBanner(ctx, t, "EMERGENCY STOP ACTIVE", COLORS.estop, "#ffffff", slot++);
  const halt = world?.halt_reason;
  if (world && !world.estop && typeof halt === "string" && halt) {
    drawBanner(ctx, t, `robots held: ${halt}`, "rgba(146,64,14,0.92)", "#fef3c7", slot++);
  }
  if (world?.strategy?.stopped?.length) {
    for (const line of stoppedBanners(world.strategy)) drawBanner(ctx, t, line, "rgba(127,29,29,0.92)", "#fee2e2", slot++);
  }
  if (input.stale && world) {
    drawBanner(ctx, t, "connection lost: showing the last data received", "rgba(120,53,15,0.92)", "#fef3c7", slot++);
  }
  if (input.placing) {
    drawBanner(ctx, t, `click where the ball goes: ${input.placing.replace(/_/g, " ").toLowerCase()}`, "rgba(30,64,175,0.92)", "#e0e7ff", slot++);
  }
  if (input.waitingForGeometry) {
    drawBanner(ctx, t, "waiting for geometry", "rgba(15,23,42,0.8)", "#e2e8f0", slot++);
  }
  ctx.restore();
  return counts;
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

  const style = trackStyle(r);
  ctx.save();
  if (style === "predicted") ctx.globalAlpha = PREDICTED_ALPHA;

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
  if (style === "lost") {
    // Hollow grey outline: the world model no longer tracks it.
    ctx.lineWidth = Math.max(1.5, Math.min(3, rad * 0.14));
    ctx.strokeStyle = COLORS.lost;
    ctx.setLineDash([4, 3]);
    ctx.stroke();
    ctx.setLineDash([]);
    ctx.font = `600 ${Math.max(9, Math.round(rad * 0.9))}px system-ui, -apple-system, "Segoe UI", Roboto, sans-serif`;
    ctx.textAlign = "center";
    ctx.textBaseline = "middle";
    ctx.fillStyle = COLORS.lost;
    ctx.fillText(String(r.id), c.x, c.y);
    ctx.restore();
    return;
  }
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

  if (r.kick || r.dribbler) drawFrontMarks(ctx, c, heading, rad, r.kick ?? null, r.dribbler === true);
  if (r.feedback?.ball_contact) drawBallContact(ctx, c, heading, rad);
  if (r.feedback?.no_answer) drawNoAnswer(ctx, c, rad);

  // Id on top, upright.
  const fontPx = Math.max(10, Math.round(rad * 1.1));
  ctx.font = `700 ${fontPx}px system-ui, -apple-system, "Segoe UI", Roboto, sans-serif`;
  ctx.textAlign = "center";
  ctx.textBaseline = "middle";
  ctx.fillStyle = r.team === "blue" ? COLORS.blueText : COLORS.yellowText;
  ctx.fillText(String(r.id), c.x, c.y + fontPx * 0.05);
  ctx.restore();
}

function drawTarget(ctx: CanvasRenderingContext2D, t: FieldTransform, r: Robot, selected: boolean, line = true) {
  if (!r.target) return;
  const to = worldToCanvas(t, r.target.x, r.target.y);
  ctx.save();
  ctx.globalAlpha = selected ? 1 : 0.75;
  ctx.strokeStyle = r.target.source === "operator" ? COLORS.target : teamColor(r.team);
  if (line) {
    const from = worldToCanvas(t, r.x, r.y);
    ctx.lineWidth = selected ? 2 : 1.5;
    ctx.setLineDash([6, 5]);
    ctx.beginPath();
    ctx.moveTo(from.x, from.y);
    ctx.lineTo(to.x, to.y);
    ctx.stroke();
    ctx.setLineDash([]);
  }
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
  const style = trackStyle(ball);
  ctx.save();
  if (style === "lost") {
    ctx.beginPath();
    ctx.arc(c.x, c.y, rad, 0, 2 * Math.PI);
    ctx.lineWidth = 1.5;
    ctx.strokeStyle = COLORS.lost;
    ctx.stroke();
    ctx.restore();
    return;
  }
  if (style === "predicted") ctx.globalAlpha = PREDICTED_ALPHA;
  ctx.beginPath();
  ctx.arc(c.x, c.y, rad, 0, 2 * Math.PI);
  ctx.fillStyle = COLORS.ball;
  ctx.fill();
  ctx.lineWidth = 1.5;
  ctx.strokeStyle = COLORS.ballOutline;
  ctx.stroke();
  if (ball.flying && ball.z > 0) {
    // A chip in the air: its height, over the ground point under it.
    ctx.font = "11px sans-serif";
    ctx.fillStyle = COLORS.ball;
    ctx.fillText(flyingLabel(ball.z), c.x + rad + 3, c.y - rad - 2);
  }
  ctx.restore();
}

/** The label of a ball in the air: its height in m. */
export function flyingLabel(zMm: number): string {
  return `↑${(zMm / 1000).toFixed(2)} m`;
}

/** Opacity of the other balls on the field (not the one played). */
export const OTHER_BALL_ALPHA = 0.3;

/** A ball seen besides the ball (left on the field): faint, outlined, not the one played. */
function drawOtherBall(ctx: CanvasRenderingContext2D, t: FieldTransform, o: World["other_balls"][number], radiusMm: number) {
  if (!Number.isFinite(o.x) || !Number.isFinite(o.y)) return;
  const c = worldToCanvas(t, o.x, o.y);
  ctx.save();
  ctx.globalAlpha = OTHER_BALL_ALPHA;
  ctx.beginPath();
  ctx.arc(c.x, c.y, Math.max(4, radiusMm * t.scale), 0, 2 * Math.PI);
  ctx.fillStyle = COLORS.ball;
  ctx.fill();
  ctx.lineWidth = 1;
  ctx.strokeStyle = COLORS.ballOutline;
  ctx.stroke();
  ctx.restore();
}

type BallKick = NonNullable<NonNullable<World["ball"]>["kick"]>;

/** Dash of the line to a kick's predicted stop point. */
export const KICK_DASH = [6, 5];

/** Half the size of the cross at a kick's stop point, px. */
export const KICK_CROSS_PX = 6;

/** What a kick in progress looks like on the canvas: the dashed line from the ball to the
 * predicted stop point (null once the ball is there), the cross and the kicker's label. */
export function kickMarks(
  t: FieldTransform,
  ball: { x: number; y: number },
  kick: BallKick,
): { line: [{ x: number; y: number }, { x: number; y: number }] | null; stop: { x: number; y: number }; label: string; labelColor: string } {
  const from = worldToCanvas(t, ball.x, ball.y);
  const stop = worldToCanvas(t, kick.stop_x, kick.stop_y);
  const line = Math.hypot(stop.x - from.x, stop.y - from.y) > KICK_CROSS_PX ? ([from, stop] as [typeof from, typeof stop]) : null;
  const r = kick.robot;
  const label = r ? `${r.team === "blue" ? "B" : "Y"}${r.id} ${kick.speed_mps.toFixed(1)} m/s` : `${kick.speed_mps.toFixed(1)} m/s`;
  return { line, stop, label, labelColor: r ? teamColor(r.team) : COLORS.kick };
}

/** Where a chip's flight in progress lands (world mm), null for a flat kick. */
export function chipLanding(kick: BallKick): { x: number; y: number } | null {
  if (!kick.chip || kick.land_x === null || kick.land_y === null) return null;
  if (!Number.isFinite(kick.land_x) || !Number.isFinite(kick.land_y)) return null;
  return { x: kick.land_x, y: kick.land_y };
}

function drawKick(ctx: CanvasRenderingContext2D, t: FieldTransform, ball: { x: number; y: number }, kick: BallKick) {
  if (![kick.stop_x, kick.stop_y, ball.x, ball.y].every(Number.isFinite)) return;
  const m = kickMarks(t, ball, kick);
  ctx.save();
  ctx.strokeStyle = COLORS.kick;
  ctx.lineWidth = 2;
  if (m.line) {
    ctx.setLineDash(KICK_DASH);
    ctx.beginPath();
    ctx.moveTo(m.line[0].x, m.line[0].y);
    ctx.lineTo(m.line[1].x, m.line[1].y);
    ctx.stroke();
    ctx.setLineDash([]);
  }
  const land = chipLanding(kick);
  if (land) {
    // A chip: where its flight in progress lands, a ring on the line.
    const p = worldToCanvas(t, land.x, land.y);
    ctx.beginPath();
    ctx.arc(p.x, p.y, KICK_CROSS_PX, 0, 2 * Math.PI);
    ctx.stroke();
  }
  const c = m.stop;
  const k = KICK_CROSS_PX;
  ctx.beginPath();
  ctx.moveTo(c.x - k, c.y - k);
  ctx.lineTo(c.x + k, c.y + k);
  ctx.moveTo(c.x - k, c.y + k);
  ctx.lineTo(c.x + k, c.y - k);
  ctx.stroke();
  ctx.font = "bold 11px system-ui, sans-serif";
  ctx.textBaseline = "bottom";
  ctx.lineWidth = 3;
  ctx.strokeStyle = COLORS.roleBg;
  ctx.strokeText(m.label, c.x + k + 2, c.y - 2);
  ctx.fillStyle = m.labelColor;
  ctx.fillText(m.label, c.x + k + 2, c.y - 2);
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

function drawRaw(ctx: CanvasRenderingContext2D, t: FieldTransform, world: World): number {
  let n = 0;
  ctx.save();
  ctx.lineWidth = 1.5;
  for (const cam of world.cameras ?? []) {
    const color = cameraColor(cam.camera_id);
    ctx.strokeStyle = color;
    ctx.fillStyle = color;
    n += cam.robots.length + cam.balls.length;
    for (const r of cam.robots) {
      const c = worldToCanvas(t, r.x, r.y);
      const rad = Math.max(6, ROBOT_RADIUS_MM * t.scale);
      ctx.beginPath();
      ctx.arc(c.x, c.y, rad, 0, 2 * Math.PI);
      ctx.stroke();
      const a = angleToCanvas(r.orientation);
      ctx.beginPath();
      ctx.moveTo(c.x, c.y);
      ctx.lineTo(c.x + Math.cos(a) * rad, c.y + Math.sin(a) * rad);
      ctx.stroke();
    }
    for (const b of cam.balls) {
      const c = worldToCanvas(t, b.x, b.y);
      const s = Math.max(4, 30 * t.scale);
      ctx.beginPath();
      ctx.moveTo(c.x - s, c.y);
      ctx.lineTo(c.x + s, c.y);
      ctx.moveTo(c.x, c.y - s);
      ctx.lineTo(c.x, c.y + s);
      ctx.stroke();
    }
  }
  ctx.restore();
  return n;
}

/**
 * The estimate recorded in a replayed log (what-if): each robot a dashed neutral ring a little
 * outside the robot's body with a heading tick, the ball a dashed ring with a tick either side. Drawn
 * over today's filter output so a difference between the two shows as an offset ring.
 * Returns the number of objects drawn.
 */
export function drawRecorded(ctx: CanvasRenderingContext2D, t: FieldTransform, rec: RecordedWorld, ballRadiusMm = BALL_RADIUS_MM): number {
  let n = 0;
  ctx.save();
  ctx.strokeStyle = COLORS.recorded;
  ctx.lineWidth = 1.5;
  ctx.setLineDash(RECORDED_DASH);
  const rad = Math.max(MIN_ROBOT_PX, ROBOT_RADIUS_MM * t.scale) + 3;
  for (const r of rec.robots) {
    if (!Number.isFinite(r.x) || !Number.isFinite(r.y)) continue;
    const c = worldToCanvas(t, r.x, r.y);
    ctx.beginPath();
    ctx.arc(c.x, c.y, rad, 0, 2 * Math.PI);
    ctx.stroke();
    if (Number.isFinite(r.orientation)) {
      const a = angleToCanvas(r.orientation);
      ctx.beginPath();
      ctx.moveTo(c.x + Math.cos(a) * rad, c.y + Math.sin(a) * rad);
      ctx.lineTo(c.x + Math.cos(a) * (rad + 6), c.y + Math.sin(a) * (rad + 6));
      ctx.stroke();
    }
    n++;
  }
  const b = rec.ball;
  if (b && Number.isFinite(b.x) && Number.isFinite(b.y)) {
    const c = worldToCanvas(t, b.x, b.y);
    const br = Math.max(4, ballRadiusMm * t.scale) + 3;
    ctx.beginPath();
    ctx.arc(c.x, c.y, br, 0, 2 * Math.PI);
    ctx.stroke();
    ctx.setLineDash([]);
    ctx.beginPath();
    ctx.moveTo(c.x - br - 3, c.y);
    ctx.lineTo(c.x - br + 2, c.y);
    ctx.moveTo(c.x + br - 2, c.y);
    ctx.lineTo(c.x + br + 3, c.y);
    ctx.stroke();
    n++;
  }
  ctx.restore();
  return n;
}

/** Arrow of 0.5 s of travel at the current velocity (mm/s). */
function drawVelocity(ctx: CanvasRenderingContext2D, t: FieldTransform, x: number, y: number, vx: number, vy: number, color: string, dash: number[] = []) {
  if (!Number.isFinite(vx) || !Number.isFinite(vy) || Math.hypot(vx, vy) < 20) return;
  const a = worldToCanvas(t, x, y);
  const b = worldToCanvas(t, x + vx * 0.5, y + vy * 0.5);
  arrow(ctx, a, b, color, 2, dash);
}

/** The commanded velocity in the field's frame (mm/s): the robot-frame command turned by the heading. */
export function commandVelocity(r: { orientation: number; command: Pick<NonNullable<Robot["command"]>, "forward_mps" | "left_mps"> | null }): { vx: number; vy: number } | null {
  const c = r.command;
  if (!c || !Number.isFinite(c.forward_mps) || !Number.isFinite(c.left_mps) || !Number.isFinite(r.orientation)) return null;
  const cos = Math.cos(r.orientation);
  const sin = Math.sin(r.orientation);
  return { vx: (c.forward_mps * cos - c.left_mps * sin) * 1000, vy: (c.forward_mps * sin + c.left_mps * cos) * 1000 };
}

/** Each commanded robot's command as an arrow of 0.5 s of travel. Returns the number drawn. */
function drawCommands(ctx: CanvasRenderingContext2D, t: FieldTransform, robots: readonly Robot[]): number {
  let n = 0;
  for (const r of robots) {
    const v = commandVelocity(r);
    if (!v || Math.hypot(v.vx, v.vy) < 20) continue;
    drawVelocity(ctx, t, r.x, r.y, v.vx, v.vy, COLORS.command);
    n++;
  }
  return n;
}

/**
 * The commands the replayed log sent (what the robots were told then), each as a dashed neutral
 * arrow of 0.5 s of travel from the robot as estimated now, turned by its heading like
 * drawCommands' arrows, so the two arrows of a robot compare directly. Returns the number drawn.
 */
export function drawRecordedCommands(ctx: CanvasRenderingContext2D, t: FieldTransform, robots: readonly Robot[], commands: readonly RecordedCommand[]): number {
  let n = 0;
  for (const c of commands) {
    const r = robots.find((x) => x.team === c.team && x.id === c.id);
    if (!r || !Number.isFinite(r.x) || !Number.isFinite(r.y)) continue;
    const v = commandVelocity({ orientation: r.orientation, command: c });
    if (!v || Math.hypot(v.vx, v.vy) < 20) continue;
    drawVelocity(ctx, t, r.x, r.y, v.vx, v.vy, COLORS.recorded, RECORDED_DASH);
    n++;
  }
  return n;
}

function arrow(ctx: CanvasRenderingContext2D, a: { x: number; y: number }, b: { x: number; y: number }, color: string, width: number, dash: number[] = []) {
  const ang = Math.atan2(b.y - a.y, b.x - a.x);
  const head = 8;
  ctx.save();
  ctx.strokeStyle = color;
  ctx.fillStyle = color;
  ctx.lineWidth = width;
  ctx.setLineDash(dash);
  ctx.beginPath();
  ctx.moveTo(a.x, a.y);
  ctx.lineTo(b.x, b.y);
  ctx.stroke();
  ctx.setLineDash([]);
  ctx.beginPath();
  ctx.moveTo(b.x, b.y);
  ctx.lineTo(b.x - head * Math.cos(ang - 0.4), b.y - head * Math.sin(ang - 0.4));
  ctx.lineTo(b.x - head * Math.cos(ang + 0.4), b.y - head * Math.sin(ang + 0.4));
  ctx.closePath();
  ctx.fill();
  ctx.restore();
}

function drawTrails(ctx: CanvasRenderingContext2D, t: FieldTransform, trails: ReadonlyMap<string, readonly { x: number; y: number }[]>) {
  ctx.save();
  ctx.lineWidth = 2;
  ctx.lineJoin = "round";
  for (const [key, pts] of trails) {
    if (pts.length < 2) continue;
    ctx.strokeStyle = key.startsWith("blue") ? "rgba(96,165,250,0.6)" : key.startsWith("yellow") ? "rgba(250,204,21,0.6)" : "rgba(249,115,22,0.7)";
    ctx.beginPath();
    pts.forEach((p, i) => {
      const c = worldToCanvas(t, p.x, p.y);
      if (i === 0) ctx.moveTo(c.x, c.y);
      else ctx.lineTo(c.x, c.y);
    });
    ctx.stroke();
  }
  ctx.restore();
}

function drawDesignated(ctx: CanvasRenderingContext2D, t: FieldTransform, p: { x: number; y: number }, command: string) {
  const c = worldToCanvas(t, p.x, p.y);
  const r = Math.max(8, 150 * t.scale);
  ctx.save();
  ctx.strokeStyle = command.includes("YELLOW") ? COLORS.yellow : command.includes("BLUE") ? "#60a5fa" : "#f8fafc";
  ctx.lineWidth = 2;
  ctx.setLineDash([4, 4]);
  ctx.beginPath();
  ctx.arc(c.x, c.y, r, 0, 2 * Math.PI);
  ctx.stroke();
  ctx.setLineDash([]);
  ctx.beginPath();
  ctx.moveTo(c.x - r * 0.5, c.y);
  ctx.lineTo(c.x + r * 0.5, c.y);
  ctx.moveTo(c.x, c.y - r * 0.5);
  ctx.lineTo(c.x, c.y + r * 0.5);
  ctx.stroke();
  ctx.restore();
}

function drawDrag(ctx: CanvasRenderingContext2D, t: FieldTransform, from: { x: number; y: number }, to: { x: number; y: number }) {
  arrow(ctx, worldToCanvas(t, from.x, from.y), worldToCanvas(t, to.x, to.y), "#f8fafc", 2.5);
}

/**
 * Marks at the robot's front: an armed kicker is a bar just ahead of the flat front (rose for
 * a flat kick, violet for a chip); the dribbler on is a cyan dot on the front edge.
 */
/** The ball held at the front: a small orange half-disc just outside the flat front. */
function drawBallContact(ctx: CanvasRenderingContext2D, c: { x: number; y: number }, heading: number, rad: number) {
  const d = rad * (FRONT_CUT + 0.12);
  const fx = c.x + Math.cos(heading) * d;
  const fy = c.y + Math.sin(heading) * d;
  ctx.beginPath();
  ctx.arc(fx, fy, Math.max(3, rad * 0.32), heading - Math.PI / 2, heading + Math.PI / 2, false);
  ctx.closePath();
  ctx.fillStyle = COLORS.ballContact;
  ctx.fill();
  ctx.lineWidth = 1;
  ctx.strokeStyle = COLORS.robotOutline;
  ctx.stroke();
}

/** A robot that does not answer its commands: a dashed red ring around it. */
function drawNoAnswer(ctx: CanvasRenderingContext2D, c: { x: number; y: number }, rad: number) {
  ctx.beginPath();
  ctx.arc(c.x, c.y, rad + Math.max(3, rad * 0.25), 0, 2 * Math.PI);
  ctx.setLineDash([3, 3]);
  ctx.lineWidth = Math.max(1.5, rad * 0.12);
  ctx.strokeStyle = COLORS.noAnswer;
  ctx.stroke();
  ctx.setLineDash([]);
}

function drawFrontMarks(
  ctx: CanvasRenderingContext2D,
  c: { x: number; y: number },
  heading: number,
  rad: number,
  kick: { speed_mps: number; chip: boolean } | null,
  dribbler: boolean,
) {
  const hx = Math.cos(heading);
  const hy = Math.sin(heading);
  if (kick) {
    const d = rad * (FRONT_CUT + 0.3);
    const fx = c.x + hx * d;
    const fy = c.y + hy * d;
    const half = rad * 0.55;
    ctx.beginPath();
    ctx.moveTo(fx + hy * half, fy - hx * half);
    ctx.lineTo(fx - hy * half, fy + hx * half);
    ctx.lineWidth = Math.max(2.5, rad * 0.22);
    ctx.lineCap = "round";
    ctx.strokeStyle = kick.chip ? COLORS.chip : COLORS.kick;
    ctx.stroke();
    ctx.lineCap = "butt";
  }
  if (dribbler) {
    ctx.beginPath();
    ctx.arc(c.x + hx * rad * FRONT_CUT, c.y + hy * rad * FRONT_CUT, Math.max(2.5, rad * 0.2), 0, 2 * Math.PI);
    ctx.fillStyle = COLORS.dribbler;
    ctx.fill();
    ctx.lineWidth = 1;
    ctx.strokeStyle = COLORS.robotOutline;
    ctx.stroke();
  }
}

/**
 * Every planned path as a dashed polyline robot -> waypoints: one stroke per team (cheap at
 * 22 robots and 60 Hz), small squares on the waypoints, the selected robot's path on top in
 * white. Returns the number of robots whose path was drawn.
 */
function drawPaths(ctx: CanvasRenderingContext2D, t: FieldTransform, robots: readonly Robot[], selected: RobotKey | null): number {
  let n = 0;
  let sel: Robot | null = null;
  ctx.save();
  ctx.lineWidth = 1.5;
  ctx.lineJoin = "round";
  ctx.setLineDash([7, 5]);
  for (const team of ["blue", "yellow"] as const) {
    ctx.beginPath();
    let any = false;
    for (const r of robots) {
      if (r.team !== team || !r.path) continue;
      if (sameRobot(r, selected)) {
        sel = r;
        continue;
      }
      if (tracePath(ctx, t, r, r.path) > 0) {
        any = true;
        n++;
      }
    }
    if (!any) continue;
    ctx.strokeStyle = team === "blue" ? COLORS.bluePath : COLORS.yellowPath;
    ctx.stroke();
  }
  if (sel) {
    ctx.beginPath();
    if (tracePath(ctx, t, sel, sel.path) > 0) {
      n++;
      ctx.lineWidth = 2.5;
      ctx.strokeStyle = COLORS.selected;
      ctx.stroke();
    }
  }
  ctx.setLineDash([]);
  // Waypoint marks.
  const s = Math.max(2, Math.min(4, 35 * t.scale));
  for (const r of robots) {
    const pts = r.path ? pathPoints(r.path) : null;
    if (!pts) continue;
    ctx.fillStyle = sameRobot(r, selected) ? COLORS.selected : r.team === "blue" ? COLORS.bluePath : COLORS.yellowPath;
    for (const p of pts) ctx.fillRect(t.originX + p.x * t.scale - s, t.originY - p.y * t.scale - s, 2 * s, 2 * s);
  }
  ctx.restore();
  return n;
}

const TAG_FONT = `system-ui, -apple-system, "Segoe UI", Roboto, sans-serif`;
/** Text widths of role tags per font size (a handful of entries; measureText is not free). */
const tagWidths = new Map<string, number>();

/** Font size of role tags in CSS px: larger in large-text mode, growing a little with zoom. */
export function roleTagPx(robotRadiusPx: number, largeText: boolean): number {
  const base = largeText ? 15 : 11;
  return Math.min(base + 8, Math.max(base, Math.round(robotRadiusPx * 0.75)));
}

/** Role tags (GK, ATK, ...) above-right of our robots. Returns the number drawn. */
function drawRoleTags(
  ctx: CanvasRenderingContext2D,
  t: FieldTransform,
  robots: readonly Robot[],
  ourTeam: Team | null,
  largeText: boolean,
): number {
  const rad = Math.max(MIN_ROBOT_PX, ROBOT_RADIUS_MM * t.scale);
  const px = roleTagPx(rad, largeText);
  const h = Math.round(px * 1.35);
  let n = 0;
  ctx.save();
  ctx.font = `700 ${px}px ${TAG_FONT}`;
  ctx.textAlign = "left";
  ctx.textBaseline = "middle";
  for (const r of robots) {
    if (ourTeam !== null && r.team !== ourTeam) continue;
    const tag = roleTag(r.role);
    if (!tag) continue;
    const key = `${px}|${tag}`;
    let w = tagWidths.get(key);
    if (w === undefined) {
      w = ctx.measureText(tag).width;
      if (tagWidths.size < 256) tagWidths.set(key, w);
    }
    const cx = t.originX + r.x * t.scale;
    const cy = t.originY - r.y * t.scale;
    const x = cx + rad * 0.7;
    const y = cy - rad * 0.7 - h;
    ctx.globalAlpha = r.lost ? 0.5 : 1;
    ctx.fillStyle = COLORS.roleBg;
    ctx.fillRect(x, y, w + px * 0.6, h);
    ctx.fillStyle = roleColor(r.role);
    ctx.fillText(tag, x + px * 0.3, y + h / 2 + px * 0.05);
    n++;
  }
  ctx.restore();
  return n;
}

/**
 * Robots a failed team-code play holds still: a solid red ring around each (the robot's own
 * no-answer ring is dashed); the play's name is in a banner over the field (stoppedBanners)
 * and in the tooltip. Returns the robots marked ("blue 3").
 */
function drawStopped(
  ctx: CanvasRenderingContext2D,
  t: FieldTransform,
  robots: readonly Robot[],
  strategy: { our_team: Team; stopped: readonly { id: number; play: string }[] },
): string[] {
  const out: string[] = [];
  const rad = Math.max(MIN_ROBOT_PX, ROBOT_RADIUS_MM * t.scale);
  ctx.save();
  ctx.lineWidth = Math.max(2.5, rad * 0.22);
  ctx.strokeStyle = COLORS.stopped;
  for (const s of strategy.stopped) {
    const r = robots.find((x) => x.team === strategy.our_team && x.id === s.id);
    if (!r || !Number.isFinite(r.x) || !Number.isFinite(r.y)) continue;
    const c = worldToCanvas(t, r.x, r.y);
    ctx.beginPath();
    ctx.arc(c.x, c.y, rad + Math.max(4, rad * 0.35), 0, 2 * Math.PI);
    ctx.stroke();
    out.push(`${r.team} ${r.id}`);
  }
  ctx.restore();
  return out;
}

/** One line per failed play over the field: "pass_drill failed: blue 1, 2 stopped" (two at most). */
export function stoppedBanners(strategy: { our_team: Team; stopped: readonly { id: number; play: string }[] }): string[] {
  const by = new Map<string, number[]>();
  for (const s of strategy.stopped) by.set(s.play, [...(by.get(s.play) ?? []), s.id]);
  const lines = [...by.entries()]
    .sort(([a], [b]) => a.localeCompare(b))
    .map(([play, ids]) => `${play} failed: ${strategy.our_team} ${ids.sort((a, b) => a - b).join(", ")} stopped`);
  return lines.length > 2 ? [lines[0]!, `${lines.length - 1} more plays failed: see the Code tab`] : lines;
}
