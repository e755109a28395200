// UI state that is not live data: the open tab, field layers, pending field actions, options.
// Kept outside React like the app store, so the field canvas can read it every frame.

import { useSyncExternalStore } from "react";
import { ALL_LAYERS as DEFAULT_LAYERS, type DrawLayers } from "../field/draw";
import type { RefereeCommand } from "../api/types";
import { createStore } from "./createStore";

export type Tab = "robots" | "params" | "plots" | "referee" | "health" | "code" | "evaluate";
export const TABS: { key: Tab; label: string }[] = [
  { key: "robots", label: "Robots" },
  { key: "params", label: "Params" },
  { key: "plots", label: "Plots" },
  { key: "referee", label: "Referee" },
  { key: "health", label: "Health" },
  { key: "code", label: "Code" },
  { key: "evaluate", label: "Evaluate" },
];

/** The field layers the user can toggle: exactly what the field drawing takes. */
export type Layers = DrawLayers;

export const LAYER_LABELS: { key: keyof Layers; label: string; help: string }[] = [
  { key: "filtered", label: "Filtered objects", help: "robots and ball from the world model" },
  { key: "raw", label: "Raw detections", help: "per camera, coloured by camera" },
  { key: "velocity", label: "Velocity vectors", help: "0.5 s of travel at the current velocity" },
  { key: "targets", label: "Targets", help: "each robot's target (a straight line to it when no path is planned)" },
  { key: "paths", label: "Planned paths", help: "the strategy's path of each robot through its waypoints, dashed" },
  { key: "roles", label: "Role tags", help: "GK, ATK, DEF, ... next to our robots (full name in the robot panel)" },
  { key: "trails", label: "Trails", help: "last 3 s of positions" },
  { key: "referee", label: "Referee marks", help: "designated position of ball placement" },
  {
    key: "kicks",
    label: "Kicks",
    help: "a kick in progress: dashed line to where the ball is predicted to stop, a cross there, the kicker and the kick speed",
  },
  {
    key: "commands",
    label: "Commands (replay)",
    help: "in replay: the velocity control would command now for each robot (an arrow of 0.5 s of travel; nothing is sent), beside the command the log sent it then (dashed)",
  },
  {
    key: "recorded",
    label: "Recorded estimate",
    help: "in replay: the robots and ball as the log's own tracker had them (dashed rings), beside today's filter output",
  },
];

export interface UiState {
  tab: Tab;
  layers: Layers;
  largeText: boolean;
  help: boolean;
  /** Ball placement waiting for a click on the field: the referee command to give. */
  placing: RefereeCommand | null;
}

const LS_KEY = "touchline.ui.v1";

function load(): Partial<UiState> {
  try {
    const raw = typeof localStorage !== "undefined" ? localStorage.getItem(LS_KEY) : null;
    return raw ? (JSON.parse(raw) as Partial<UiState>) : {};
  } catch {
    return {};
  }
}

const saved = load();
/** The layers a first visit shows: the field drawing's defaults. */
export const defaultLayers: Layers = { ...DEFAULT_LAYERS };

export const uiStore = createStore<UiState>({
  tab: saved.tab ?? "robots",
  layers: { ...defaultLayers, ...(saved.layers ?? {}) },
  largeText: saved.largeText ?? false,
  help: false,
  placing: null,
});

uiStore.subscribe(() => {
  const s = uiStore.getState();
  try {
    localStorage.setItem(LS_KEY, JSON.stringify({ tab: s.tab, layers: s.layers, largeText: s.largeText }));
  } catch {
    /* private mode */
  }
});

export function useUi<T>(sel: (s: UiState) => T): T {
  return useSyncExternalStore(
    uiStore.subscribe,
    () => sel(uiStore.getState()),
    () => sel(uiStore.getState()),
  );
}

export function setTab(tab: Tab): void {
  uiStore.setState({ tab });
}

export function toggleLayer(k: keyof Layers): void {
  uiStore.setState((s) => ({ layers: { ...s.layers, [k]: !s.layers[k] } }));
}
