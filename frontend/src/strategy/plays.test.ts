import { describe, expect, it } from "vitest";
import type { StrategyInfo } from "../api/types";
import { strategyView } from "../ws/fixtures";
import { currentPlay, humanizePlay, playList, situationLine } from "./plays";

const info: StrategyInfo = strategyView([
    { name: "match", title: "Match", description: "Full game: keeper, attackers, supporters, defenders" },
    { name: "defend", title: "Defend", description: "Everyone behind the ball" },
    { name: "formation", title: "", description: "" },
  ]);

describe("playList", () => {
  it("lists the station's plays in its order, a missing title from the name", () => {
    expect(playList(info, undefined, "match").map((p) => [p.name, p.title])).toEqual([
      ["match", "Match"],
      ["defend", "Defend"],
      ["formation", "Formation"],
    ]);
  });
  it("falls back to the enum of the play parameter", () => {
    const l = playList(null, ["match", "attack-drill", "idle"], "idle");
    expect(l.map((p) => p.title)).toEqual(["Match", "Attack drill", "Idle"]);
    expect(l.every((p) => p.description === "")).toBe(true);
  });
  it("always contains the current play and ignores malformed entries", () => {
    const bad = { ...info, plays: [{ name: 3 }, null, { name: "match" }] } as unknown as StrategyInfo;
    expect(playList(bad, undefined, "secret").map((p) => p.name)).toEqual(["match", "secret"]);
  });
  it("is empty when the station has no strategy", () => {
    expect(playList(null, undefined, null)).toEqual([]);
  });
});

describe("currentPlay", () => {
  it("prefers the parameter, then the world, then GET /api/strategy", () => {
    expect(currentPlay({ strategy: { play: "defend" } }, "match", info)).toBe("defend");
    expect(currentPlay({ team: {} }, "formation", info)).toBe("formation");
    expect(currentPlay(undefined, null, info)).toBe("match");
    expect(currentPlay(undefined, null, null)).toBeNull();
  });
});

describe("situationLine", () => {
  it("shows the text and the goal we defend", () => {
    expect(situationLine({ situation: "stop", situation_text: "STOP: keep 0.5 m from the ball", our_side: "negative-x", side_from_referee: false }))
      .toEqual({ text: "STOP: keep 0.5 m from the ball", side: "we defend the −x goal (left)" });
    expect(situationLine({ situation: "kickoff", situation_text: "", our_side: "positive-x", side_from_referee: true }))
      .toEqual({ text: "kickoff", side: "we defend the +x goal (right), side from the referee" });
  });
  it("is null without a strategy", () => {
    expect(situationLine(null)).toBeNull();
    expect(situationLine({ situation: "", situation_text: "" })).toBeNull();
  });
  it("humanizes play names", () => {
    expect(humanizePlay("attack-drill")).toBe("Attack drill");
  });
});
