// Reconnect delay schedule: base, doubling per failed attempt, capped.

export interface BackoffOptions {
  baseMs: number;
  maxMs: number;
  /** Fraction of random spread added on top, 0 = deterministic. */
  jitter: number;
}

export const defaultBackoff: BackoffOptions = { baseMs: 500, maxMs: 5000, jitter: 0 };

/**
 * Delay before reconnect attempt number `attempt` (0 = first retry after a close).
 * `random` returns a value in [0, 1) and is only used when jitter > 0.
 */
export function backoffDelay(
  attempt: number,
  opts: BackoffOptions = defaultBackoff,
  random: () => number = Math.random,
): number {
  const n = Math.max(0, Math.floor(Number.isFinite(attempt) ? attempt : 0));
  // Avoid overflow for large attempt numbers: 2^n saturates at the cap anyway.
  const raw = n >= 30 ? opts.maxMs : opts.baseMs * 2 ** n;
  const capped = Math.min(opts.maxMs, raw);
  if (opts.jitter <= 0) return capped;
  return Math.min(opts.maxMs, capped * (1 + opts.jitter * random()));
}
