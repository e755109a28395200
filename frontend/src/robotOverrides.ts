// Pure: per-robot controller and filter overrides in the parameter values
// (`control.robots["blue/3"].algorithm`, `filters.robot_overrides["blue/3"]`) and the PATCH
// bodies that set or remove them (docs/api.md: a null value removes a robot's override).

import type { ParamValues, RobotKey } from "./api/types";

export const ALGORITHMS = [
  { value: "algorithm1", label: "Algorithm 1" },
  { value: "algorithm2", label: "Algorithm 2" },
  { value: "proportional", label: "Proportional" },
] as const;

export const FILTERS = [
  { value: "raw", label: "Raw" },
  { value: "median", label: "Median" },
  { value: "paper", label: "Paper" },
  { value: "kalman", label: "Kalman" },
  { value: "adaptive", label: "Adaptive" },
] as const;

export function labelOf(options: readonly { value: string; label: string }[], v: string | null | undefined): string {
  if (!v) return "—";
  return options.find((o) => o.value === v)?.label ?? v;
}

/** "blue/3": the key of the per-robot maps. */
export function overrideKey(k: RobotKey): string {
  return `${k.team}/${k.id}`;
}

function obj(v: unknown): Record<string, unknown> | null {
  return typeof v === "object" && v !== null && !Array.isArray(v) ? (v as Record<string, unknown>) : null;
}

function str(v: unknown): string | null {
  return typeof v === "string" && v ? v : null;
}

export interface RobotOverrides {
  /** Per-robot controller, or null (the default applies). */
  algorithm: string | null;
  defaultAlgorithm: string | null;
  /** Per-robot filter, or null (filters.robot applies). */
  filter: string | null;
  defaultFilter: string | null;
}

export function robotOverrides(values: ParamValues | null | undefined, k: RobotKey): RobotOverrides {
  const control = obj(values?.control);
  const filters = obj(values?.filters);
  const key = overrideKey(k);
  return {
    algorithm: str(obj(obj(control?.robots)?.[key])?.algorithm),
    defaultAlgorithm: str(control?.default_algorithm),
    filter: str(obj(filters?.robot_overrides)?.[key]),
    defaultFilter: str(filters?.robot),
  };
}

/**
 * PATCH body choosing a robot's controller ("" or null: back to the default). A robot override
 * that also sets other fields (v / w / K / a) keeps them: only its algorithm becomes null.
 */
export function controllerPatch(values: ParamValues | null | undefined, k: RobotKey, algorithm: string | null): Record<string, unknown> {
  const key = overrideKey(k);
  let entry: unknown;
  if (algorithm) {
    entry = { algorithm };
  } else {
    const cur = obj(obj(obj(values?.control)?.robots)?.[key]);
    const others = cur ? Object.entries(cur).filter(([f, v]) => f !== "algorithm" && v !== null && v !== undefined) : [];
    entry = others.length ? { ...Object.fromEntries(others), algorithm: null } : null;
  }
  return { control: { robots: { [key]: entry } } };
}

/** PATCH body choosing a robot's filter ("" or null: back to `filters.robot`). */
export function filterPatch(k: RobotKey, filter: string | null): Record<string, unknown> {
  return { filters: { robot_overrides: { [overrideKey(k)]: filter ? filter : null } } };
}

/** Plot signal names of one robot (see plots/signals.ts). */
export function robotSignal(k: RobotKey, field: string): string {
  return `robot.${k.team}.${k.id}.${field}`;
}

/** Plots the "Plot C, x* vs x and speeds" button opens, one signal list per plot. */
export function controllerPlots(k: RobotKey): string[][] {
  return [
    [robotSignal(k, "control.c_estimate")],
    [robotSignal(k, "control.ref_x_m"), robotSignal(k, "control.x_m")],
    [robotSignal(k, "control.cmd_speed_mps"), robotSignal(k, "control.meas_speed_mps")],
  ];
}

/** Plots the "Plot raw vs filtered x/y" button opens. */
export function filterPlots(k: RobotKey): string[][] {
  return [
    [robotSignal(k, "raw_x"), robotSignal(k, "x")],
    [robotSignal(k, "raw_y"), robotSignal(k, "y")],
  ];
}
