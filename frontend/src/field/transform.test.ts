import { describe, expect, it } from "vitest";
import { DEFAULT_GEOMETRY } from "./defaultGeometry";
import { canvasToWorld, fieldExtent, lengthToCanvas, makeTransform, worldToCanvas } from "./transform";

const ext = fieldExtent(DEFAULT_GEOMETRY); // 9000x6000 + 300 boundary -> 4800 x 3300 half sizes

describe("fieldExtent", () => {
  it("adds the boundary to the half sizes", () => {
    expect(ext).toEqual({ halfX: 4800, halfY: 3300 });
  });
  it("keeps the goals visible when the boundary is thinner than the goal depth", () => {
    expect(fieldExtent({ field_length: 9000, field_width: 6000, boundary_width: 100, goal_depth: 180 })).toEqual({
      halfX: 4680,
      halfY: 3100,
    });
  });
});

describe("makeTransform", () => {
  it("fits the width when the canvas is wide and centres the origin", () => {
    const t = makeTransform(1000, 1000, ext, 10);
    expect(t.scale).toBeCloseTo(980 / 9600, 12);
    expect(worldToCanvas(t, 0, 0)).toEqual({ x: 500, y: 500 });
    // left edge of the boundary lands on the padding
    expect(worldToCanvas(t, -4800, 0).x).toBeCloseTo(10, 9);
    expect(worldToCanvas(t, 4800, 0).x).toBeCloseTo(990, 9);
  });

  it("fits the height when the canvas is short", () => {
    const t = makeTransform(2000, 500, ext, 0);
    expect(t.scale).toBeCloseTo(500 / 6600, 12);
    expect(worldToCanvas(t, 0, 3300).y).toBeCloseTo(0, 9);
    expect(worldToCanvas(t, 0, -3300).y).toBeCloseTo(500, 9);
  });

  it("has x to the right and y up", () => {
    const t = makeTransform(960, 660, ext, 0);
    const o = worldToCanvas(t, 0, 0);
    const px = worldToCanvas(t, 1000, 0);
    const py = worldToCanvas(t, 0, 1000);
    expect(px.x).toBeGreaterThan(o.x);
    expect(px.y).toBeCloseTo(o.y, 9);
    expect(py.y).toBeLessThan(o.y);
    expect(py.x).toBeCloseTo(o.x, 9);
    expect(lengthToCanvas(t, 1000)).toBeCloseTo(100, 9);
  });

  it("keeps a positive scale for degenerate sizes", () => {
    const t = makeTransform(0, 0, ext, 20);
    expect(t.scale).toBeGreaterThan(0);
    expect(Number.isFinite(canvasToWorld(t, 3, 4).x)).toBe(true);
  });
});

describe("round trips", () => {
  const sizes: [number, number][] = [
    [1280, 720],
    [375, 500],
    [883, 611],
    [3840, 2160],
  ];
  const points = [
    [0, 0],
    [4500, 3000],
    [-4500, -3000],
    [1234.5, -987.25],
    [-4800, 3300],
  ] as const;
  for (const [w, h] of sizes) {
    it(`world -> canvas -> world at ${w}x${h}`, () => {
      const t = makeTransform(w, h, ext, 12);
      for (const [x, y] of points) {
        const c = worldToCanvas(t, x, y);
        const back = canvasToWorld(t, c.x, c.y);
        expect(back.x).toBeCloseTo(x, 6);
        expect(back.y).toBeCloseTo(y, 6);
      }
    });
    it(`canvas -> world -> canvas at ${w}x${h}`, () => {
      const t = makeTransform(w, h, ext, 12);
      for (const [px, py] of [
        [0, 0],
        [w, h],
        [w / 3, (2 * h) / 3],
      ] as const) {
        const p = canvasToWorld(t, px, py);
        const c = worldToCanvas(t, p.x, p.y);
        expect(c.x).toBeCloseTo(px, 6);
        expect(c.y).toBeCloseTo(py, 6);
      }
    });
  }

  it("maps the whole extent inside the canvas", () => {
    const t = makeTransform(1280, 720, ext, 12);
    for (const [x, y] of [
      [-4800, -3300],
      [4800, 3300],
    ] as const) {
      const c = worldToCanvas(t, x, y);
      expect(c.x).toBeGreaterThanOrEqual(12 - 1e-9);
      expect(c.x).toBeLessThanOrEqual(1280 - 12 + 1e-9);
      expect(c.y).toBeGreaterThanOrEqual(12 - 1e-9);
      expect(c.y).toBeLessThanOrEqual(720 - 12 + 1e-9);
    }
  });
});
