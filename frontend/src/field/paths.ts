// Pure: a robot's planned path (world mm waypoints, the last one its target) as a polyline
// on the canvas, and its length. Written against a minimal path sink so the field draws all
// paths of a team in one stroke (the canvas context is one) and the tests can record calls.

import type { Vec } from "../api/types";
import type { FieldTransform, Point } from "./transform";

export interface PathSink {
  moveTo(x: number, y: number): void;
  lineTo(x: number, y: number): void;
}

function finitePoint(p: unknown): p is Vec {
  return (
    typeof p === "object" &&
    p !== null &&
    Number.isFinite((p as Vec).x) &&
    Number.isFinite((p as Vec).y)
  );
}

/** The usable waypoints of a path: null when there is none (absent, empty, or all invalid). */
export function pathPoints(path: readonly Vec[] | null | undefined): readonly Vec[] | null {
  if (!Array.isArray(path) || path.length === 0) return null;
  // The common case allocates nothing.
  if (path.every(finitePoint)) return path;
  const ok = path.filter(finitePoint);
  return ok.length ? ok : null;
}

/**
 * Trace the polyline robot -> waypoints into `sink` in canvas px. Returns the number of
 * segments traced (0 when the robot has no usable path or its position is not finite).
 */
export function tracePath(sink: PathSink, t: FieldTransform, from: Vec, path: readonly Vec[] | null | undefined): number {
  const pts = pathPoints(path);
  if (!pts || !Number.isFinite(from.x) || !Number.isFinite(from.y)) return 0;
  // worldToCanvas inlined: no allocation per point at 60 Hz.
  const { originX: ox, originY: oy, scale: k } = t;
  sink.moveTo(ox + from.x * k, oy - from.y * k);
  for (const p of pts) sink.lineTo(ox + p.x * k, oy - p.y * k);
  return pts.length;
}

/** The waypoints of a path in canvas px, robot position first (for markers and tests). */
export function pathToCanvas(t: FieldTransform, from: Vec, path: readonly Vec[] | null | undefined): Point[] {
  const out: Point[] = [];
  tracePath({ moveTo: (x, y) => out.push({ x, y }), lineTo: (x, y) => out.push({ x, y }) }, t, from, path);
  return out;
}

/** Length in mm of robot -> waypoints (0 without a path). */
export function pathLengthMm(from: Vec, path: readonly Vec[] | null | undefined): number {
  const pts = pathPoints(path);
  if (!pts || !Number.isFinite(from.x) || !Number.isFinite(from.y)) return 0;
  let len = 0;
  let prev = from;
  for (const p of pts) {
    len += Math.hypot(p.x - prev.x, p.y - prev.y);
    prev = p;
  }
  return len;
}
