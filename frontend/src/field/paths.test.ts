import { describe, expect, it } from "vitest";
import { pathLengthMm, pathPoints, pathToCanvas, tracePath, type PathSink } from "./paths";
import { makeTransform, worldToCanvas } from "./transform";

const t = makeTransform(1000, 800, { halfX: 5000, halfY: 4000 }, 0); // 0.1 px per mm, origin at (500, 400)

function recorder(): PathSink & { calls: string[] } {
  const calls: string[] = [];
  return {
    calls,
    moveTo: (x, y) => calls.push(`M${x},${y}`),
    lineTo: (x, y) => calls.push(`L${x},${y}`),
  };
}

describe("tracePath", () => {
  it("starts at the robot and goes through every waypoint, y up in the world is up on the canvas", () => {
    const sink = recorder();
    const n = tracePath(sink, t, { x: 0, y: 0 }, [{ x: 1000, y: 0 }, { x: 1000, y: 2000 }]);
    expect(n).toBe(2);
    expect(sink.calls).toEqual(["M500,400", "L600,400", "L600,200"]);
  });
  it("matches worldToCanvas for every point, also zoomed and panned", () => {
    const z = { ...t, scale: 0.37, originX: 123.5, originY: 456.25 };
    const path = [{ x: -1500, y: 800 }, { x: 2200, y: -3100 }, { x: 4000, y: 10 }];
    const pts = pathToCanvas(z, { x: -4000, y: 2500 }, path);
    const want = [{ x: -4000, y: 2500 }, ...path].map((p) => worldToCanvas(z, p.x, p.y));
    expect(pts).toHaveLength(4);
    pts.forEach((p, i) => {
      expect(p.x).toBeCloseTo(want[i]!.x, 9);
      expect(p.y).toBeCloseTo(want[i]!.y, 9);
    });
  });
  it("traces nothing without a usable path or robot position", () => {
    const sink = recorder();
    expect(tracePath(sink, t, { x: 0, y: 0 }, null)).toBe(0);
    expect(tracePath(sink, t, { x: 0, y: 0 }, undefined)).toBe(0);
    expect(tracePath(sink, t, { x: 0, y: 0 }, [])).toBe(0);
    expect(tracePath(sink, t, { x: Number.NaN, y: 0 }, [{ x: 1, y: 1 }])).toBe(0);
    expect(sink.calls).toEqual([]);
  });
  it("skips waypoints that are not finite", () => {
    const sink = recorder();
    expect(tracePath(sink, t, { x: 0, y: 0 }, [{ x: Number.NaN, y: 0 }, { x: 1000, y: 1000 }])).toBe(1);
    expect(sink.calls).toEqual(["M500,400", "L600,300"]);
  });
});

describe("pathPoints and pathLengthMm", () => {
  it("returns the same array when every point is fine (no allocation per frame)", () => {
    const p = [{ x: 1, y: 2 }];
    expect(pathPoints(p)).toBe(p);
    expect(pathPoints([{ x: Infinity, y: 0 }])).toBeNull();
  });
  it("measures robot -> waypoints", () => {
    expect(pathLengthMm({ x: 0, y: 0 }, [{ x: 300, y: 400 }, { x: 300, y: 1400 }])).toBe(1500);
    expect(pathLengthMm({ x: 0, y: 0 }, null)).toBe(0);
  });
});
