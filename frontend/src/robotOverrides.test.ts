import { describe, expect, it } from "vitest";
import { worldSignals } from "./plots/signals";
import { controllerPatch, controllerPlots, filterPatch, filterPlots, robotOverrides } from "./robotOverrides";
import { trackStyle } from "./field/draw";

const k = { team: "blue" as const, id: 3 };
const values = {
  control: { default_algorithm: "algorithm2", robots: { "blue/3": { algorithm: "algorithm1", v_mps: null }, "blue/4": { algorithm: "proportional", v_mps: 1.5 } } },
  filters: { robot: "kalman", robot_overrides: { "blue/3": "paper" } },
};

describe("robot overrides", () => {
  it("reads the per-robot choice and the defaults", () => {
    expect(robotOverrides(values, k)).toEqual({ algorithm: "algorithm1", defaultAlgorithm: "algorithm2", filter: "paper", defaultFilter: "kalman" });
    expect(robotOverrides(values, { team: "yellow", id: 3 })).toMatchObject({ algorithm: null, filter: null });
    expect(robotOverrides(null, k)).toEqual({ algorithm: null, defaultAlgorithm: null, filter: null, defaultFilter: null });
  });

  it("builds PATCH bodies; Default removes the override (null) but keeps other per-robot fields", () => {
    expect(controllerPatch(values, k, "algorithm2")).toEqual({ control: { robots: { "blue/3": { algorithm: "algorithm2" } } } });
    expect(controllerPatch(values, k, null)).toEqual({ control: { robots: { "blue/3": null } } });
    expect(controllerPatch(values, { team: "blue", id: 4 }, null)).toEqual({ control: { robots: { "blue/4": { v_mps: 1.5, algorithm: null } } } });
    expect(filterPatch(k, "median")).toEqual({ filters: { robot_overrides: { "blue/3": "median" } } });
    expect(filterPatch(k, "")).toEqual({ filters: { robot_overrides: { "blue/3": null } } });
  });

  it("the one-click plots name signals that worldSignals derives from the nested control object", () => {
    const robot = {
      team: "blue", id: 3, x: 1, y: 2, vx: 0, vy: 0, raw_x: 1.5, raw_y: 2.5, filter: "paper",
      control: { algorithm: "algorithm1", phase: "cruise", c_estimate: 0.9, ref_x_m: 0.4, x_m: 0.38, cmd_speed_mps: 1, meas_speed_mps: 0.95 },
    };
    const sig = worldSignals({ robots: [robot], ball: null });
    for (const keys of [...controllerPlots(k), ...filterPlots(k)]) for (const key of keys) expect(sig.has(key)).toBe(true);
    expect(sig.get("robot.blue.3.control.c_estimate")).toBe(0.9);
    expect(sig.has("robot.blue.3.control.phase")).toBe(false); // strings are not signals
  });

  it("draw style: lost > predicted > measured", () => {
    expect(trackStyle({ visible: true, predicted: false, lost: false })).toBe("measured");
    expect(trackStyle({ visible: true, predicted: true, lost: false })).toBe("predicted");
    expect(trackStyle({ visible: false, predicted: true, lost: true })).toBe("lost");
  });
});
