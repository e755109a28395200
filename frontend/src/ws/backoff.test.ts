import { describe, expect, it } from "vitest";
import { backoffDelay } from "./backoff";

describe("backoffDelay", () => {
  it("starts at 0.5 s and doubles up to 5 s", () => {
    expect([0, 1, 2, 3, 4, 5, 6].map((n) => backoffDelay(n))).toEqual([500, 1000, 2000, 4000, 5000, 5000, 5000]);
  });

  it("stays capped for huge attempt numbers and sane for bad input", () => {
    expect(backoffDelay(1000)).toBe(5000);
    expect(backoffDelay(Infinity)).toBe(500);
    expect(backoffDelay(-3)).toBe(500);
    expect(backoffDelay(NaN)).toBe(500);
  });

  it("adds bounded jitter when asked", () => {
    const opts = { baseMs: 500, maxMs: 5000, jitter: 0.2 };
    expect(backoffDelay(0, opts, () => 0)).toBe(500);
    expect(backoffDelay(0, opts, () => 0.5)).toBe(550);
    expect(backoffDelay(4, opts, () => 0.99)).toBe(5000);
  });
});
