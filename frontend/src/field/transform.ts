// World (SSL vision frame: mm, x right, y up, origin at the field centre) <-> canvas
// (CSS px, origin at the canvas's top-left, y down). Pure; no DOM.

export interface Point {
  x: number;
  y: number;
}

/** Half sizes of the drawn area in mm (field plus boundary), centred on the origin. */
export interface FieldExtent {
  halfX: number;
  halfY: number;
}

export interface FieldTransform {
  /** CSS px per mm. */
  scale: number;
  /** Canvas position (CSS px) of the world origin. */
  originX: number;
  originY: number;
  width: number;
  height: number;
}

export function fieldExtent(g: {
  field_length: number;
  field_width: number;
  boundary_width: number;
  goal_depth?: number;
}): FieldExtent {
  const boundary = Math.max(0, g.boundary_width);
  // The goals stick out behind the goal line; keep them visible even with a thin boundary.
  const goal = Math.max(0, g.goal_depth ?? 0);
  return {
    halfX: g.field_length / 2 + Math.max(boundary, goal),
    halfY: g.field_width / 2 + boundary,
  };
}

/**
 * Fit the extent into a width x height canvas with `padding` CSS px on every side,
 * keeping the aspect ratio and centring the field.
 */
export function makeTransform(
  width: number,
  height: number,
  extent: FieldExtent,
  padding = 12,
): FieldTransform {
  const w = Math.max(1, width);
  const h = Math.max(1, height);
  const availX = Math.max(1, w - 2 * padding);
  const availY = Math.max(1, h - 2 * padding);
  const scale = Math.max(1e-6, Math.min(availX / (2 * extent.halfX), availY / (2 * extent.halfY)));
  return { scale, originX: w / 2, originY: h / 2, width: w, height: h };
}

export function worldToCanvas(t: FieldTransform, x: number, y: number): Point {
  return { x: t.originX + x * t.scale, y: t.originY - y * t.scale };
}

export function canvasToWorld(t: FieldTransform, px: number, py: number): Point {
  return { x: (px - t.originX) / t.scale, y: (t.originY - py) / t.scale };
}

/** A world length (mm) in CSS px. */
export function lengthToCanvas(t: FieldTransform, mm: number): number {
  return mm * t.scale;
}

/** A world angle (rad, counter-clockwise, y up) as a canvas angle (clockwise, y down). */
export function angleToCanvas(rad: number): number {
  return -rad;
}

/** The user's view: zoom relative to the fitted field and the world point at the centre. */
export interface View {
  zoom: number;
  cx: number;
  cy: number;
}

export const MIN_ZOOM = 0.5;
export const MAX_ZOOM = 25;

/** Apply a view to a fitted transform (whose origin is at the canvas centre). */
export function applyView(base: FieldTransform, v: View): FieldTransform {
  const scale = base.scale * v.zoom;
  return {
    ...base,
    scale,
    originX: base.width / 2 - v.cx * scale,
    originY: base.height / 2 + v.cy * scale,
  };
}

/** The view after zooming by `factor` about canvas pixel (px, py): that world point stays put. */
export function zoomAround(base: FieldTransform, v: View, px: number, py: number, factor: number): View {
  const before = applyView(base, v);
  const p = canvasToWorld(before, px, py);
  const zoom = Math.max(MIN_ZOOM, Math.min(MAX_ZOOM, v.zoom * factor));
  const scale = base.scale * zoom;
  // px = w/2 - cx*scale + p.x*scale  ->  cx = p.x - (px - w/2)/scale
  return { zoom, cx: p.x - (px - base.width / 2) / scale, cy: p.y + (py - base.height / 2) / scale };
}
