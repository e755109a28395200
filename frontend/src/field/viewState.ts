// The canvas currently showing the field, so tests (window.__touchline) and other code can
// map world coordinates to the same CSS pixels the renderer uses.

import type { Geometry } from "../api/types";
import { effectiveGeometry } from "./defaultGeometry";
import { fieldExtent, makeTransform, type FieldTransform } from "./transform";

export const FIELD_PADDING_PX = 12;

let canvas: HTMLCanvasElement | null = null;

export function registerFieldCanvas(el: HTMLCanvasElement | null): void {
  canvas = el;
}

export function transformFor(width: number, height: number, geometry: Geometry | null): FieldTransform {
  return makeTransform(width, height, fieldExtent(effectiveGeometry(geometry)), FIELD_PADDING_PX);
}

/** Transform of the registered canvas at its current CSS size, or null without a canvas. */
export function currentTransform(geometry: Geometry | null): FieldTransform | null {
  if (!canvas) return null;
  const rect = canvas.getBoundingClientRect();
  return transformFor(rect.width, rect.height, geometry);
}
