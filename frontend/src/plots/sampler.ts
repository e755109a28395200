// Feeds the live sample table from the app store (which the websocket client updates):
// one row per world message and one per health message, stamped with the arrival time.
// While a log replays, world rows are stamped with the log's wall time at the playhead
// (world.replay.t_unix) and the plots' right edge is the playhead; the table starts again
// when the replay jumps (a new epoch: open, seek) or the source switches live <-> log, so
// time never goes backwards in a plot. Health rows (the live station's) are not sampled
// during a replay: they belong to another time line.
// Runs outside React; plots read the table on animation frames.

import { useSyncExternalStore } from "react";
import type { AppStore } from "../store/appStore";
import { createStore } from "../store/createStore";
import { getPlayerHistory } from "../api/http";
import type { PlayerHistory } from "../api/types";
import { SampleTable } from "./ring";
import { healthSignals, worldSignals } from "./signals";

/** ~66 s of world rows at 60 Hz (plus health rows at 2 Hz). */
export const TABLE_CAPACITY = 4096;
export const samples = new SampleTable(TABLE_CAPACITY);

export function nowS(): number {
  return (performance.timeOrigin + performance.now()) / 1000;
}

/** The replay's playhead (log wall time, Unix s) while a log plays, else null. */
let playhead: number | null = null;

export function replayPlayhead(): number | null {
  return playhead;
}

/** The plots' "now": the playhead while replaying, else the wall clock. */
export function plotNow(): number {
  return playhead ?? nowS();
}

/** The plots' past after a seek (the world model re-run over the log before the playhead). */
export type HistoryFetch = (seconds: number) => Promise<PlayerHistory>;

export function startSampler(store: AppStore, history: HistoryFetch = getPlayerHistory): () => void {
  let world = store.getState().world;
  let health = store.getState().health;
  /** "live", or "log:<epoch>": a change starts the table again. */
  let timeline: string | null = null;
  let lastT = Number.NaN;
  playhead = world?.replay?.t_unix ?? null;
  return store.subscribe(() => {
    const s = store.getState();
    if (s.world !== world) {
      world = s.world;
      if (world) {
        const r = world.replay ?? null;
        const key = r ? `log:${r.epoch}` : "live";
        const t = r ? r.t_unix : nowS();
        // A new time line, or a replay stepping back without a new epoch: start again.
        const back = r !== null && Number.isFinite(lastT) && t < lastT - 1e-3;
        if ((timeline !== null && key !== timeline) || back) {
          samples.clear();
          // a frozen window would show nothing of the new time line
          if (plotsStore.getState().paused) plotsStore.setState({ pausedAt: t });
        }
        const fresh = r !== null && key !== timeline;
        timeline = key;
        lastT = t;
        if (fresh) {
          // a new replay time line: fill the plot window with what came before the playhead
          history(plotsStore.getState().windowS)
            .then((h) => {
              if (timeline === `log:${h.epoch}`) {
                samples.prepend(h.samples.map((s) => [s.t_unix, worldSignals(s.world)] as const));
              }
            })
            .catch(() => undefined); // a replay without its past still plays
        }
        playhead = r ? t : null;
        samples.append(t, worldSignals(world));
      }
    }
    if (s.health !== health) {
      health = s.health;
      if (health && playhead === null) samples.append(nowS(), healthSignals(health));
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
  /** Right edge of the window while paused (Unix s; the log's time while replaying). */
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
  plotsStore.setState({ paused, pausedAt: plotNow() });
}

export function togglePaused(): void {
  setPaused(!plotsStore.getState().paused);
}

export function setWindow(windowS: number): void {
  plotsStore.setState({ windowS: Math.max(1, Math.min(60, windowS)) });
}

/** The visible time range [t0, t1] of every plot (shared); t1 is the playhead while replaying. */
export function visibleRange(): [number, number] {
  const s = plotsStore.getState();
  const t1 = s.paused ? s.pausedAt : plotNow();
  return [t1 - s.windowS, t1];
}
