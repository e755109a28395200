import { describe, expect, it } from "vitest";
import { lowerBound, Ring, SampleTable } from "./ring";

describe("Ring", () => {
  it("keeps the newest `capacity` values, oldest first", () => {
    const r = new Ring(3);
    expect(r.length).toBe(0);
    expect(r.last()).toBeNaN();
    r.push(1);
    r.push(2);
    expect(r.slice()).toEqual([1, 2]);
    r.push(3);
    r.push(4);
    expect(r.length).toBe(3);
    expect(r.slice()).toEqual([2, 3, 4]);
    expect(r.get(0)).toBe(2);
    expect(r.last()).toBe(4);
    expect(r.get(3)).toBeNaN();
    expect(r.slice(1, 2)).toEqual([3]);
    r.clear();
    expect(r.length).toBe(0);
  });
  it("rejects a zero capacity", () => {
    expect(() => new Ring(0)).toThrow();
  });
});

describe("lowerBound", () => {
  it("finds the first index at or after t", () => {
    const a = [1, 2, 2, 5];
    const at = (i: number) => a[i]!;
    expect(lowerBound(4, at, 0)).toBe(0);
    expect(lowerBound(4, at, 2)).toBe(1);
    expect(lowerBound(4, at, 3)).toBe(3);
    expect(lowerBound(4, at, 9)).toBe(4);
  });
});

describe("SampleTable", () => {
  it("aligns columns that appear later and leaves gaps as null", () => {
    const t = new SampleTable(8);
    t.append(1, { a: 10 });
    t.append(2, { a: 11, b: 20 });
    t.append(3, new Map([["b", 21]]));
    expect(t.keys()).toEqual(["a", "b"]);
    const w = t.window(0, 10, ["a", "b"]);
    expect(w.t).toEqual([1, 2, 3]);
    expect(w.cols).toEqual([
      [10, 11, null],
      [null, 20, 21],
    ]);
    expect(t.latest("a")).toEqual({ t: 2, v: 11 });
    expect(t.latest("zzz")).toBeNull();
  });
  it("returns only rows inside the window and skips rows without any requested key", () => {
    const t = new SampleTable(100);
    for (let i = 0; i < 20; i++) t.append(i, i % 2 === 0 ? { world: i } : { health: i });
    const w = t.window(5, 10, ["world"]);
    expect(w.t).toEqual([6, 8, 10]);
    expect(w.cols[0]).toEqual([6, 8, 10]);
  });
  it("wraps around and keeps times non-decreasing", () => {
    const t = new SampleTable(4);
    for (let i = 0; i < 10; i++) t.append(i, { a: i });
    t.append(5, { a: 99 }); // clock stepped back: stamped at the last time
    expect(t.length).toBe(4);
    expect(t.rows).toBe(11);
    const w = t.window(-1, 100, ["a"]);
    expect(w.t).toEqual([7, 8, 9, 9]);
    expect(w.cols[0]).toEqual([7, 8, 9, 99]);
  });
});
