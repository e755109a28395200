// Pure: every numeric signal of a world / health message as a flat map "path" -> number.
// Derived generically from the numeric fields, so fields added by the backend later (raw_x,
// estimated C, reference x*(t), controller telemetry) appear in the signal list by
// themselves. Arrays of records are keyed by their identity (robots by team.id, processors
// and topics by name, cameras by camera_id); arrays of plain numbers are skipped.

const MAX_DEPTH = 5;

/** Keys that are identities or clocks, not signals. */
const SKIP_KEYS = new Set(["seq", "id", "team", "camera_id", "frame_number", "t_capture", "time_ns", "command_counter", "t_unix", "epoch"]);

function recordKey(item: Record<string, unknown>, index: number): string | null {
  if (typeof item.team === "string" && typeof item.id === "number") return `${item.team}.${item.id}`;
  if (typeof item.name === "string") return item.name;
  if (typeof item.camera_id === "number") return `cam${item.camera_id}`;
  return index < 16 ? String(index) : null;
}

/** Flatten numeric leaves (booleans as 0/1) of `value` into `out` under `prefix`. */
export function flattenNumeric(value: unknown, prefix: string, out: Map<string, number>, depth = 0): void {
  if (depth > MAX_DEPTH) return;
  if (typeof value === "number") {
    if (Number.isFinite(value) && prefix) out.set(prefix, value);
    return;
  }
  if (typeof value === "boolean") {
    if (prefix) out.set(prefix, value ? 1 : 0);
    return;
  }
  if (Array.isArray(value)) {
    for (let i = 0; i < value.length; i++) {
      const item = value[i];
      if (typeof item !== "object" || item === null || Array.isArray(item)) continue; // number lists: skip
      const k = recordKey(item as Record<string, unknown>, i);
      if (k !== null) flattenNumeric(item, prefix ? `${prefix}.${k}` : k, out, depth + 1);
    }
    return;
  }
  if (typeof value === "object" && value !== null) {
    for (const [k, v] of Object.entries(value as Record<string, unknown>)) {
      if (SKIP_KEYS.has(k)) continue;
      flattenNumeric(v, prefix ? `${prefix}.${k}` : k, out, depth + 1);
    }
  }
}

/** Signals of a world message: robot.<team>.<id>.<field>, ball.<field>, plus derived speeds. */
export function worldSignals(world: unknown, out: Map<string, number> = new Map()): Map<string, number> {
  if (typeof world !== "object" || world === null) return out;
  const w = world as Record<string, unknown>;
  for (const [k, v] of Object.entries(w)) {
    if (k === "team") {
      teamSignals(v, out);
      continue;
    }
    if (k === "cameras" || SKIP_KEYS.has(k)) continue; // raw detections are drawn, not plotted
    if (k === "robots" && Array.isArray(v)) {
      for (const r of v) {
        if (typeof r !== "object" || r === null) continue;
        const rr = r as Record<string, unknown>;
        if (typeof rr.team !== "string" || typeof rr.id !== "number") continue;
        const p = `robot.${rr.team}.${rr.id}`;
        flattenNumeric(rr, p, out, 1);
        if (typeof rr.vx === "number" && typeof rr.vy === "number") out.set(`${p}.speed_mps`, Math.hypot(rr.vx, rr.vy) / 1000);
      }
      continue;
    }
    flattenNumeric(v, k, out, 1);
    if (k === "ball" && typeof v === "object" && v !== null) {
      const b = v as Record<string, unknown>;
      if (typeof b.vx === "number" && typeof b.vy === "number") out.set("ball.speed_mps", Math.hypot(b.vx, b.vy) / 1000);
    }
  }
  return out;
}

/**
 * The team's processors' outputs (world.team: {processor: {key: number}}) as
 * team.<processor>.<key>, every key as the processor names it (an output called "id" or
 * "team" is a signal like any other here, unlike the identity fields of records).
 */
function teamSignals(team: unknown, out: Map<string, number>): void {
  if (typeof team !== "object" || team === null || Array.isArray(team)) return;
  for (const [name, outputs] of Object.entries(team as Record<string, unknown>)) {
    if (typeof outputs !== "object" || outputs === null || Array.isArray(outputs)) continue;
    for (const [key, v] of Object.entries(outputs as Record<string, unknown>)) {
      if (typeof v === "number" && Number.isFinite(v)) out.set(`team.${name}.${key}`, v);
      else if (typeof v === "boolean") out.set(`team.${name}.${key}`, v ? 1 : 0);
    }
  }
}

/** Signals of a health message: health.processors.<name>.measured_hz, health.streams.vision.rate_hz, ... */
export function healthSignals(health: unknown, out: Map<string, number> = new Map()): Map<string, number> {
  flattenNumeric(health, "health", out, 0);
  out.delete("health.ok");
  out.delete("health.uptime_s");
  return out;
}

/** Case-insensitive search: every space-separated word must occur in the key. */
export function searchSignals(keys: readonly string[], query: string, limit = 200): string[] {
  const words = query.toLowerCase().split(/\s+/).filter(Boolean);
  const out: string[] = [];
  for (const k of keys) {
    const lk = k.toLowerCase();
    if (words.every((w) => lk.includes(w))) {
      out.push(k);
      if (out.length >= limit) break;
    }
  }
  return out;
}

/** Natural order: robot.blue.2 before robot.blue.10. */
export function compareSignals(a: string, b: string): number {
  return a.localeCompare(b, undefined, { numeric: true });
}
