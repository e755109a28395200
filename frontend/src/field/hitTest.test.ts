import { describe, expect, it } from "vitest";
import { decideClick } from "./clickAction";
import { hitRadiusMm, hitTestRobot, ROBOT_RADIUS_MM } from "./hitTest";
import { robot } from "./testRobots";

const robots = [robot("blue", 3, 0, 0), robot("yellow", 3, 1000, 500), robot("blue", 7, 150, 0)];

describe("hitTestRobot", () => {
  it("hits the robot under the point", () => {
    expect(hitTestRobot(robots, { x: 1000, y: 500 })?.team).toBe("yellow");
    expect(hitTestRobot(robots, { x: 1050, y: 540 })?.id).toBe(3);
  });

  it("misses just outside the 90 mm radius and hits on the edge", () => {
    expect(hitTestRobot(robots, { x: 1000 + ROBOT_RADIUS_MM + 0.5, y: 500 })).toBeNull();
    expect(hitTestRobot(robots, { x: 1000, y: 500 - ROBOT_RADIUS_MM })?.team).toBe("yellow");
  });

  it("returns null on an empty point or without robots", () => {
    expect(hitTestRobot(robots, { x: -2000, y: 0 })).toBeNull();
    expect(hitTestRobot([], { x: 0, y: 0 })).toBeNull();
  });

  it("picks the nearest of overlapping robots", () => {
    expect(hitTestRobot(robots, { x: 70, y: 0 })?.id).toBe(3);
    expect(hitTestRobot(robots, { x: 80, y: 0 })?.id).toBe(7);
  });

  it("honours a bigger tolerance radius", () => {
    expect(hitTestRobot(robots, { x: -150, y: 0 })).toBeNull();
    expect(hitTestRobot(robots, { x: -150, y: 0 }, 200)?.id).toBe(3);
  });

  it("can skip invisible robots and ignores non-finite positions", () => {
    const rs = [robot("blue", 1, 0, 0, { visible: false }), robot("blue", 2, NaN, 0)];
    expect(hitTestRobot(rs, { x: 0, y: 0 })?.id).toBe(1);
    expect(hitTestRobot(rs, { x: 0, y: 0 }, 90, false)).toBeNull();
  });
});

describe("hitRadiusMm", () => {
  it("is the robot radius when zoomed in and grows when zoomed out", () => {
    expect(hitRadiusMm(1)).toBe(ROBOT_RADIUS_MM);
    expect(hitRadiusMm(0.05, 10)).toBeCloseTo(200, 9);
    expect(hitRadiusMm(0)).toBe(ROBOT_RADIUS_MM);
  });
});

describe("decideClick", () => {
  it("selects a clicked robot, even with another selected", () => {
    expect(decideClick(robots, null, { x: 0, y: 0 }, 90)).toEqual({ kind: "select", robot: { team: "blue", id: 3 } });
    expect(decideClick(robots, { team: "blue", id: 3 }, { x: 1000, y: 500 }, 90)).toEqual({
      kind: "select",
      robot: { team: "yellow", id: 3 },
    });
  });

  it("sends the selected robot to an empty point", () => {
    expect(decideClick(robots, { team: "blue", id: 7 }, { x: -2000, y: 1500 }, 90)).toEqual({
      kind: "target",
      robot: { team: "blue", id: 7 },
      point: { x: -2000, y: 1500 },
    });
  });

  it("does nothing on an empty point without a selection", () => {
    expect(decideClick(robots, null, { x: -2000, y: 1500 }, 90)).toEqual({ kind: "none" });
  });
});
