import { describe, expect, it } from "vitest";
import type { StrategyInfo, TeamFile } from "../api/types";
import { strategyView } from "../ws/fixtures";
import { currentPlay, humanizePlay, playGroups, playList, robotPlayPatch, robotPlays, showGroups, situationLine, teamPlaysKey } from "./plays";
import { teamFile } from "../ws/fixtures";

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

describe("team plays beside the built-in ones", () => {
  const withTeam: StrategyInfo = strategyView([
    { name: "match", title: "Match", description: "" },
    { name: "defend", title: "Defend", description: "" },
    { name: "pass_drill", title: "Pass drill", description: "Two robots pass", source: "team", file: "pass_drill.py", language: "python" },
    { name: "keeper_wall", title: "Keeper and wall (Octave)", description: "", source: "team", file: "keeper_wall.m", language: "octave" },
  ]);

  it("groups them Built-in / Team, titles from the station, in its order", () => {
    const g = playGroups(playList(withTeam, undefined, "match"));
    expect(g.map((x) => [x.label, x.plays.map((p) => p.title)])).toEqual([
      ["Built-in", ["Match", "Defend"]],
      ["Team", ["Pass drill", "Keeper and wall (Octave)"]],
    ]);
    expect(showGroups(g)).toBe(true);
  });

  it("shows no group labels while the team has no plays", () => {
    const g = playGroups(playList(info, undefined, "match"));
    expect(g).toHaveLength(1);
    expect(showGroups(g)).toBe(false);
    expect(playGroups([])).toEqual([]);
  });

  it("keeps a chosen team play whose file is gone in the list (taken as built-in: the station says why it fails)", () => {
    const l = playList(info, undefined, "old_drill");
    expect(l.at(-1)).toMatchObject({ name: "old_drill", source: "builtin" });
  });

  it("asks for the plays again when a team play is added, removed or retitled, not on a save of code", () => {
    const files = [
      teamFile("pass_drill.py", { kind: "play", play: "pass_drill", title: "Pass drill", version: "aaaaaaaaaaaa" }),
      teamFile("lib/util.py"),
    ];
    const k = teamPlaysKey(files);
    const saved: TeamFile = { ...files[0]!, version: "bbbbbbbbbbbb", state: "error" };
    expect(teamPlaysKey([saved, files[1]!])).toBe(k);
    expect(teamPlaysKey([...files, teamFile("lib/more.py")])).toBe(k); // a library: no play
    expect(teamPlaysKey([files[1]!])).not.toBe(k);
    expect(teamPlaysKey([{ ...files[0]!, title: "Passing" }, files[1]!])).not.toBe(k);
    expect(teamPlaysKey([...files, teamFile("wall.m", { kind: "play", play: "wall" })])).not.toBe(k);
    expect(teamPlaysKey(undefined)).toBe("");
  });
});

describe("per-robot plays", () => {
  it("reads strategy.robot_plays and makes the PATCH that sets or removes one", () => {
    expect(robotPlays({ strategy: { play: "match", robot_plays: { "3": "pass_drill", "4": "", "5": null } } })).toEqual({ "3": "pass_drill" });
    expect(robotPlays({ strategy: { play: "match" } })).toEqual({});
    expect(robotPlays(null)).toEqual({});
    expect(robotPlayPatch(3, "pass_drill")).toEqual({ strategy: { robot_plays: { "3": "pass_drill" } } });
    expect(robotPlayPatch(3, null)).toEqual({ strategy: { robot_plays: { "3": null } } });
  });
});
