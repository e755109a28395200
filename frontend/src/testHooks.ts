// Read-only hooks for end-to-end tests: window.__touchline.

import type { World } from "./api/types";
import { canvasToWorld, worldToCanvas, type Point } from "./field/transform";
import { currentTransform } from "./field/viewState";
import { appStore } from "./store/appStore";

export interface TouchlineTestApi {
  /** World mm -> CSS px relative to the field canvas's top-left corner. */
  worldToScreen(x_mm: number, y_mm: number): Point;
  /** CSS px relative to the canvas's top-left -> world mm. */
  screenToWorld(x_px: number, y_px: number): Point;
  getWorld(): World | null;
  getSelected(): { team: string; id: number } | null;
}

declare global {
  interface Window {
    __touchline?: TouchlineTestApi;
  }
}

export function installTestHooks(): void {
  const api: TouchlineTestApi = Object.freeze({
    worldToScreen(x_mm: number, y_mm: number): Point {
      const t = currentTransform(appStore.getState().geometry);
      if (!t) throw new Error("field canvas is not mounted");
      return worldToCanvas(t, x_mm, y_mm);
    },
    screenToWorld(x_px: number, y_px: number): Point {
      const t = currentTransform(appStore.getState().geometry);
      if (!t) throw new Error("field canvas is not mounted");
      return canvasToWorld(t, x_px, y_px);
    },
    getWorld: () => appStore.getState().world,
    getSelected: () => appStore.getState().selected,
  });
  Object.defineProperty(window, "__touchline", {
    value: api,
    writable: false,
    configurable: true,
    enumerable: false,
  });
}
