// Number formatting for the tables (fixed width, no layout jumps).

export function fmtInt(v: number | null | undefined): string {
  if (v === null || v === undefined || !Number.isFinite(v)) return "—";
  const r = Math.round(v);
  return String(Object.is(r, -0) ? 0 : r);
}

export function fmtFixed(v: number | null | undefined, digits: number): string {
  if (v === null || v === undefined || !Number.isFinite(v)) return "—";
  const s = v.toFixed(digits);
  return /^-0\.?0*$/.test(s) ? s.slice(1) : s;
}

export function fmtDeg(rad: number | null | undefined): string {
  if (rad === null || rad === undefined || !Number.isFinite(rad)) return "—";
  return `${fmtInt((rad * 180) / Math.PI)}°`;
}

/** An angle in degrees normalised to (-180, 180]. */
export function fmtHeading(rad: number | null | undefined): string {
  if (rad === null || rad === undefined || !Number.isFinite(rad)) return "—";
  let deg = ((((rad * 180) / Math.PI) % 360) + 360) % 360;
  if (deg > 180) deg -= 360;
  return `${fmtInt(deg)}°`;
}

/** Robot speed in m/s from mm/s components. */
export function speedMps(vx: number, vy: number): number {
  return Math.hypot(vx, vy) / 1000;
}
