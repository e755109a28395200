// Pure: the compute engine's health (health.engine) as rows for the Health tab and a one-line
// summary. Missing numbers show as "—" (an older or newer backend may omit some).

import type { EngineHealth } from "../api/types";
import { fmtFixed } from "../format";

export interface EngineRow {
  key: string;
  label: string;
  value: string;
  /** Worth a look: errors, timeouts, crashes, fallbacks, no worker running... */
  warn: boolean;
}

function n(v: unknown): number | null {
  return typeof v === "number" && Number.isFinite(v) ? v : null;
}

function count(v: unknown): string {
  const x = n(v);
  return x === null ? "—" : String(Math.round(x));
}

function ms(v: unknown): string {
  const x = n(v);
  return x === null ? "—" : `${fmtFixed(x, x < 10 ? 2 : 1)} ms`;
}

function positive(v: unknown): boolean {
  const x = n(v);
  return x !== null && x > 0;
}

/** The engine in use, or null when it is off (health.engine null or absent). */
export function engineOf(h: { engine?: EngineHealth | null } | null | undefined): EngineHealth | null {
  const e = h?.engine;
  return typeof e === "object" && e !== null ? e : null;
}

export function engineRows(e: EngineHealth): EngineRow[] {
  const p99 = n(e.latency_p99_ms);
  return [
    { key: "kind", label: "engine", value: String(e.kind ?? "—"), warn: false },
    { key: "function", label: "function", value: e.function || "—", warn: false },
    { key: "rate", label: "calls/s", value: n(e.calls_per_s) === null ? "—" : fmtFixed(e.calls_per_s, 1), warn: false },
    { key: "latency", label: "latency mean / p99", value: `${ms(e.latency_mean_ms)} / ${ms(e.latency_p99_ms)}`, warn: p99 !== null && p99 > 50 },
    { key: "calls", label: "calls / ok", value: `${count(e.calls)} / ${count(e.ok)}`, warn: false },
    { key: "errors", label: "errors", value: count(e.errors), warn: positive(e.errors) },
    { key: "timeouts", label: "timeouts", value: count(e.timeouts), warn: positive(e.timeouts) },
    { key: "crashes", label: "crashes", value: count(e.crashes), warn: positive(e.crashes) },
    { key: "restarts", label: "restarts", value: count(e.restarts), warn: positive(e.restarts) },
    { key: "start_failures", label: "start failures", value: count(e.start_failures), warn: positive(e.start_failures) },
    {
      key: "workers",
      label: "workers busy / idle",
      value: `${count(e.workers)}: ${count(e.busy)} busy / ${count(e.idle)} idle`,
      // All busy is normal (the strategy keeps one call in flight); no worker at all is not.
      warn: n(e.workers) === 0,
    },
    { key: "fallbacks", label: "fallbacks to numpy", value: count(e.fallbacks), warn: positive(e.fallbacks) },
  ];
}

/** Short status for the health summary: "off", "numpy 20/s", "octave 18/s · 3 err · 2 fallbacks". */
export function engineSummary(e: EngineHealth | null): { text: string; warn: boolean } {
  if (!e) return { text: "off", warn: false };
  const parts = [`${e.kind ?? "engine"} ${n(e.calls_per_s) === null ? "—" : fmtFixed(e.calls_per_s, 0)}/s`];
  const bad = (n(e.errors) ?? 0) + (n(e.timeouts) ?? 0) + (n(e.crashes) ?? 0);
  if (bad > 0) parts.push(`${bad} err`);
  const fb = n(e.fallbacks) ?? 0;
  if (fb > 0) parts.push(`${fb} fallback${fb === 1 ? "" : "s"}`);
  return { text: parts.join(" · "), warn: bad > 0 || fb > 0 || Boolean(e.last_error) };
}
