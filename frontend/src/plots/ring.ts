// Pure ring buffers for live signals, outside React.
//
// `Ring`: fixed-capacity Float64 ring. `SampleTable`: one shared time column plus one column
// per signal, all the same capacity, so a row is one message (world or health); a signal
// missing from a row is NaN. Columns appear when a signal is first seen (earlier rows NaN).

export class Ring {
  readonly capacity: number;
  private data: Float64Array;
  private head = 0; // next write index
  private n = 0;

  constructor(capacity: number, fill = Number.NaN) {
    if (!(capacity >= 1)) throw new Error("capacity must be >= 1");
    this.capacity = Math.floor(capacity);
    this.data = new Float64Array(this.capacity).fill(fill);
  }

  get length(): number {
    return this.n;
  }

  push(v: number): void {
    this.data[this.head] = v;
    this.head = (this.head + 1) % this.capacity;
    if (this.n < this.capacity) this.n++;
  }

  /** Element i counted from the oldest (0) to the newest (length - 1). */
  get(i: number): number {
    if (i < 0 || i >= this.n) return Number.NaN;
    return this.data[(this.head - this.n + i + this.capacity) % this.capacity] as number;
  }

  last(): number {
    return this.n === 0 ? Number.NaN : this.get(this.n - 1);
  }

  clear(): void {
    this.head = 0;
    this.n = 0;
  }

  /** Copy elements [from, to) (oldest-based indices) into a plain array. */
  slice(from = 0, to = this.n): number[] {
    const a = Math.max(0, from);
    const b = Math.min(this.n, to);
    const out = new Array<number>(Math.max(0, b - a));
    for (let i = a; i < b; i++) out[i - a] = this.get(i);
    return out;
  }

  /** Backfill: make the ring hold `n` NaN-valued elements ending at the current head. */
  padTo(n: number): void {
    while (this.n < Math.min(n, this.capacity)) this.push(Number.NaN);
  }
}

/** First index i in [0, n) with time(i) >= t, for non-decreasing times (n when none). */
export function lowerBound(n: number, time: (i: number) => number, t: number): number {
  let lo = 0;
  let hi = n;
  while (lo < hi) {
    const mid = (lo + hi) >>> 1;
    if (time(mid) < t) lo = mid + 1;
    else hi = mid;
  }
  return lo;
}

export interface WindowData {
  /** Times (s). */
  t: number[];
  /** One array per requested key; null where the signal had no value (a gap). */
  cols: (number | null)[][];
}

export class SampleTable {
  readonly capacity: number;
  readonly time: Ring;
  private cols = new Map<string, Ring>();
  /** Rows ever appended (grows forever; use to detect new data). */
  rows = 0;

  constructor(capacity: number) {
    this.capacity = capacity;
    this.time = new Ring(capacity);
  }

  keys(): string[] {
    return [...this.cols.keys()];
  }

  has(key: string): boolean {
    return this.cols.has(key);
  }

  get length(): number {
    return this.time.length;
  }

  /** Append one row at time `t` (non-decreasing). Values not given are NaN in this row. */
  append(t: number, values: ReadonlyMap<string, number> | Record<string, number>): void {
    const entries = values instanceof Map ? values : new Map(Object.entries(values));
    const before = this.time.length;
    for (const [k] of entries) {
      if (!this.cols.has(k)) {
        const r = new Ring(this.capacity);
        r.padTo(before);
        this.cols.set(k, r);
      }
    }
    // Guard against clocks stepping back: keep times non-decreasing for the binary search.
    const last = this.time.last();
    this.time.push(Number.isFinite(last) && t < last ? last : t);
    for (const [k, ring] of this.cols) {
      const v = entries.get(k);
      ring.push(typeof v === "number" ? v : Number.NaN);
    }
    this.rows++;
  }

  /** The newest value of a key and its time, or null. */
  latest(key: string): { t: number; v: number } | null {
    const ring = this.cols.get(key);
    if (!ring) return null;
    for (let i = ring.length - 1; i >= 0; i--) {
      const v = ring.get(i);
      if (!Number.isNaN(v)) return { t: this.time.get(i), v };
    }
    return null;
  }

  /**
   * Rows with t0 <= time <= t1 for the given keys. Rows where every requested key is NaN are
   * left out (e.g. health rows for world signals), so a plot only gets its own samples.
   */
  window(t0: number, t1: number, keys: readonly string[]): WindowData {
    const n = this.time.length;
    const timeAt = (i: number) => this.time.get(i);
    const a = lowerBound(n, timeAt, t0);
    const b = lowerBound(n, timeAt, t1 + 1e-9);
    const rings = keys.map((k) => this.cols.get(k));
    const t: number[] = [];
    const cols: (number | null)[][] = keys.map(() => []);
    for (let i = a; i < b; i++) {
      let any = false;
      for (const r of rings) if (r && !Number.isNaN(r.get(i))) any = true;
      if (!any && keys.length > 0) continue;
      t.push(this.time.get(i));
      for (let j = 0; j < rings.length; j++) {
        const v = rings[j] ? rings[j]!.get(i) : Number.NaN;
        cols[j]!.push(Number.isNaN(v) ? null : v);
      }
    }
    return { t, cols };
  }

  /**
   * Put `rows` (times ascending) before the rows held: the past of a replay after a seek.
   * Rows not older than the oldest row held are left out; the newest rows win the capacity.
   */
  prepend(rows: ReadonlyArray<readonly [number, ReadonlyMap<string, number>]>): void {
    const n = this.time.length;
    const first = n > 0 ? this.time.get(0) : Number.POSITIVE_INFINITY;
    const older = rows.filter(([t]) => t < first);
    if (older.length === 0) return;
    const keep: [number, Map<string, number>][] = [];
    for (let i = 0; i < n; i++) {
      const m = new Map<string, number>();
      for (const [k, r] of this.cols) {
        const v = r.get(i);
        if (!Number.isNaN(v)) m.set(k, v);
      }
      keep.push([this.time.get(i), m]);
    }
    const counted = this.rows;
    this.clear();
    for (const [t, v] of older) this.append(t, v);
    for (const [t, v] of keep) this.append(t, v);
    this.rows = counted + older.length;
  }

  /** Drop every row and column; `rows` keeps counting (plots compare it to see new data). */
  clear(): void {
    this.time.clear();
    this.cols.clear();
  }
}
