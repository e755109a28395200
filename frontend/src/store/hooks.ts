// React bindings for the app store. Components subscribe to slow slices only; the world
// (up to 60 Hz) is sampled at a throttled rate for the table.

import { useEffect, useState, useSyncExternalStore } from "react";
import type { World } from "../api/types";
import { appStore, type AppState } from "./appStore";

/** Subscribe to a slice; the selector must return a reference that is stable while unchanged. */
export function useAppState<T>(selector: (s: AppState) => T): T {
  return useSyncExternalStore(
    appStore.subscribe,
    () => selector(appStore.getState()),
    () => selector(appStore.getState()),
  );
}

/** The latest world, re-rendered at most every `intervalMs` (default 5 Hz). */
export function useThrottledWorld(intervalMs = 200): World | null {
  const [world, setWorld] = useState<World | null>(() => appStore.getState().world);
  useEffect(() => {
    let last = appStore.getState().world;
    setWorld(last);
    const timer = setInterval(() => {
      const w = appStore.getState().world;
      if (w !== last) {
        last = w;
        setWorld(w);
      }
    }, intervalMs);
    return () => clearInterval(timer);
  }, [intervalMs]);
  return world;
}

/** Re-render every `ms` while `active` (for countdowns). */
export function useTicker(active: boolean, ms = 500): number {
  const [now, setNow] = useState(() => Date.now());
  useEffect(() => {
    if (!active) return;
    const timer = setInterval(() => setNow(Date.now()), ms);
    return () => clearInterval(timer);
  }, [active, ms]);
  return now;
}
