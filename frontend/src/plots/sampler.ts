// Feeds the live sample table from the app store (which the websocket client updates):
// one row per world message and one per health message, stamped with the arrival time.
// Runs outside React; plots read the table on animation frames.

import { useSyncExternalStore } from "react";
import type { AppStore } from "../store/appStore";
import { createStore } from "../store/createStore";
import { SampleTable } from "./ring";
import { healthSignals, worldSignals } from "./signals";

/** ~66 s of world rows at 60 Hz (plus health rows at 2 Hz). */
export const TABLE_CAPACITY = 4096;
export const samples = new SampleTable(TABLE_CAPACITY);

export function nowS(): number {
  return (performance.timeOrigin + performance.now()) / 1000;
}

export function startSampler(store: AppStore): () => void {
  let world = store.getState().world;
  let health = store.getState().health;
  return store.subscribe(() => {
    const s = store.getState();
    if (s.world !== world) {
      world = s.world;
      if (world) samples.append(nowS(), worldSignals(world));
    }
    if (s.health !== health) {
      health = s.health;
      if (health) samples.append(nowS(), healthSignals(health));
    }
  });
}

export interface PlotDef {
  id: number;
  keys: string[];
}

export interface PlotsState {
  plots: PlotDef[];
  windowS: number;
  paused: boolean;
  /** Right edge of the window while paused (Unix s). */
  pausedAt: number;
}

const LS_KEY = "touchline.plots.v1";

function load(): Partial<PlotsState> {
  try {
    const raw = typeof localStorage !== "undefined" ? localStorage.getItem(LS_KEY) : null;
    return raw ? (JSON.parse(raw) as Partial<PlotsState>) : {};
  } catch {
    return {};
  }
}

const saved = load();
let nextId = Math.max(0, ...(saved.plots ?? []).map((p) => p.id)) + 1;

export const plotsStore = createStore<PlotsState>({
  plots: saved.plots ?? [],
  windowS: saved.windowS ?? 10,
  paused: false,
  pausedAt: 0,
});

plotsStore.subscribe(() => {
  const s = plotsStore.getState();
  try {
    localStorage.setItem(LS_KEY, JSON.stringify({ plots: s.plots, windowS: s.windowS }));
  } catch {
    /* ignore */
  }
});

export function usePlots(): PlotsState {
  return useSyncExternalStore(plotsStore.subscribe, plotsStore.getState, plotsStore.getState);
}

export function addPlot(keys: string[] = []): number {
  const id = nextId++;
  plotsStore.setState((s) => ({ plots: [...s.plots, { id, keys }] }));
  return id;
}

export function removePlot(id: number): void {
  plotsStore.setState((s) => ({ plots: s.plots.filter((p) => p.id !== id) }));
}

export function addSignal(id: number, key: string): void {
  plotsStore.setState((s) => ({
    plots: s.plots.map((p) => (p.id === id && !p.keys.includes(key) ? { ...p, keys: [...p.keys, key] } : p)),
  }));
}

export function removeSignal(id: number, key: string): void {
  plotsStore.setState((s) => ({ plots: s.plots.map((p) => (p.id === id ? { ...p, keys: p.keys.filter((k) => k !== key) } : p)) }));
}

export function setPaused(paused: boolean): void {
  plotsStore.setState({ paused, pausedAt: nowS() });
}

export function togglePaused(): void {
  setPaused(!plotsStore.getState().paused);
}

export function setWindow(windowS: number): void {
  plotsStore.setState({ windowS: Math.max(1, Math.min(60, windowS)) });
}

/** The visible time range [t0, t1] of every plot (shared). */
export function visibleRange(): [number, number] {
  const s = plotsStore.getState();
  const t1 = s.paused ? s.pausedAt : nowS();
  return [t1 - s.windowS, t1];
}
