// Pure logic of the replay timeline: time formatting, position <-> pixel mapping, marker
// layout, speeds, and which event is next.

import type { PlayerEvent } from "../api/types";

export type EventKind = PlayerEvent["kind"];

/** The speeds the page offers (0 = as fast as possible, "max"), slowest first; 0 is last. */
export const SPEEDS: readonly number[] = [0.1, 0.25, 0.5, 1, 2, 5, 10, 0];

export function speedLabel(speed: number): string {
  return speed === 0 ? "max" : `${speed}×`;
}

/** The next speed up (+1) or down (-1) in SPEEDS; "max" is above 10. Unknown speeds snap to the nearest. */
export function nextSpeed(speed: number, dir: 1 | -1): number {
  const order = SPEEDS; // 0.1 .. 10, then 0 (max)
  let i = order.indexOf(speed);
  if (i < 0) {
    // nearest listed speed below (dir +1) or above (dir -1) the given one
    const finite = order.filter((s) => s > 0);
    if (dir > 0) {
      const up = finite.find((s) => s > speed);
      return up ?? 0;
    }
    const down = [...finite].reverse().find((s) => s < speed);
    return down ?? (finite[0] as number);
  }
  i = Math.max(0, Math.min(order.length - 1, i + dir));
  return order[i] as number;
}

/** `m:ss.s` (tenths truncated, never rounded up past the duration). */
export function fmtPosition(s: number): string {
  if (!Number.isFinite(s) || s < 0) s = 0;
  const tenths = Math.floor(s * 10 + 1e-6);
  const m = Math.floor(tenths / 600);
  const rest = tenths - m * 600;
  const sec = Math.floor(rest / 10);
  return `${m}:${String(sec).padStart(2, "0")}.${rest % 10}`;
}

/** `m:ss` of a duration (rounded up: a 59.5 s log lasts 1:00). */
export function fmtDuration(s: number): string {
  if (!Number.isFinite(s) || s < 0) s = 0;
  const a = Math.ceil(s - 1e-6);
  return `${Math.floor(a / 60)}:${String(a % 60).padStart(2, "0")}`;
}

/** Local wall time `HH:MM:SS` of a Unix time (s), or "" when unknown. */
export function fmtWallTime(tUnix: number | null | undefined): string {
  if (tUnix === null || tUnix === undefined || !Number.isFinite(tUnix) || tUnix <= 0) return "";
  const d = new Date(tUnix * 1000);
  const p = (n: number) => String(n).padStart(2, "0");
  return `${p(d.getHours())}:${p(d.getMinutes())}:${p(d.getSeconds())}`;
}

/** Position (s) -> x (px) on a bar `width` px wide; clamped to the bar. */
export function positionToX(position: number, duration: number, width: number): number {
  if (!(duration > 0) || !(width > 0)) return 0;
  return Math.max(0, Math.min(width, (position / duration) * width));
}

/** x (px, from the bar's left edge) -> position (s); clamped to [0, duration]. */
export function xToPosition(x: number, duration: number, width: number): number {
  if (!(duration > 0) || !(width > 0)) return 0;
  return Math.max(0, Math.min(duration, (x / width) * duration));
}

export interface MarkerSlot {
  event: PlayerEvent;
  /** Left edge in % of the bar. */
  pct: number;
  /** Row (0 = on the bar's top edge): markers closer than `minGapPct` stack. */
  row: number;
}

/**
 * Where each event's marker goes, in % of the bar (so it survives resizes). Markers closer
 * than `minGapPct` to the previous one in a row go to the next row (at most `rows` rows; the
 * rest share the last row).
 */
export function layoutMarkers(events: readonly PlayerEvent[], duration: number, minGapPct = 0.6, rows = 3): MarkerSlot[] {
  if (!(duration > 0)) return [];
  const sorted = events
    .filter((e) => Number.isFinite(e.t_s))
    .slice()
    .sort((a, b) => a.t_s - b.t_s);
  const lastInRow: number[] = [];
  return sorted.map((event) => {
    const pct = Math.max(0, Math.min(100, (event.t_s / duration) * 100));
    let row = 0;
    while (row < rows - 1 && lastInRow[row] !== undefined && pct - (lastInRow[row] as number) < minGapPct) row++;
    lastInRow[row] = pct;
    return { event, pct, row };
  });
}

/**
 * The first event after (`next`) or before (`prev`) the position, of a kind (or any): what a
 * jump lands on. Events within `eps` s of the position do not count (the playhead is on them).
 */
export function findEvent(
  events: readonly PlayerEvent[],
  position: number,
  direction: "next" | "prev",
  kind: EventKind | "any" = "any",
  eps = 0.05,
): PlayerEvent | null {
  let best: PlayerEvent | null = null;
  for (const e of events) {
    if (kind !== "any" && e.kind !== kind) continue;
    if (direction === "next") {
      if (e.t_s > position + eps && (best === null || e.t_s < best.t_s)) best = e;
    } else if (e.t_s < position - eps && (best === null || e.t_s > best.t_s)) best = e;
  }
  return best;
}

/** "NORMAL_FIRST_HALF" -> "normal first half". */
export function prettyStage(stage: string): string {
  return stage.replace(/_/g, " ").toLowerCase();
}

/** The file name of a path (either separator). */
export function baseName(path: string | null | undefined): string {
  if (!path) return "";
  const parts = path.split(/[\\/]/);
  return parts[parts.length - 1] ?? path;
}

/** Bytes as MB with one decimal. */
export function fmtMB(bytes: number): string {
  return `${(Math.max(0, bytes) / 1e6).toFixed(1)} MB`;
}
