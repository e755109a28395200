// The canvas currently showing the field and the user's view of it (zoom and pan), so tests
// (window.__touchline) and other code map world coordinates to the same CSS pixels the
// renderer uses.

import type { Geometry } from "../api/types";
import { effectiveGeometry } from "./defaultGeometry";
import { applyView, fieldExtent, makeTransform, zoomAround, type FieldTransform, type View } from "./transform";

export const FIELD_PADDING_PX = 12;

let canvas: HTMLCanvasElement | null = null;
let view: View = { zoom: 1, cx: 0, cy: 0 };
/** Increases with every view change (the canvas redraws when it changes). */
export let viewVersion = 0;

export function registerFieldCanvas(el: HTMLCanvasElement | null): void {
  canvas = el;
}

export function getView(): View {
  return view;
}

export function setView(v: View): void {
  view = v;
  viewVersion++;
}

export function fitView(): void {
  setView({ zoom: 1, cx: 0, cy: 0 });
}

/** Fitted transform with the user's zoom and pan applied. */
export function transformFor(width: number, height: number, geometry: Geometry | null): FieldTransform {
  return applyView(makeTransform(width, height, fieldExtent(effectiveGeometry(geometry)), FIELD_PADDING_PX), view);
}

/** Zoom by `factor` keeping the world point under canvas pixel (px, py) in place. */
export function zoomAt(width: number, height: number, geometry: Geometry | null, px: number, py: number, factor: number): void {
  const base = makeTransform(width, height, fieldExtent(effectiveGeometry(geometry)), FIELD_PADDING_PX);
  setView(zoomAround(base, view, px, py, factor));
}

/** Pan by a drag of (dx, dy) CSS px. */
export function panBy(dx: number, dy: number, scalePxPerMm: number): void {
  setView({ ...view, cx: view.cx - dx / scalePxPerMm, cy: view.cy + dy / scalePxPerMm });
}

/** Transform of the registered canvas at its current CSS size, or null without a canvas. */
export function currentTransform(geometry: Geometry | null): FieldTransform | null {
  if (!canvas) return null;
  const rect = canvas.getBoundingClientRect();
  return transformFor(rect.width, rect.height, geometry);
}
