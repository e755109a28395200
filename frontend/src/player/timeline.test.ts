import { describe, expect, it } from "vitest";
import type { PlayerEvent } from "../api/types";
import {
  baseName,
  findEvent,
  fmtDuration,
  fmtMB,
  fmtPosition,
  fmtWallTime,
  layoutMarkers,
  nextSpeed,
  positionToX,
  speedLabel,
  xToPosition,
} from "./timeline";

const events: PlayerEvent[] = [
  { t_s: 40, kind: "goal", label: "goal blue" },
  { t_s: 10, kind: "command", label: "FORCE_START" },
  { t_s: 60, kind: "stage", label: "half time" },
  { t_s: 90, kind: "card", label: "yellow card" },
];

describe("time formatting", () => {
  it("formats the position as m:ss.s and the duration as m:ss", () => {
    expect(fmtPosition(0)).toBe("0:00.0");
    expect(fmtPosition(5.25)).toBe("0:05.2");
    expect(fmtPosition(61.99)).toBe("1:01.9");
    expect(fmtPosition(600)).toBe("10:00.0");
    expect(fmtPosition(-3)).toBe("0:00.0");
    expect(fmtPosition(Number.NaN)).toBe("0:00.0");
    expect(fmtDuration(59.5)).toBe("1:00");
    expect(fmtDuration(125)).toBe("2:05");
    expect(fmtDuration(0)).toBe("0:00");
  });

  it("formats the wall time as local HH:MM:SS", () => {
    const t = new Date(2026, 10, 25, 9, 5, 7).getTime() / 1000;
    expect(fmtWallTime(t)).toBe("09:05:07");
    expect(fmtWallTime(0)).toBe("");
    expect(fmtWallTime(null)).toBe("");
  });

  it("formats sizes and file names", () => {
    expect(fmtMB(12_345_678)).toBe("12.3 MB");
    expect(baseName("var/logs/a.log.gz")).toBe("a.log.gz");
    expect(baseName("C:\\logs\\b.log")).toBe("b.log");
    expect(baseName(null)).toBe("");
  });
});

describe("position <-> pixel", () => {
  it("maps both ways and clamps to the bar", () => {
    expect(positionToX(30, 120, 600)).toBe(150);
    expect(xToPosition(150, 120, 600)).toBe(30);
    expect(positionToX(200, 120, 600)).toBe(600);
    expect(xToPosition(-10, 120, 600)).toBe(0);
    expect(xToPosition(700, 120, 600)).toBe(120);
  });
  it("gives 0 for an empty log or a bar without width", () => {
    expect(positionToX(10, 0, 600)).toBe(0);
    expect(xToPosition(10, 120, 0)).toBe(0);
  });
});

describe("layoutMarkers", () => {
  it("places markers in % of the log, in time order", () => {
    const slots = layoutMarkers(events, 120);
    expect(slots.map((s) => s.event.t_s)).toEqual([10, 40, 60, 90]);
    expect(slots[2]!.pct).toBe(50);
    expect(slots.every((s) => s.row === 0)).toBe(true);
  });
  it("stacks markers that would overlap, up to the last row", () => {
    const close: PlayerEvent[] = [0, 0.1, 0.2, 0.3, 50].map((t) => ({ t_s: t, kind: "command", label: String(t) }));
    const slots = layoutMarkers(close, 100, 1, 3);
    expect(slots.map((s) => s.row)).toEqual([0, 1, 2, 2, 0]);
  });
  it("is empty without a duration", () => {
    expect(layoutMarkers(events, 0)).toEqual([]);
  });
});

describe("findEvent", () => {
  it("finds the next and previous event of any kind", () => {
    expect(findEvent(events, 30, "next")?.t_s).toBe(40);
    expect(findEvent(events, 30, "prev")?.t_s).toBe(10);
    expect(findEvent(events, 95, "next")).toBeNull();
    expect(findEvent(events, 5, "prev")).toBeNull();
  });
  it("skips the event under the playhead and filters by kind", () => {
    expect(findEvent(events, 40, "next")?.t_s).toBe(60);
    expect(findEvent(events, 40.01, "prev")?.t_s).toBe(10);
    expect(findEvent(events, 0, "next", "card")?.t_s).toBe(90);
  });
});

describe("speeds", () => {
  it("steps through the list, max above 10", () => {
    expect(nextSpeed(1, 1)).toBe(2);
    expect(nextSpeed(1, -1)).toBe(0.5);
    expect(nextSpeed(10, 1)).toBe(0);
    expect(nextSpeed(0, 1)).toBe(0);
    expect(nextSpeed(0, -1)).toBe(10);
    expect(nextSpeed(0.1, -1)).toBe(0.1);
  });
  it("snaps an unlisted speed to the neighbour in the direction", () => {
    expect(nextSpeed(1.5, 1)).toBe(2);
    expect(nextSpeed(1.5, -1)).toBe(1);
    expect(nextSpeed(0.05, -1)).toBe(0.1);
  });
  it("labels max", () => {
    expect(speedLabel(0)).toBe("max");
    expect(speedLabel(0.25)).toBe("0.25×");
  });
});
