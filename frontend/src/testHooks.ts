// Read-only hooks for end-to-end tests: window.__touchline.

import type { Player, ReplayClock, StrategyState, Team, Vec, World } from "./api/types";
import { canvasToWorld, worldToCanvas, type Point } from "./field/transform";
import { currentTransform } from "./field/viewState";
import { appStore } from "./store/appStore";
import { fieldStats } from "./components/FieldView";
import { plotInfo, plotStats } from "./components/PlotsPanel";
import { plotNow, samples, visibleRange } from "./plots/sampler";

export interface TouchlineTestApi {
  /** World mm -> CSS px relative to the field canvas's top-left corner. */
  worldToScreen(x_mm: number, y_mm: number): Point;
  /** CSS px relative to the canvas's top-left -> world mm. */
  screenToWorld(x_px: number, y_px: number): Point;
  getWorld(): World | null;
  getSelected(): { team: string; id: number } | null;
  /** Frame counters: field rAF callbacks and draws, plot loop frames and draws. */
  stats(): {
    t: number; fieldRafs: number; fieldDraws: number; plotFrames: number; plotDraws: number; sampleRows: number;
    /** Filtered robots and raw detections (robots + balls) the last field frame drew. */
    robotsDrawn: number; rawDrawn: number;
    /** Robots whose planned path / role tag the last field frame drew. */
    pathsDrawn: number; rolesDrawn: number;
    /** The ball placement mark the last field frame drew (world mm), null when none. */
    designatedDrawn: { x: number; y: number } | null;
    /** Objects (robots + ball) of the recorded estimate the last field frame drew (replay). */
    recordedDrawn: number;
    /** Our robots the last field frame marked as stopped by a failed team-code play ("blue 3"). */
    stoppedDrawn: string[];
    /** Command arrows the last field frame drew (in replay: what control would command now). */
    commandsDrawn: number;
    recordedCommandsDrawn: number;
  };
  /** The strategy's state in the latest world (null before the station reports one). */
  strategy(): StrategyState | null;
  /** Role of every robot in the latest world (null: none); `ours` keeps our team's only. */
  roles(ours?: boolean): { team: Team; id: number; role: string | null }[];
  /** Planned path of every robot in the latest world (null: none). */
  paths(): { team: Team; id: number; path: Vec[] | null }[];
  /** Kicker armed / dribbler on per robot in the latest world. */
  actuators(): { team: Team; id: number; kick: { speed_mps: number; chip: boolean } | null; dribbler: boolean }[];
  /** What each live plot shows: its signals, the newest x drawn (Unix s) and the point count. */
  plots(): { id: number; keys: string[]; lastX: number; points: number }[];
  /** Every signal name the plots can show. */
  signals(): string[];
  /** The log player's state (null before the first snapshot). */
  player(): Player | null;
  /** The replay clock of the latest world (null when live). */
  replay(): ReplayClock | null;
  /** The plots' "now" (the playhead while replaying) and their visible range (Unix s). */
  plotTime(): { now: number; range: [number, number] };
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
    stats: () => ({
      t: performance.now(),
      fieldRafs: fieldStats.rafs,
      fieldDraws: fieldStats.draws,
      plotFrames: plotStats.frames,
      plotDraws: plotStats.draws,
      sampleRows: samples.rows,
      robotsDrawn: fieldStats.robotsDrawn,
      rawDrawn: fieldStats.rawDrawn,
      pathsDrawn: fieldStats.pathsDrawn,
      rolesDrawn: fieldStats.rolesDrawn,
      designatedDrawn: fieldStats.designatedDrawn,
      recordedDrawn: fieldStats.recordedDrawn,
      stoppedDrawn: [...fieldStats.stoppedDrawn],
      commandsDrawn: fieldStats.commandsDrawn,
      recordedCommandsDrawn: fieldStats.recordedCommandsDrawn,
    }),
    strategy: () => appStore.getState().world?.strategy ?? null,
    roles: (ours = false) => {
      const w = appStore.getState().world;
      const team = w?.strategy?.our_team ?? null;
      return (w?.robots ?? [])
        .filter((r) => !ours || team === null || r.team === team)
        .map((r) => ({ team: r.team, id: r.id, role: r.role ?? null }));
    },
    paths: () => (appStore.getState().world?.robots ?? []).map((r) => ({ team: r.team, id: r.id, path: r.path ?? null })),
    actuators: () =>
      (appStore.getState().world?.robots ?? []).map((r) => ({ team: r.team, id: r.id, kick: r.kick ?? null, dribbler: r.dribbler === true })),
    plots: () => plotInfo(),
    signals: () => samples.keys(),
    player: () => appStore.getState().player,
    replay: () => appStore.getState().world?.replay ?? null,
    plotTime: () => ({ now: plotNow(), range: visibleRange() }),
  });
  Object.defineProperty(window, "__touchline", {
    value: api,
    writable: false,
    configurable: true,
    enumerable: false,
  });
}
